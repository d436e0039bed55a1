#pragma once
// Internal to the planner library. The constraint rows of the problem, one family per term
// (the layout of TOWR's constraints/): each term says how many rows it adds at a sample (or at a
// contact switch) and computes them from the state there. The problem stacks the terms in the
// order of sampleTerms() / eventTerms(); the row layout (offsets, families) is derived from
// them, never counted by hand. Rows are scaled to O(1) by a named scale with units (each term's
// file states it); inequalities are <= 0, equalities = 0.
//
// Derivatives: the problem differentiates the stacked rows (OverstepProblem::derivatives).
#include <memory>
#include <vector>

#include "../problem_model.hpp"

namespace overstep::planner::detail {

/// What the row terms of one sample read: the grid point, the robot state there (the model holds
/// the same state, with its kinematics) and the capsules in the world.
struct SampleData {
  const GridPoint* g = nullptr;
  double t = 0.0;                           ///< s
  robots::WholeBodyModel* model = nullptr;  ///< at the sample's state
  const State* st = nullptr;
  std::vector<robots::Capsule> capsules;  ///< world frame, ProblemModel::caps order
  /// How far each capsule can travel before the nearer sample (m; swept clearance, 0 when off).
  std::vector<double> sweep;
  Eigen::Vector3d com_acc = Eigen::Vector3d::Zero();  ///< CoM acceleration, world axes (m/s^2)
  /// Scratch for a term's list of per-sample values (distances, ratios): one SampleData per
  /// workspace (thread), so the terms evaluate without allocating once it has grown.
  mutable Eigen::VectorXd values;
  /// The first n entries of `values`, grown to at least n.
  Eigen::VectorXd::SegmentReturnType scratch(Eigen::Index n) const {
    if (values.size() < n) values.resize(n);
    return values.head(n);
  }
};

/// A family of rows at the samples.
class SampleTerm {
 public:
  virtual ~SampleTerm() = default;
  virtual Family family() const = 0;
  virtual bool equality() const { return false; }
  /// Rows at grid point g (0: the term does not apply there).
  virtual int rows(const ProblemModel& p, const GridPoint& g) const = 0;
  /// Writes rows(p, *d.g) values to out.
  virtual void evaluate(const ProblemModel& p, const SampleData& d, double* out) const = 0;
  /// For a term whose rows at this sample read the configuration alone: their exact derivatives
  /// with respect to it, rows(p, *d.g) x dofs, in the model's velocity coordinates (the base's
  /// six, then the joints: d row = J dv for a configuration moving by dv dt), and true. False
  /// (J untouched) where the rows also read velocities, accelerations or wrenches, or have no
  /// closed form at this state: the problem then differentiates the sample by finite differences.
  virtual bool configurationJacobian(const ProblemModel& p, const SampleData& d,
                                     Eigen::Ref<Eigen::MatrixXd> J) const {
    (void)p;
    (void)d;
    (void)J;
    return false;
  }
};

/// What the row terms of a contact switch read: the state of the double-support phase at the
/// switch (ProblemModel::eventPhase) and the splines' values there.
struct EventData {
  int event = 0;  ///< 0..3: t1 (end of phase 0), t2 (start of 2), t3 (end of 2), t4 (start of 4)
  const State* st = nullptr;
  const SplineState* spline = nullptr;
};

/// A family of rows at the contact switches.
class EventTerm {
 public:
  virtual ~EventTerm() = default;
  virtual Family family() const = 0;
  virtual int rows(const ProblemModel& p, int event) const = 0;
  virtual void evaluate(const ProblemModel& p, const EventData& d, double* out) const = 0;
};

/// The sole frame's wrench of foot f: moment and force about the sole origin, sole axes.
inline void soleWrench(const State& st, int f, Eigen::Vector3d& mo, Eigen::Vector3d& fo) {
  // Rt from a plain matrix: GCC's -O1 flags the transpose of the isometry's block as maybe
  // uninitialized (a false positive in Eigen's aliasing check).
  const Eigen::Matrix3d R = st.sole[f].linear();
  const Eigen::Matrix3d Rt = R.transpose();
  mo = Rt * st.wrench[f].moment;
  fo = Rt * st.wrench[f].force;
}

// One factory per term (its file).
std::unique_ptr<SampleTerm> makeContactCop(int foot);
std::unique_ptr<SampleTerm> makeContactFriction(int foot);
std::unique_ptr<SampleTerm> makeContactUnilateral(int foot);
std::unique_ptr<SampleTerm> makeSwingClearance();
std::unique_ptr<SampleTerm> makeObstacleClearance();
std::unique_ptr<SampleTerm> makeSelfClearance();
std::unique_ptr<SampleTerm> makePelvisTilt();
std::unique_ptr<SampleTerm> makeVelocityLimit();
std::unique_ptr<SampleTerm> makeTorqueLimit();
std::unique_ptr<SampleTerm> makeJointLimits();
std::unique_ptr<SampleTerm> makeLegReach();
std::unique_ptr<SampleTerm> makeSwayBalance();
std::unique_ptr<SampleTerm> makeElasticDynamics();
std::unique_ptr<EventTerm> makeSwitching();
std::unique_ptr<EventTerm> makeLiftOff();
std::unique_ptr<EventTerm> makeTouchdown();

/// The sample terms in stacking order (contact rows of the right foot, then the left, then the
/// rest), and the switch terms.
std::vector<std::unique_ptr<SampleTerm>> sampleTerms();
std::vector<std::unique_ptr<EventTerm>> eventTerms();

}  // namespace overstep::planner::detail
