#include "overstep/sim/simulator.hpp"

#include <algorithm>
#include <dart/collision/CollisionFilter.hpp>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/dart/DARTCollisionDetector.hpp>
#include <dart/constraint/BoxedLcpConstraintSolver.hpp>
#include <dart/constraint/ConstraintSolver.hpp>
#include <dart/constraint/ContactConstraint.hpp>
#include <dart/constraint/PgsBoxedLcpSolver.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/BoxShape.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/PrismaticJoint.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/SimpleFrame.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/WeldJoint.hpp>
#include <dart/simulation/World.hpp>
#include <deque>
#include <limits>

#include "overstep/core/error.hpp"
#include "overstep/robots/collision.hpp"

namespace overstep::sim {

namespace dd = dart::dynamics;

namespace {

/// Oriented box: pose of its centre and half extents.
struct Obb {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
};

/// True when two boxes are closer than `margin` (or overlap): no separating axis among the 15 of
/// the separating-axis theorem once each box is grown by margin / 2.
bool boxesNear(const Obb& a, const Obb& b, double margin) {
  const Eigen::Matrix3d Ra = a.X.linear(), Rb = b.X.linear();
  const Eigen::Vector3d ha = a.half.array() + 0.5 * margin, hb = b.half.array() + 0.5 * margin;
  const Eigen::Vector3d d = b.X.translation() - a.X.translation();
  auto separated = [&](const Eigen::Vector3d& axis) {
    const double n = axis.norm();
    if (n < 1e-9) return false;
    const Eigen::Vector3d u = axis / n;
    const double ra = (Ra.transpose() * u).cwiseAbs().dot(ha);
    const double rb = (Rb.transpose() * u).cwiseAbs().dot(hb);
    return std::abs(d.dot(u)) > ra + rb;
  };
  for (int i = 0; i < 3; ++i)
    if (separated(Ra.col(i)) || separated(Rb.col(i))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (separated(Ra.col(i).cross(Rb.col(j)))) return false;
  return true;
}

}  // namespace

struct Simulator::Impl {
  robots::WholeBodyModel model;
  TruthEffects truth;
  SimOptions opt;
  dart::simulation::WorldPtr world;
  dd::SkeletonPtr robot;
  std::vector<dd::Joint*> actuated;      // model order
  std::vector<dd::Joint*> elastic;       // model order
  std::vector<double> bushing_inertia;   // kg m^2, bodies below each bushing about its axis
  std::array<dd::BodyNode*, 2> foot{};   // the foot links (capsules, sensors)
  std::array<dd::BodyNode*, 2> sole{};   // what touches the ground: the foot link, or the body on
                                         // its vertical bushing spring (bushing_vertical)
  std::array<dd::Joint*, 2> vertical{};  // that spring's prismatic joint (nullptr: rigid)
  std::array<core::FootDescription, 2> foot_desc{};
  std::array<Eigen::Isometry3d, 2> sole_in_foot{
      {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()}};
  std::array<Obb, 2> foot_box{};  // collision box of each foot, body frame
  std::array<bool, 2> foot_is_box{{false, false}};
  Obb bar_box;
  std::array<std::vector<dd::BodyNode*>, 2> below_sensor;  // bushing links + foot
  std::array<dd::SimpleFramePtr, 2> sensor;
  dd::SimpleFramePtr imu;
  dd::BodyNode* base = nullptr;
  std::vector<std::pair<const dd::BodyNode*, core::CapsuleDescription>> capsules;
  std::vector<bool> capsule_is_foot;
  bool has_obstacle = false;
  robots::ObstacleGeometry obstacle;
  Eigen::VectorXd q_ref, qd_ref;  // what the servos track (after delay and lag)
  std::deque<std::pair<double, std::pair<Eigen::VectorXd, Eigen::VectorXd>>> pending;  // delay
  Eigen::VectorXd q_cmd, qd_cmd;  // newest command released by the delay line
  double t_cmd = 0.0;             // when it was released
  Eigen::VectorXd stick;          // where Coulomb friction holds the servo target (play operator)
  Eigen::VectorXd motor;          // motor-side position (what the encoders read)
  Eigen::VectorXd load_target;    // load-side servo target after the backlash dead band
  Eigen::VectorXd friction;       // N m, joint friction torque of the last step
  // Motor torque of the last few steps (servo impulse / dt + friction), averaged by state(): the
  // velocity servo's per-step impulse swings by tens of N m around the inverse-dynamics torque
  // (measured: 14 N m RMS on the arms and chest during the excitation plan, even with the true
  // base motion), as a current sensor's filter would not show.
  Eigen::MatrixXd motor_torque;  // joints x torque_window
  int torque_slot = 0, torque_filled = 0;
  // Each foot's sensor wrench [F; M] (sensor frame) of the same steps, averaged the same way
  // (the sensor's anti-aliasing filter): sampled once per control period, the per-step value
  // aliased the servo's impulses into a bias (measured: +5..+12 N of summed normal force during
  // the excitation plan, with the base height constant).
  std::array<Eigen::Matrix<double, 6, Eigen::Dynamic>, 2> ft_hist;

  explicit Impl(const robots::WholeBodyModel& m) : model(m) {}
  void addVerticalBushings();
};

void Simulator::Impl::addVerticalBushings() {
  const std::size_t n_model = robot->getNumDofs();
  for (std::size_t f = 0; f < 2; ++f) {
    dd::BodyNode* link = foot[f];
    // The sole slides along the sole frame's normal, from the foot link's origin.
    dd::PrismaticJoint::Properties jp;
    jp.mName = link->getName() + "_VERTICAL";
    jp.mAxis = sole_in_foot[f].linear().col(2);
    auto pair = link->createChildJointAndBodyNodePair<dd::PrismaticJoint>(jp);
    dd::PrismaticJoint* jt = pair.first;
    dd::BodyNode* body = pair.second;
    body->setName(link->getName() + "_SOLE");
    // All but 2 % of the foot's mass is below the bushing; both parts keep the foot's centre of
    // mass, so the bodies below each rotational bushing keep their inertia about its axis.
    const dd::Inertia I = link->getInertia();
    const double keep = 0.02;
    body->setInertia(
        dd::Inertia((1.0 - keep) * I.getMass(), I.getLocalCOM(), (1.0 - keep) * I.getMoment()));
    link->setInertia(dd::Inertia(keep * I.getMass(), I.getLocalCOM(), keep * I.getMoment()));
    std::vector<dd::ShapeNode*> moved;
    for (std::size_t k = 0; k < link->getNumShapeNodes(); ++k)
      if (link->getShapeNode(k)->has<dd::CollisionAspect>()) moved.push_back(link->getShapeNode(k));
    for (dd::ShapeNode* sn : moved) {
      auto* copy =
          body->createShapeNodeWith<dd::CollisionAspect, dd::DynamicsAspect>(sn->getShape());
      copy->setRelativeTransform(sn->getRelativeTransform());
      copy->getDynamicsAspect()->setFrictionCoeff(opt.ground_friction);
      sn->remove();
    }
    // The spring acts explicitly: stable while k dt^2 / m stays below 1 on the sole's mass.
    if (model.description().bushing_vertical_stiffness * opt.dt * opt.dt > body->getMass())
      throw InputError("sim: bushing_vertical stiffness is unstable at this time step on a " +
                       std::to_string(body->getMass()) + " kg foot (k dt^2 / m > 1)");
    jt->setActuatorType(dd::Joint::FORCE);
    jt->setForceLowerLimit(0, -std::numeric_limits<double>::infinity());
    jt->setForceUpperLimit(0, std::numeric_limits<double>::infinity());
    sole[f] = body;
    vertical[f] = jt;
    below_sensor[f].push_back(body);
  }
  // The model's coordinates keep their indices (the two new ones come last): framePose() and
  // the model-order accessors read the robot through them.
  for (std::size_t i = 0; i < n_model; ++i)
    if (robot->getDof(i)->getName() != model.skeleton()->getDof(i)->getName())
      throw std::logic_error("sim: the vertical bushings reordered the robot's coordinates");
}

Simulator::Simulator(const robots::WholeBodyModel& model, const TruthEffects& truth,
                     const SimOptions& options)
    : impl_(std::make_unique<Impl>(model)) {
  Impl& s = *impl_;
  s.truth = truth;
  s.opt = options;
  if (!(options.dt > 0.0 && options.dt <= 0.005))
    throw InputError("sim: time step: expected 0 < dt <= 0.005 s");
  if (!(options.servo_gain > 0.0 && options.servo_gain * options.dt <= 1.0))
    throw InputError("sim: servo gain: expected 0 < Kv dt <= 1");
  const auto& d = s.model.description();
  // The explicit bushing damper on the light foot diverges beyond d dt ~ 0.01 (d = 12 N m s/rad
  // diverged in one of seven step tests at 1 ms, 10 in none; measured, sim/README.md).
  for (double d_e : truth.elastic_damping)
    if (d_e * options.dt > 0.01 + 1e-12)
      throw InputError("sim: bushing damping " + std::to_string(d_e) +
                       " N m s/rad is unstable at this time step (explicit damper: d dt <= 0.01)");
  if (truth.viscous.size() != static_cast<Eigen::Index>(s.model.actuatedCount()) ||
      truth.elastic_stiffness.size() != d.elastic.size())
    throw InputError("sim: truth effects were made for another robot");

  // The robot in half-sitting, soles on z = 0.
  const Eigen::VectorXd q0 = s.model.halfSitting();
  s.model.setPositions(q0);
  s.robot = s.model.skeleton()->cloneSkeleton("robot");
  s.robot->setPositions(s.model.skeleton()->getPositions());
  s.robot->setVelocities(Eigen::VectorXd::Zero(s.robot->getNumDofs()));

  // Bent links: the joint carrying the link sits rotated on its parent.
  for (const auto& b : truth.bends) {
    dd::BodyNode* bn = s.robot->getBodyNode(b.link);
    if (!bn || !bn->getParentJoint())
      throw InputError("sim: bend link '" + b.link + "' is not a body with a parent joint");
    dd::Joint* jt = bn->getParentJoint();
    Eigen::Isometry3d T = jt->getTransformFromParentBodyNode();
    if (b.rotation.norm() > 0.0)
      T.linear() = T.linear() *
                   Eigen::AngleAxisd(b.rotation.norm(), b.rotation.normalized()).toRotationMatrix();
    jt->setTransformFromParentBodyNode(T);
  }
  // Payloads: mass and inertia merged into the link (point masses at an offset).
  for (const auto& p : truth.payloads)
    robots::WholeBodyModel::attachPointMass(*s.robot, p.link, p.mass, p.offset);

  for (int j = 0; j < s.model.actuatedCount(); ++j) {
    dd::DegreeOfFreedom* dof =
        s.robot->getDof(static_cast<std::size_t>(s.model.dartIndex(s.model.actuatedCoordinate(j))));
    dd::Joint* jt = dof->getJoint();
    jt->setActuatorType(dd::Joint::SERVO);
    const double lim = d.actuated[static_cast<std::size_t>(j)].torque;
    jt->setForceLowerLimit(0, -lim);
    jt->setForceUpperLimit(0, lim);
    s.actuated.push_back(jt);
  }
  for (std::size_t e = 0; e < d.elastic.size(); ++e) {
    dd::DegreeOfFreedom* dof = s.robot->getDof(static_cast<std::size_t>(
        s.model.dartIndex(s.model.elasticCoordinate(static_cast<int>(e)))));
    dd::Joint* jt = dof->getJoint();
    // Spring and damper as an explicit joint torque each step: DART's implicit joint spring is
    // implicit only in the free step, not in the contact-impulse step, so under contact the
    // bushing came out 26 % soft (static deflection 13.9 mrad where moment / stiffness gives
    // 10.3; measured), and implicit damping tipped the standing robot over (as runtime.md warns).
    jt->setActuatorType(dd::Joint::FORCE);
    // The URDF gives passive joints effort 0, which DART turns into force limits of 0.
    jt->setForceLowerLimit(0, -std::numeric_limits<double>::infinity());
    jt->setForceUpperLimit(0, std::numeric_limits<double>::infinity());
    jt->setSpringStiffness(0, 0.0);
    jt->setRestPosition(0, 0.0);
    jt->setDampingCoefficient(0, 0.0);
    s.elastic.push_back(jt);
    // Inertia of the bodies below the bushing about its axis (initial posture).
    const auto* rj = dynamic_cast<const dd::RevoluteJoint*>(jt);
    const Eigen::Isometry3d Xj =
        rj->getChildBodyNode()->getWorldTransform() * rj->getTransformFromChildBodyNode();
    const Eigen::Vector3d axis = Xj.linear() * rj->getAxis(), o = Xj.translation();
    double inertia = 0.0;
    std::vector<const dd::BodyNode*> stack{rj->getChildBodyNode()};
    while (!stack.empty()) {
      const dd::BodyNode* b = stack.back();
      stack.pop_back();
      const Eigen::Matrix3d R = b->getWorldTransform().linear();
      const Eigen::Vector3d r = b->getCOM() - o;
      inertia += axis.dot(R * b->getInertia().getMoment() * R.transpose() * axis) +
                 b->getMass() * (r - r.dot(axis) * axis).squaredNorm();
      for (std::size_t c = 0; c < b->getNumChildBodyNodes(); ++c)
        stack.push_back(b->getChildBodyNode(c));
    }
    s.bushing_inertia.push_back(std::max(inertia, 1e-6));
  }

  // Feet, sensors, IMU.
  for (int f = 0; f < 2; ++f) {
    const core::FootDescription* fd = d.foot(f == 0 ? "right" : "left");
    if (!fd) throw InputError("sim: the robot needs a right and a left foot");
    s.foot[static_cast<std::size_t>(f)] = s.robot->getBodyNode(fd->link);
    s.foot_desc[static_cast<std::size_t>(f)] = *fd;
    for (const auto& fr : d.frames)
      if (fr.name == fd->sole_frame && fr.link == fd->link)
        s.sole_in_foot[static_cast<std::size_t>(f)] = fr.X_LF;
    // The sensor frame's link and offset from the YAML.
    for (const auto& fr : d.frames) {
      if (fr.name != fd->force_sensor_frame) continue;
      dd::BodyNode* parent = s.robot->getBodyNode(fr.link);
      s.sensor[static_cast<std::size_t>(f)] =
          std::make_shared<dd::SimpleFrame>(parent, fd->force_sensor_frame, fr.X_LF);
      // Bodies below the sensor: the descendants of the sensor's link.
      std::vector<dd::BodyNode*> stack{parent};
      while (!stack.empty()) {
        dd::BodyNode* b = stack.back();
        stack.pop_back();
        for (std::size_t c = 0; c < b->getNumChildBodyNodes(); ++c) {
          s.below_sensor[static_cast<std::size_t>(f)].push_back(b->getChildBodyNode(c));
          stack.push_back(b->getChildBodyNode(c));
        }
      }
    }
    if (!s.sensor[static_cast<std::size_t>(f)])
      throw InputError("sim: force sensor frame '" + fd->force_sensor_frame + "' not found");
  }
  for (const auto& fr : d.frames)
    if (fr.name == "imu")
      s.imu = std::make_shared<dd::SimpleFrame>(s.robot->getBodyNode(fr.link), "imu", fr.X_LF);
  if (!s.imu) throw InputError("sim: the robot YAML has no 'imu' frame");
  s.base = s.robot->getBodyNode(d.base_link);

  // Only the feet collide (with the ground).
  for (std::size_t b = 0; b < s.robot->getNumBodyNodes(); ++b) {
    dd::BodyNode* bn = s.robot->getBodyNode(b);
    const bool is_foot = bn == s.foot[0] || bn == s.foot[1];
    for (std::size_t k = 0; k < bn->getNumShapeNodes(); ++k) {
      dd::ShapeNode* sn = bn->getShapeNode(k);
      if (!is_foot && sn->has<dd::CollisionAspect>()) sn->removeCollisionAspect();
      if (is_foot && sn->has<dd::DynamicsAspect>())
        sn->getDynamicsAspect()->setFrictionCoeff(options.ground_friction);
    }
  }
  s.sole = s.foot;
  // The bushings' vertical give (the robot description's bushing_vertical; the planner's model
  // leaves it out): each foot's mass and collision box on a vertical spring below its link.
  if (d.bushing_vertical_stiffness > 0.0) s.addVerticalBushings();
  // Capsules for the geometric checks; the obstacle, if any, as a box the feet can stand on.
  for (const auto& c : d.capsules) {
    const dd::BodyNode* bn = s.robot->getBodyNode(c.link);
    if (!bn) continue;
    s.capsules.emplace_back(bn, c);
    s.capsule_is_foot.push_back(bn == s.foot[0] || bn == s.foot[1]);
  }
  if (options.has_obstacle) {
    core::validate(options.obstacle);
    double toes_x = -1e9;
    for (int f = 0; f < 2; ++f) {
      const core::FootDescription* fd = d.foot(f == 0 ? "right" : "left");
      toes_x = std::max(toes_x, (s.model.framePose(s.model.frameIndex(fd->sole_frame)) *
                                 Eigen::Vector3d(fd->sole.x_front, 0.0, 0.0))
                                    .x());
    }
    s.has_obstacle = true;
    s.obstacle = robots::ObstacleGeometry::fromSpec(options.obstacle, toes_x);
  }
  auto ground = dd::Skeleton::create("ground");
  auto gb = ground->createJointAndBodyNodePair<dd::WeldJoint>().second;
  auto box = std::make_shared<dd::BoxShape>(Eigen::Vector3d(20.0, 20.0, 0.2));
  auto* gs = gb->createShapeNodeWith<dd::CollisionAspect, dd::DynamicsAspect>(box);
  gs->setRelativeTranslation(Eigen::Vector3d(0.0, 0.0, -0.1));
  gs->getDynamicsAspect()->setFrictionCoeff(options.ground_friction);

  s.world = dart::simulation::World::create("overstep");
  if (!(options.contact_softness >= 1e-9 && options.contact_softness <= 0.1))
    throw InputError("sim: contact softness: expected 1e-9 to 0.1");
  dart::constraint::ContactConstraint::setConstraintForceMixing(options.contact_softness);
  // With a soft contact the penetration must be pushed back, or a standing robot sinks at the
  // error-reduction velocity cap (DART's 1e-3 m/s: 0.5 mm/s and a 1.4 cm CoM drift in 6 s,
  // measured). ERP 0.2 with a 0.1 m/s cap holds the soles within 0.01 mm of the surface.
  dart::constraint::ContactConstraint::setErrorReductionParameter(0.2);
  dart::constraint::ContactConstraint::setMaxErrorReductionVelocity(0.1);
  s.world->setTimeStep(options.dt);
  s.world->setGravity(Eigen::Vector3d(0.0, 0.0, -d.gravity));
  // The contact impulses by projected Gauss-Seidel (DART's PgsBoxedLcpSolver, to its default
  // tolerance), not DART's default Dantzig pivoting. With both soles down the legs and the
  // ground close a chain that the velocity servos make rigid, and the contact problem leaves the
  // split of the horizontal force between the feet undetermined: Dantzig returns a vertex of its
  // solution set, which jumped between steps (each sole's Fx by 6.3 N per 1 ms step on average
  // and up to 320 N, 63 steps at the friction limit in one default demo; up to 270 N of internal
  // shear on the first step, standing), where projected Gauss-Seidel's solution moves with the
  // state (0.9 N per step, none at the limit; the same with a 1000 times tighter tolerance).
  s.world->setConstraintSolver(std::make_unique<dart::constraint::BoxedLcpConstraintSolver>(
      std::make_shared<dart::constraint::PgsBoxedLcpSolver>(), nullptr));
  s.world->getConstraintSolver()->setCollisionDetector(
      dart::collision::DARTCollisionDetector::create());
  s.world->addSkeleton(ground);
  // The bar is detected, not collided with (collisions()): touching it fails the run anyway,
  // and as a DART box it was unsafe. DART's box-box test reported a contact between the swing
  // foot and the bar's top edge with the sole 3.7 cm above it (measured), and the false impulse
  // on the light foot blew up its bushing within 2 ms.
  if (s.has_obstacle) {
    for (int f = 0; f < 2; ++f) {
      const auto fi = static_cast<std::size_t>(f);
      for (std::size_t k = 0; k < s.sole[fi]->getNumShapeNodes(); ++k) {
        const dd::ShapeNode* sn = s.sole[fi]->getShapeNode(k);
        const auto box_shape = std::dynamic_pointer_cast<const dd::BoxShape>(sn->getShape());
        if (!sn->has<dd::CollisionAspect>() || !box_shape) continue;
        s.foot_box[fi].X = sn->getRelativeTransform();
        s.foot_box[fi].half = 0.5 * box_shape->getSize();
        s.foot_is_box[fi] = true;
      }
    }
    s.bar_box.X.translation() = s.obstacle.centre;
    s.bar_box.half =
        s.obstacle.shape == core::ObstacleSpec::Shape::Box
            ? Eigen::Vector3d(0.5 * s.obstacle.size)
            : Eigen::Vector3d(s.obstacle.radius, 0.5 * s.obstacle.length, s.obstacle.radius);
  }
  s.world->addSkeleton(s.robot);

  const int na = s.model.actuatedCount();
  s.q_ref.resize(na);
  for (int j = 0; j < na; ++j) s.q_ref(j) = s.actuated[static_cast<std::size_t>(j)]->getPosition(0);
  s.qd_ref.setZero(na);
  s.q_cmd = s.q_ref;
  s.qd_cmd = s.qd_ref;
  s.stick = s.q_ref;
  s.motor = s.q_ref;
  s.load_target = s.q_ref;
  s.friction.setZero(na);
  s.motor_torque.setZero(na, std::max(1, s.opt.torque_window));
  for (auto& h : s.ft_hist) h.setZero(6, std::max(1, s.opt.torque_window));
  if (!(options.servo_stiffness > 0.0)) throw InputError("sim: servo stiffness: expected > 0");
}

Simulator::~Simulator() = default;

void Simulator::setCommand(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref) {
  Impl& s = *impl_;
  s.pending.emplace_back(time() + s.truth.command_delay, std::make_pair(q_ref, qd_ref));
}

double Simulator::time() const { return impl_->world->getTime(); }

void Simulator::step() {
  Impl& s = *impl_;
  const double dt = s.opt.dt;
  // Command delay line, then first-order lag of the references.
  while (!s.pending.empty() && s.pending.front().first <= time() + 1e-12) {
    s.q_cmd = s.pending.front().second.first;
    s.qd_cmd = s.pending.front().second.second;
    s.t_cmd = time();
    s.pending.pop_front();
  }
  // Between commands the servo follows the commanded position extrapolated with the commanded
  // velocity (holding the position instead made the joint lead it by qd_ref / Kv). With DART's
  // velocity servo the joint ends the step where the target was at its start plus qd dt, so the
  // target is taken at the start of the step (measured: one step of lead otherwise).
  const double since = time() - s.t_cmd;
  if (s.truth.command_lag > 0.0) {
    const double a = dt / (s.truth.command_lag + dt);
    s.q_ref += a * (s.q_cmd + s.qd_cmd * since - s.q_ref);
    s.qd_ref += a * (s.qd_cmd - s.qd_ref);
  } else {
    s.q_ref = s.q_cmd + s.qd_cmd * since;
    s.qd_ref = s.qd_cmd;
  }
  for (std::size_t j = 0; j < s.actuated.size(); ++j) {
    dd::Joint* jt = s.actuated[j];
    const auto i = static_cast<Eigen::Index>(j);
    // Joint friction (truth). The servo's position loop (stiffness k) lags by friction / k.
    // Coulomb friction F sticks the joint until the servo's error reaches F / k: a play operator
    // of half-width F / k on the reference, and the motor torque it costs, k (q_ref - stick),
    // runs between -F and F (stick-slip). (F tanh(v / 0.01) of the measured velocity fed back
    // into the target has a loop gain servo_gain F / (k 0.01) = 40 at 4 N m, and left a torque
    // residual that no friction model fitted; docs/identification.md.)
    const double v = jt->getVelocity(0);
    const double play = s.truth.coulomb(i) / s.opt.servo_stiffness;
    const double stuck_at = s.stick(i);
    s.stick(i) = std::clamp(stuck_at, s.q_ref(i) - play, s.q_ref(i) + play);
    const bool sticking = play > 0.0 && s.stick(i) == stuck_at;
    s.friction(i) = s.truth.viscous(i) * v + s.opt.servo_stiffness * (s.q_ref(i) - s.stick(i));
    s.motor(i) = s.stick(i) - s.truth.viscous(i) * v / s.opt.servo_stiffness;
    // Backlash (truth): the load side follows the motor only beyond half the dead band.
    const double half = 0.5 * s.truth.backlash(i);
    const double before = s.load_target(i);
    s.load_target(i) = std::clamp(before, s.motor(i) - half, s.motor(i) + half);
    const bool in_band = half > 0.0 && s.load_target(i) == before;
    const double ff = sticking || in_band ? 0.0 : s.qd_ref(i);
    jt->setCommand(0, s.opt.servo_gain * (s.load_target(i) - jt->getPosition(0)) + ff);
  }
  // A foot held flat by the ground (a tenth of the weight, its centre of pressure at least 5 mm
  // inside the sole) makes the bushing move the whole body: the explicit damper is stable there
  // (up to d dt ~ 0.01). A foot in the air, touching down or landing on an edge turns freely
  // (about the edge): a tiny inertia on the damper (d dt / I ~ 2-7), so the damper is integrated
  // implicitly on that inertia. Counting any contact, and then any load, as held both let the
  // bushing spike to 10 rad within two steps (measured: at a planned touchdown, and at a 1 kN
  // edge hit when a lifted foot fell back).
  bool held[2] = {false, false};
  for (int f = 0; f < 2; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    const core::Wrench& w_W = contacts_.foot_wrench[fi];
    if (!contacts_.foot_contact[fi] ||
        w_W.force.z() < 0.1 * s.robot->getMass() * s.model.description().gravity)
      continue;
    const Eigen::Isometry3d X_WS = s.sole[fi]->getWorldTransform() * s.sole_in_foot[fi];
    const core::Wrench w_S = w_W.inFrame(X_WS, core::Axes::kSole);
    if (w_S.force.z() <= 0.0) continue;
    const Eigen::Vector2d cop = core::localCop(w_S);
    const double cx = cop.x(), cy = cop.y(), margin = 0.005;
    const auto& fd = s.foot_desc[fi];
    held[f] = cx > -fd.sole.x_back + margin && cx < fd.sole.x_front - margin &&
              cy > fd.yMin() + margin && cy < fd.yMax() - margin;
  }
  for (std::size_t e = 0; e < s.elastic.size(); ++e) {
    const double d = s.truth.elastic_damping[e];
    const double d_use = held[e / 2] ? d : d / (1.0 + dt * d / s.bushing_inertia[e]);
    s.elastic[e]->setCommand(0, -s.truth.elastic_stiffness[e] * s.elastic[e]->getPosition(0) -
                                    d_use * s.elastic[e]->getVelocity(0));
  }
  for (std::size_t f = 0; f < 2; ++f) {
    dd::Joint* jt = s.vertical[f];
    if (!jt) continue;
    // The same split as the rotational bushings': explicit on a held foot, implicit on the
    // sole's own mass in the air (c dt / m = 1 there).
    const auto& d = s.model.description();
    const double c = d.bushing_vertical_damping, m = s.sole[f]->getMass();
    const double c_use = held[f] ? c : c / (1.0 + dt * c / m);
    jt->setCommand(0,
                   -d.bushing_vertical_stiffness * jt->getPosition(0) - c_use * jt->getVelocity(0));
  }
  s.world->step();

  // Ground reaction on each foot from its constraint impulse (only contacts act on the feet).
  contacts_ = ContactInfo{};
  for (int f = 0; f < 2; ++f) {
    dd::BodyNode* bn = s.sole[static_cast<std::size_t>(f)];
    const Eigen::Vector6d imp = bn->getConstraintImpulse() / dt;  // [angular; linear], body frame
    // About the foot body's origin, in its axes (the sole's, up to the sole offset).
    const core::Wrench w_B = core::Wrench::fromSpatial(imp, core::Axes::kSole);
    contacts_.foot_wrench[static_cast<std::size_t>(f)] =
        w_B.expressedIn(bn->getWorldTransform(), core::Axes::kWorld).about(Eigen::Vector3d::Zero());
    contacts_.foot_contact[static_cast<std::size_t>(f)] = w_B.force.norm() > 1e-6;
  }
  contacts_.contact_points = static_cast<int>(s.world->getLastCollisionResult().getNumContacts());
  for (std::size_t j = 0; j < s.actuated.size(); ++j)
    s.motor_torque(static_cast<Eigen::Index>(j), s.torque_slot) =
        s.actuated[j]->getConstraintImpulse(0) / dt + s.friction(static_cast<Eigen::Index>(j));
  for (int f = 0; f < 2; ++f)
    s.ft_hist[static_cast<std::size_t>(f)].col(s.torque_slot) = sensorWrench(f).forceMoment();
  s.torque_slot = (s.torque_slot + 1) % static_cast<int>(s.motor_torque.cols());
  s.torque_filled = std::min(s.torque_filled + 1, static_cast<int>(s.motor_torque.cols()));
}

void Simulator::settle(int steps) {
  // Dynamic relaxation: let the sway on the bushings run and stop every motion each time its
  // kinetic energy (proxy: the bushing rates) has just peaked, i.e. at the equilibrium.
  Impl& s = *impl_;
  double previous = 0.0;
  for (int i = 0; i < steps; ++i) {
    step();
    // Every velocity, not just the bushings': the soft contact adds a slow mode of its own.
    const double energy = s.robot->getVelocities().squaredNorm();
    if (energy < previous) {
      s.robot->setVelocities(
          Eigen::VectorXd::Zero(static_cast<Eigen::Index>(s.robot->getNumDofs())));
      previous = 0.0;
    } else {
      previous = energy;
    }
  }
  s.world->setTime(0.0);
  s.t_cmd = 0.0;
  s.pending.clear();
}

double Simulator::totalMass() const { return impl_->robot->getMass(); }

double Simulator::massBelowSensor(int foot) const {
  double m = 0.0;
  for (auto* b : impl_->below_sensor[static_cast<std::size_t>(foot)]) m += b->getMass();
  return m;
}

Eigen::Isometry3d Simulator::basePose() const { return impl_->base->getWorldTransform(); }

Eigen::Isometry3d Simulator::framePose(const std::string& frame) const {
  Impl& s = *impl_;
  s.model.skeleton()->setPositions(
      s.robot->getPositions().head(static_cast<Eigen::Index>(s.model.skeleton()->getNumDofs())));
  return s.model.framePose(s.model.frameIndex(frame));
}

double Simulator::baseSpeed() const { return impl_->base->getLinearVelocity().norm(); }

std::array<double, 2> Simulator::obstacleRangeX() const {
  const Impl& s = *impl_;
  if (!s.has_obstacle) return {0.0, 0.0};
  const double half = s.obstacle.shape == core::ObstacleSpec::Shape::Box ? 0.5 * s.obstacle.size.x()
                                                                         : s.obstacle.radius;
  return {s.obstacle.centre.x() - half, s.obstacle.centre.x() + half};
}

Eigen::Vector3d Simulator::com() const { return impl_->robot->getCOM(); }

CollisionStatus Simulator::collisions() const {
  const Impl& s = *impl_;
  CollisionStatus c;
  for (std::size_t i = 0; i < s.capsules.size(); ++i) {
    const auto& [bn, cd] = s.capsules[i];
    const Eigen::Isometry3d X = bn->getWorldTransform();
    const robots::Capsule cap{X * cd.p0, X * cd.p1, cd.radius};
    if (!s.capsule_is_foot[i]) {
      const double low = std::min(cap.p0.z(), cap.p1.z()) - cap.radius;
      if (low < c.ground_clearance) c.ground_clearance = low, c.ground_link = cd.link;
    }
    if (s.has_obstacle) {
      const double dist = robots::obstacleDistanceFcl(cap, s.obstacle);
      if (dist < c.obstacle_distance) c.obstacle_distance = dist, c.obstacle_link = cd.link;
    }
  }
  // The soles' boxes against the bar (a box, or the cylinder's bounding box: conservative).
  if (s.has_obstacle)
    for (int f = 0; f < 2; ++f) {
      const auto fi = static_cast<std::size_t>(f);
      if (!s.foot_is_box[fi]) continue;
      Obb foot = s.foot_box[fi];
      foot.X = s.sole[fi]->getWorldTransform() * foot.X;
      if (boxesNear(foot, s.bar_box, 0.0) && c.obstacle_distance > 0.0) {
        c.obstacle_distance = 0.0;
        c.obstacle_link = s.foot[fi]->getName();
      }
    }
  return c;
}

Eigen::VectorXd Simulator::jointPositions() const {
  const Impl& s = *impl_;
  Eigen::VectorXd q(static_cast<Eigen::Index>(s.actuated.size()));
  for (std::size_t j = 0; j < s.actuated.size(); ++j)
    q(static_cast<Eigen::Index>(j)) = s.actuated[j]->getPosition(0);
  return q;
}

Eigen::Vector4d Simulator::elasticPositions() const {
  Eigen::Vector4d q;
  for (int e = 0; e < 4; ++e) q(e) = impl_->elastic[static_cast<std::size_t>(e)]->getPosition(0);
  return q;
}

Eigen::Vector4d Simulator::elasticExternalTorque() const {
  const Impl& s = *impl_;
  const Eigen::Vector3d g(0.0, 0.0, -s.model.description().gravity);
  Eigen::Vector4d out;
  for (int e = 0; e < 4; ++e) {
    const auto* jt = dynamic_cast<const dd::RevoluteJoint*>(s.elastic[static_cast<std::size_t>(e)]);
    const dd::BodyNode* child = jt->getChildBodyNode();
    const Eigen::Isometry3d Xj = child->getWorldTransform() * jt->getTransformFromChildBodyNode();
    const Eigen::Vector3d axis = Xj.linear() * jt->getAxis(), o = Xj.translation();
    const int f = e / 2;
    Eigen::Vector3d m = contacts_.foot_wrench[static_cast<std::size_t>(f)].about(o).moment;
    std::vector<const dd::BodyNode*> stack{child};  // the bodies below this joint
    while (!stack.empty()) {
      const dd::BodyNode* b = stack.back();
      stack.pop_back();
      m += (b->getCOM() - o).cross(b->getMass() * g);
      for (std::size_t c = 0; c < b->getNumChildBodyNodes(); ++c)
        stack.push_back(b->getChildBodyNode(c));
    }
    out(e) = axis.dot(m);
  }
  return out;
}

core::Wrench Simulator::sensorWrench(int f) const {
  const Impl& s = *impl_;
  const Eigen::Vector3d g(0.0, 0.0, -s.model.description().gravity);
  // What the foot side transmits to the leg through the sensor, by Newton-Euler on the bodies
  // below it: ground reaction + their weight - their momentum rate, about the sensor origin.
  const Eigen::Vector3d o =
      s.sensor[static_cast<std::size_t>(f)]->getWorldTransform().translation();
  core::Wrench w = contacts_.foot_wrench[static_cast<std::size_t>(f)].about(o);
  for (const dd::BodyNode* b : s.below_sensor[static_cast<std::size_t>(f)]) {
    const double m = b->getMass();
    const Eigen::Vector3d c = b->getCOM();
    const Eigen::Matrix3d R = b->getWorldTransform().linear();
    const Eigen::Matrix3d Iw = R * b->getInertia().getMoment() * R.transpose();
    const Eigen::Vector3d om = b->getAngularVelocity(), al = b->getAngularAcceleration();
    const Eigen::Vector3d force = m * (g - b->getCOMLinearAcceleration());
    const Eigen::Vector3d torque_c = -(Iw * al + om.cross(Iw * om));
    w.moment += torque_c + (c - o).cross(force);
    w.force += force;
  }
  return w
      .expressedIn(s.sensor[static_cast<std::size_t>(f)]->getWorldTransform().inverse(),
                   core::Axes::kSensor)
      .about(Eigen::Vector3d::Zero());
}

core::RobotState Simulator::state() const {
  const Impl& s = *impl_;
  core::RobotState st;
  const int na = s.model.actuatedCount();
  st.resize(na);
  st.utime = static_cast<std::int64_t>(std::llround(time() * 1e6));
  for (int j = 0; j < na; ++j) {
    const dd::Joint* jt = s.actuated[static_cast<std::size_t>(j)];
    // Motor-side encoder: the load-side angle plus the backlash offset.
    st.q(j) = jt->getPosition(0) + (s.motor(j) - s.load_target(j));
    st.qd(j) = jt->getVelocity(0);
    // Motor torque: what the servo applies plus the joint friction it overcomes, averaged over
    // the last torque_window steps (a current sensor's filter).
    st.tau(j) = s.torque_filled > 0
                    ? s.motor_torque.row(j).head(s.torque_filled).sum() / s.torque_filled
                    : jt->getConstraintImpulse(0) / s.opt.dt + s.friction(j);
  }
  for (int f = 0; f < 2; ++f) {
    const auto& h = s.ft_hist[static_cast<std::size_t>(f)];
    const core::Wrench w = s.torque_filled > 0
                               ? core::Wrench::fromForceMoment(
                                     h.leftCols(s.torque_filled).rowwise().sum() / s.torque_filled,
                                     core::Axes::kSensor)
                               : sensorWrench(f);
    (f == 0 ? st.ft_right : st.ft_left) = s.truth.ft[static_cast<std::size_t>(f)].measured(w);
  }
  const Eigen::Vector3d g(0.0, 0.0, -s.model.description().gravity);
  const Eigen::Isometry3d Xi = s.imu->getWorldTransform();
  st.imu_orientation = Eigen::Quaterniond(Xi.linear());
  st.imu_angular_velocity = Xi.linear().transpose() * s.imu->getAngularVelocity();
  st.imu_linear_acceleration = Xi.linear().transpose() * (s.imu->getLinearAcceleration() - g);
  st.has_ground_truth = true;
  st.base_pose = s.base->getWorldTransform();
  st.base_linear_velocity = s.base->getLinearVelocity();
  st.base_angular_velocity = s.base->getAngularVelocity();
  return st;
}

}  // namespace overstep::sim
