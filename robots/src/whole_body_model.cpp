#include "overstep/robots/whole_body_model.hpp"

#include <urdf_parser/urdf_parser.h>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/FreeJoint.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/utils/urdf/DartLoader.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <unordered_map>

#include "overstep/core/error.hpp"
#include "overstep/core/stderr_capture.hpp"

namespace overstep::robots {
namespace {

/// Each collision and visual shape of `link` with finite, positive sizes: DART asserts on a box,
/// sphere or cylinder of size <= 0 (an abort; found by fuzz_robot's long run), and a mesh's scale
/// must be finite.
void checkShapes(const std::string& path, const std::string& name, const urdf::Link& link) {
  auto check = [&](const urdf::GeometrySharedPtr& g, const char* what) {
    if (!g) return;
    auto bad = [&](const std::string& size) {
      throw InputError(path + ": link '" + name + "' " + what + " " + size +
                       ": expected finite and > 0");
    };
    auto ok = [](double v) { return std::isfinite(v) && v > 0.0 && v <= 1e3; };
    switch (g->type) {
      case urdf::Geometry::BOX: {
        const auto& b = static_cast<const urdf::Box&>(*g).dim;
        if (!ok(b.x) || !ok(b.y) || !ok(b.z)) bad("box size");
        break;
      }
      case urdf::Geometry::SPHERE:
        if (!ok(static_cast<const urdf::Sphere&>(*g).radius)) bad("sphere radius");
        break;
      case urdf::Geometry::CYLINDER: {
        const auto& c = static_cast<const urdf::Cylinder&>(*g);
        if (!ok(c.radius) || !ok(c.length)) bad("cylinder size");
        break;
      }
      case urdf::Geometry::MESH: {
        const auto& sc = static_cast<const urdf::Mesh&>(*g).scale;
        if (!ok(std::abs(sc.x)) || !ok(std::abs(sc.y)) || !ok(std::abs(sc.z))) bad("mesh scale");
        break;
      }
    }
  };
  for (const auto& c : link.collision_array)
    if (c) check(c->geometry, "collision");
  if (link.collision) check(link.collision->geometry, "collision");
  for (const auto& v : link.visual_array)
    if (v) check(v->geometry, "visual");
  if (link.visual) check(link.visual->geometry, "visual");
}

using dart::dynamics::BodyNode;
using dart::dynamics::Frame;
using dart::dynamics::SkeletonPtr;

/// Bounds of a URDF that urdfdom (TinyXML parses recursively: 100,000 nested elements overflowed
/// the stack) and DART (assertions on huge or non-finite values) can be given.
constexpr std::size_t kMaxUrdfBytes = 16u << 20;
constexpr int kMaxXmlDepth = 64;  // a URDF is 4-5 deep: robot / link / inertial / origin
constexpr std::size_t kMaxLinks = 1000;
constexpr double kMaxLength = 100.0;    // m: origins, geometry
constexpr double kMaxMass = 1e4;        // kg per link
constexpr double kMaxInertia = 1e4;     // kg m^2 per entry
constexpr double kMaxJointValue = 1e6;  // limits (rad, rad/s, N m), damping, friction

/// The element nesting depth of `xml`, refused beyond kMaxXmlDepth before any parser sees it
/// (comments, CDATA, processing instructions and declarations skipped, quoted attributes
/// honoured). Not a validation of the XML: urdfdom does that.
void checkXmlNesting(const std::string& xml, const std::string& path) {
  if (xml.size() > kMaxUrdfBytes)
    throw InputError(path + ": " + std::to_string(xml.size()) + " bytes, more than a URDF of " +
                     std::to_string(kMaxUrdfBytes >> 20) + " MiB");
  int depth = 0;
  std::size_t i = 0;
  const auto skipTo = [&](const char* end, std::size_t from) {
    const std::size_t at = xml.find(end, from);
    return at == std::string::npos ? xml.size() : at + std::strlen(end);
  };
  while ((i = xml.find('<', i)) != std::string::npos) {
    if (xml.compare(i, 4, "<!--") == 0) {
      i = skipTo("-->", i + 4);
    } else if (xml.compare(i, 9, "<![CDATA[") == 0) {
      i = skipTo("]]>", i + 9);
    } else if (xml.compare(i, 2, "<?") == 0) {
      i = skipTo("?>", i + 2);
    } else if (xml.compare(i, 2, "<!") == 0 || xml.compare(i, 2, "</") == 0) {
      if (xml[i + 1] == '/') --depth;
      i = skipTo(">", i + 2);
    } else {
      std::size_t j = i + 1;
      char quote = 0;
      for (; j < xml.size(); ++j) {
        const char c = xml[j];
        if (quote) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          break;
        }
      }
      if (j < xml.size() && xml[j - 1] != '/' && ++depth > kMaxXmlDepth)
        throw InputError(path + ": elements nested more than " + std::to_string(kMaxXmlDepth) +
                         " deep (at byte " + std::to_string(i) + ")");
      i = j + 1;
    }
  }
}

/// Throws "PATH: WHAT: expected finite, |x| <= LIMIT, got V" for the first bad value.
void checkFinite(const std::string& path, const std::string& what, double v, double limit) {
  if (!std::isfinite(v) || std::abs(v) > limit) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": expected a finite value of magnitude <= %g, got %g", limit,
                  v);
    throw InputError(path + ": " + what + buf);
  }
}

void checkPose(const std::string& path, const std::string& what, const urdf::Pose& pose) {
  checkFinite(path, what + " origin xyz", pose.position.x, kMaxLength);
  checkFinite(path, what + " origin xyz", pose.position.y, kMaxLength);
  checkFinite(path, what + " origin xyz", pose.position.z, kMaxLength);
  const urdf::Rotation& r = pose.rotation;
  for (const double q : {r.x, r.y, r.z, r.w})
    checkFinite(path, what + " origin rpy", q, 1.0 + 1e-9);
}

void checkGeometry(const std::string& path, const std::string& what,
                   const urdf::GeometrySharedPtr& g) {
  if (!g) return;
  switch (g->type) {
    case urdf::Geometry::SPHERE:
      checkFinite(path, what + " sphere radius", static_cast<const urdf::Sphere&>(*g).radius,
                  kMaxLength);
      break;
    case urdf::Geometry::BOX: {
      const auto& b = static_cast<const urdf::Box&>(*g).dim;
      for (const double v : {b.x, b.y, b.z}) checkFinite(path, what + " box size", v, kMaxLength);
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& c = static_cast<const urdf::Cylinder&>(*g);
      checkFinite(path, what + " cylinder radius", c.radius, kMaxLength);
      checkFinite(path, what + " cylinder length", c.length, kMaxLength);
      break;
    }
    case urdf::Geometry::MESH: {
      const auto& m = static_cast<const urdf::Mesh&>(*g).scale;
      for (const double v : {m.x, m.y, m.z}) checkFinite(path, what + " mesh scale", v, 1e3);
      break;
    }
  }
}

/// Every number urdfdom read from the URDF, finite and inside physical bounds, before DART sees
/// them (issue 20: 1e308 reached DART's assertions).
void checkUrdfValues(const urdf::ModelInterface& model, const std::string& path) {
  if (model.links_.size() > kMaxLinks)
    throw InputError(path + ": " + std::to_string(model.links_.size()) + " links, more than " +
                     std::to_string(kMaxLinks));
  for (const auto& [name, link] : model.links_) {
    const std::string w = "link '" + name + "'";
    if (const auto& in = link->inertial) {
      checkPose(path, w + " inertial", in->origin);
      checkFinite(path, w + " mass", in->mass, kMaxMass);
      for (const double v : {in->ixx, in->ixy, in->ixz, in->iyy, in->iyz, in->izz})
        checkFinite(path, w + " inertia", v, kMaxInertia);
    }
    for (const auto& c : link->collision_array) {
      checkPose(path, w + " collision", c->origin);
      checkGeometry(path, w + " collision", c->geometry);
    }
    for (const auto& v : link->visual_array) {
      checkPose(path, w + " visual", v->origin);
      checkGeometry(path, w + " visual", v->geometry);
    }
  }
  for (const auto& [name, joint] : model.joints_) {
    const std::string w = "joint '" + name + "'";
    checkPose(path, w, joint->parent_to_joint_origin_transform);
    const urdf::Vector3& a = joint->axis;
    for (const double v : {a.x, a.y, a.z}) checkFinite(path, w + " axis", v, 1e3);
    if (joint->type != urdf::Joint::FIXED && !(a.x * a.x + a.y * a.y + a.z * a.z > 1e-12))
      throw InputError(path + ": " + w + " axis: expected a non-zero vector");
    if (const auto& l = joint->limits) {
      for (const double v : {l->lower, l->upper, l->effort, l->velocity})
        checkFinite(path, w + " limit", v, kMaxJointValue);
    }
    if (const auto& dy = joint->dynamics) {
      checkFinite(path, w + " damping", dy->damping, kMaxJointValue);
      checkFinite(path, w + " friction", dy->friction, kMaxJointValue);
    }
  }
}

/// Checks the URDF against the description with urdfdom before DART sees it (Debian's DART aborts
/// on assertions, so invalid masses must never reach it). What urdfdom (and TinyXML) print goes
/// into the one-line error.
void validateUrdf(const core::RobotDescription& d, const std::string& urdf_text) {
  const std::string& path = d.urdf_path;
  checkXmlNesting(urdf_text, path);
  urdf::ModelInterfaceSharedPtr model;
  {
    core::StderrCapture said;
    model = urdf::parseURDF(urdf_text);
    const std::string text = said.text();
    if (!model)
      throw InputError(path + ": malformed URDF (urdfdom: " +
                       (text.empty() ? std::string("could not parse it") : text) + ")");
  }
  checkUrdfValues(*model, path);
  if (!model->getRoot() || model->getRoot()->name != d.base_link) {
    throw InputError(path + ": root link is '" + (model->getRoot() ? model->getRoot()->name : "") +
                     "', expected base_link '" + d.base_link + "' from " + d.yaml_path);
  }
  std::set<std::string> named;
  auto checkJoint = [&](const std::string& name, const char* what) {
    auto it = model->joints_.find(name);
    if (it == model->joints_.end()) {
      throw InputError(path + ": has no joint '" + name + "' (named as " + what + " in " +
                       d.yaml_path + ")");
    }
    if (it->second->type != urdf::Joint::REVOLUTE && it->second->type != urdf::Joint::CONTINUOUS) {
      throw InputError(path + ": joint '" + name + "' must be revolute, as " + what);
    }
    named.insert(name);
  };
  for (const auto& a : d.actuated) checkJoint(a.name, "an actuated joint");
  for (const auto& e : d.elastic) checkJoint(e.name, "an elastic joint");
  for (const auto& [name, joint] : model->joints_) {
    if (joint->type != urdf::Joint::FIXED && !named.count(name)) {
      throw InputError(path + ": movable joint '" + name + "' is neither actuated nor elastic in " +
                       d.yaml_path);
    }
  }
  for (const auto& [name, link] : model->links_) {
    const auto& in = link->inertial;
    if (!in) throw InputError(path + ": link '" + name + "' has no <inertial>");
    if (!(in->mass > 0.0) || !std::isfinite(in->mass)) {
      throw InputError(path + ": link '" + name + "' mass: expected > 0, got " +
                       std::to_string(in->mass));
    }
    Eigen::Matrix3d I;
    I << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(I);
    if (!I.allFinite() || es.eigenvalues().minCoeff() <= 0.0) {
      throw InputError(path + ": link '" + name + "' inertia: expected positive definite");
    }
    checkShapes(path, name, *link);
  }
  for (const auto& f : d.frames) {
    if (!model->getLink(f.link)) {
      throw InputError(d.yaml_path + ": frame '" + f.name + "' names link '" + f.link +
                       "', which " + path + " does not have");
    }
  }
  for (const auto& c : d.capsules) {
    if (!model->getLink(c.link)) {
      throw InputError(d.yaml_path + ": capsule names link '" + c.link + "', which " + path +
                       " does not have");
    }
  }
  for (const auto& f : d.feet) {
    if (!model->getLink(f.link)) {
      throw InputError(d.yaml_path + ": foot '" + f.side + "' names link '" + f.link + "', which " +
                       path + " does not have");
    }
  }
}

}  // namespace

struct WholeBodyModel::Impl {
  core::RobotDescription desc;
  SkeletonPtr skel;
  int n = 0;
  int nb = 0;
  std::vector<int> perm;       // model index -> DART index
  std::vector<int> from_dart;  // DART index -> model index
  // Scratch for the setters, anchorBase and contactWrenchFromBase (a model serves one thread at
  // a time).
  Eigen::VectorXd dart_order;
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd reflected;  // per model coordinate: rotor term (0 for base/elastic)
  Eigen::VectorXd stiffness;  // per model coordinate
  Eigen::VectorXd damping;    // per model coordinate
  struct FrameRef {
    std::string name;
    BodyNode* body;
    Eigen::Isometry3d X_BF;
  };
  std::vector<FrameRef> frames;
  std::unordered_map<std::string, int> frame_index;
  double mass = 0.0;

  void bindFrames() {
    frames.clear();
    frame_index.clear();
    for (std::size_t i = 0; i < skel->getNumBodyNodes(); ++i) {
      BodyNode* b = skel->getBodyNode(i);
      frame_index[b->getName()] = static_cast<int>(frames.size());
      frames.push_back({b->getName(), b, Eigen::Isometry3d::Identity()});
    }
    for (const auto& f : desc.frames) {
      frame_index[f.name] = static_cast<int>(frames.size());
      frames.push_back({f.name, skel->getBodyNode(f.link), f.X_LF});
    }
  }

  /// x in DART's order, in the scratch vector.
  const Eigen::VectorXd& inDartOrder(const Eigen::VectorXd& x) {
    dart_order.resize(n);
    for (int i = 0; i < n; ++i) dart_order(perm[i]) = x(i);
    return dart_order;
  }
  /// World-aligned Jacobian of a point of `body` (p_BP in the body frame) in model columns:
  /// DART's TemplatedJacobianNode::getWorldJacobian(offset) on the body's cached Jacobian, with
  /// the same arithmetic, written into J's columns.
  void pointJacobian(const BodyNode* body, const Eigen::Vector3d& p_BP, Eigen::MatrixXd& J) const {
    const dart::math::Jacobian& J_body = body->getWorldJacobian();  // 6 x dependent coordinates
    const Eigen::Vector3d r = body->getWorldTransform().linear() * p_BP;
    const std::vector<std::size_t>& deps = body->getDependentGenCoordIndices();
    J.setZero(6, n);
    for (std::size_t k = 0; k < deps.size(); ++k) {
      const auto c = static_cast<Eigen::Index>(k);
      const int col = from_dart[deps[k]];
      J.col(col).head<3>() = J_body.col(c).head<3>();
      J(3, col) = J_body(3, c) + (J_body(1, c) * r(2) - J_body(2, c) * r(1));
      J(4, col) = J_body(4, c) + (J_body(2, c) * r(0) - J_body(0, c) * r(2));
      J(5, col) = J_body(5, c) + (J_body(0, c) * r(1) - J_body(1, c) * r(0));
    }
  }
  Eigen::VectorXd fromDart(const Eigen::VectorXd& x) const {
    Eigen::VectorXd out(n);
    for (int i = 0; i < n; ++i) out(i) = x(perm[i]);
    return out;
  }
  Eigen::MatrixXd colsFromDart(const Eigen::MatrixXd& J) const {
    Eigen::MatrixXd out(J.rows(), n);
    for (int i = 0; i < n; ++i) out.col(i) = J.col(perm[i]);
    return out;
  }
  void checkSize(const Eigen::VectorXd& x, const char* what) const {
    if (x.size() != n) {
      throw InputError(std::string(what) + ": expected " + std::to_string(n) + " entries, got " +
                       std::to_string(x.size()));
    }
  }
  const FrameRef& frame(int i) const {
    if (i < 0 || i >= static_cast<int>(frames.size())) {
      throw InputError("frame index " + std::to_string(i) + " out of range");
    }
    return frames[static_cast<std::size_t>(i)];
  }
};

WholeBodyModel::WholeBodyModel(core::RobotDescription description)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.desc = std::move(description);
  const std::string urdf_text = core::readFile(m.desc.urdf_path);
  validateUrdf(m.desc, urdf_text);

  dart::utils::DartLoader::Options opts;
  opts.mDefaultRootJointType = m.desc.floating_base
                                   ? dart::utils::DartLoader::RootJointType::FLOATING
                                   : dart::utils::DartLoader::RootJointType::FIXED;
  dart::utils::DartLoader loader(opts);
  {
    core::StderrCapture said;  // DART's warnings and errors go into the error line
    m.skel =
        loader.parseSkeletonString(urdf_text, dart::common::Uri::createFromPath(m.desc.urdf_path));
    const std::string text = said.text();
    if (!m.skel)
      throw InputError(m.desc.urdf_path + ": DART could not build a skeleton from it" +
                       (text.empty() ? std::string() : " (" + text + ")"));
  }
  m.skel->setGravity(Eigen::Vector3d(0.0, 0.0, -m.desc.gravity));

  m.nb = m.desc.floating_base ? 6 : 0;
  const int na = static_cast<int>(m.desc.actuated.size());
  const int ne = static_cast<int>(m.desc.elastic.size());
  m.n = m.nb + na + ne;
  if (static_cast<int>(m.skel->getNumDofs()) != m.n) {
    throw InputError(m.desc.urdf_path + ": skeleton has " + std::to_string(m.skel->getNumDofs()) +
                     " coordinates, expected " + std::to_string(m.n) + " from " + m.desc.yaml_path);
  }
  m.perm.assign(static_cast<std::size_t>(m.n), -1);
  for (int i = 0; i < m.nb; ++i) m.perm[static_cast<std::size_t>(i)] = i;
  m.reflected = Eigen::VectorXd::Zero(m.n);
  m.stiffness = Eigen::VectorXd::Zero(m.n);
  m.damping = Eigen::VectorXd::Zero(m.n);
  for (int i = 0; i < na; ++i) {
    const auto& a = m.desc.actuated[static_cast<std::size_t>(i)];
    dart::dynamics::Joint* j = m.skel->getJoint(a.name);
    m.perm[static_cast<std::size_t>(m.nb + i)] = static_cast<int>(j->getIndexInSkeleton(0));
    m.reflected(m.nb + i) = a.reflectedInertia();
    j->setLimitEnforcement(false);
  }
  for (int i = 0; i < ne; ++i) {
    const auto& e = m.desc.elastic[static_cast<std::size_t>(i)];
    dart::dynamics::Joint* j = m.skel->getJoint(e.name);
    const int c = m.nb + na + i;
    m.perm[static_cast<std::size_t>(c)] = static_cast<int>(j->getIndexInSkeleton(0));
    j->setSpringStiffness(0, e.stiffness);
    j->setRestPosition(0, 0.0);
    j->setDampingCoefficient(0, e.damping);
    j->setLimitEnforcement(false);
    m.stiffness(c) = e.stiffness;
    m.damping(c) = e.damping;
  }
  m.from_dart.assign(static_cast<std::size_t>(m.n), -1);
  for (int i = 0; i < m.n; ++i) m.from_dart[static_cast<std::size_t>(m.perm[i])] = i;
  // A model overlay's payloads (docs/model-overlay.md).
  for (const auto& p : m.desc.effects.payloads) {
    try {
      attachPointMass(*m.skel, p.link, p.mass, p.offset);
    } catch (const InputError& e) {
      throw InputError(m.desc.yaml_path + ": " + e.what());
    }
  }
  m.mass = m.skel->getMass();
  m.bindFrames();
}

void WholeBodyModel::attachPointMass(dart::dynamics::Skeleton& skel, const std::string& link,
                                     double mass, const Eigen::Vector3d& offset) {
  dart::dynamics::BodyNode* bn = skel.getBodyNode(link);
  if (!bn) throw InputError("payload link '" + link + "' is not a body of the robot");
  const dart::dynamics::Inertia I = bn->getInertia();
  const double m0 = I.getMass(), m1 = m0 + mass;
  const Eigen::Vector3d c0 = I.getLocalCOM(), c1 = (m0 * c0 + mass * offset) / m1;
  auto shifted = [](const Eigen::Vector3d& r) {
    return (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose()).eval();
  };
  const Eigen::Matrix3d J = I.getMoment() + m0 * shifted(c0 - c1) + mass * shifted(offset - c1);
  bn->setInertia(dart::dynamics::Inertia(m1, c1, J));
}

WholeBodyModel WholeBodyModel::fromFile(const std::string& yaml_path) {
  return WholeBodyModel(core::loadRobotDescription(yaml_path));
}

WholeBodyModel::WholeBodyModel(const WholeBodyModel& other)
    : impl_(std::make_unique<Impl>(*other.impl_)) {
  impl_->skel = other.impl_->skel->cloneSkeleton();
  impl_->bindFrames();
}

WholeBodyModel& WholeBodyModel::operator=(const WholeBodyModel& other) {
  if (this != &other) *this = WholeBodyModel(other);
  return *this;
}

WholeBodyModel::WholeBodyModel(WholeBodyModel&&) noexcept = default;
WholeBodyModel& WholeBodyModel::operator=(WholeBodyModel&&) noexcept = default;
WholeBodyModel::~WholeBodyModel() = default;

const core::RobotDescription& WholeBodyModel::description() const { return impl_->desc; }
int WholeBodyModel::dofs() const { return impl_->n; }
int WholeBodyModel::baseDofs() const { return impl_->nb; }
int WholeBodyModel::actuatedCount() const { return static_cast<int>(impl_->desc.actuated.size()); }
int WholeBodyModel::elasticCount() const { return static_cast<int>(impl_->desc.elastic.size()); }
double WholeBodyModel::totalMass() const { return impl_->mass; }
int WholeBodyModel::dartIndex(int i) const { return impl_->perm.at(static_cast<std::size_t>(i)); }
std::shared_ptr<dart::dynamics::Skeleton> WholeBodyModel::skeleton() const { return impl_->skel; }

std::vector<std::string> WholeBodyModel::coordinateNames() const {
  std::vector<std::string> names;
  if (impl_->nb == 6) names = {"base_rx", "base_ry", "base_rz", "base_x", "base_y", "base_z"};
  for (const auto& a : impl_->desc.actuated) names.push_back(a.name);
  for (const auto& e : impl_->desc.elastic) names.push_back(e.name);
  return names;
}

void WholeBodyModel::setPositions(const Eigen::VectorXd& q) {
  impl_->checkSize(q, "positions");
  impl_->skel->setPositions(impl_->inDartOrder(q));
}
void WholeBodyModel::setVelocities(const Eigen::VectorXd& v) {
  impl_->checkSize(v, "velocities");
  impl_->skel->setVelocities(impl_->inDartOrder(v));
}
void WholeBodyModel::setAccelerations(const Eigen::VectorXd& a) {
  impl_->checkSize(a, "accelerations");
  // Coordinate by coordinate, as MetaSkeleton::setAccelerations does (which also builds a
  // std::string for its error message on every call).
  for (int i = 0; i < impl_->n; ++i)
    impl_->skel->getDof(static_cast<std::size_t>(impl_->perm[i]))->setAcceleration(a(i));
}
void WholeBodyModel::setState(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                              const Eigen::VectorXd& a) {
  setPositions(q);
  setVelocities(v);
  setAccelerations(a);
}
Eigen::VectorXd WholeBodyModel::positions() const {
  return impl_->fromDart(impl_->skel->getPositions());
}
Eigen::VectorXd WholeBodyModel::velocities() const {
  return impl_->fromDart(impl_->skel->getVelocities());
}
Eigen::VectorXd WholeBodyModel::accelerations() const {
  return impl_->fromDart(impl_->skel->getAccelerations());
}

Eigen::VectorXd WholeBodyModel::integrate(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                          double dt) const {
  impl_->checkSize(q, "positions");
  impl_->checkSize(v, "velocities");
  Eigen::VectorXd out = q + v * dt;
  if (impl_->nb == 6) {
    Eigen::Isometry3d X = dart::dynamics::FreeJoint::convertToTransform(q.head<6>());
    const Eigen::Vector6d V = v.head<6>() * dt;  // body-frame twist
    X = X * dart::math::expMap(V);
    out.head<6>() = dart::dynamics::FreeJoint::convertToPositions(X);
  }
  return out;
}

Eigen::VectorXd WholeBodyModel::difference(const Eigen::VectorXd& q1,
                                           const Eigen::VectorXd& q0) const {
  impl_->checkSize(q1, "positions");
  impl_->checkSize(q0, "positions");
  Eigen::VectorXd out = q1 - q0;
  if (impl_->nb == 6) {
    const Eigen::Isometry3d X0 = dart::dynamics::FreeJoint::convertToTransform(q0.head<6>());
    const Eigen::Isometry3d X1 = dart::dynamics::FreeJoint::convertToTransform(q1.head<6>());
    out.head<6>() = dart::math::logMap(X0.inverse() * X1);
  }
  return out;
}

Eigen::VectorXd WholeBodyModel::halfSitting() {
  const Eigen::VectorXd saved = impl_->skel->getPositions();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(impl_->n);
  q.segment(impl_->nb, actuatedCount()) = impl_->desc.half_sitting;
  const auto* r = impl_->desc.foot("right");
  const auto* l = impl_->desc.foot("left");
  if (impl_->nb == 6 && r && l) {
    setPositions(q);
    const Eigen::Vector3d mid = 0.5 * (framePose(frameIndex(r->sole_frame)).translation() +
                                       framePose(frameIndex(l->sole_frame)).translation());
    q.segment<3>(3) = -mid;
  }
  impl_->skel->setPositions(saved);
  return q;
}

void WholeBodyModel::anchorBase(int frame, const Eigen::Isometry3d& X_WF, Eigen::VectorXd& q,
                                Eigen::VectorXd& v, Eigen::VectorXd& a) {
  if (impl_->nb != 6) throw InputError("anchorBase needs a floating-base robot");
  impl_->checkSize(q, "positions");
  impl_->checkSize(v, "velocities");
  impl_->checkSize(a, "accelerations");
  // The frame in the base body from the joints alone: the relative transforms from the base down
  // (DART's world transforms with the base at the identity, the same products), with the base
  // left where it is until it is set. A call whose joints and resulting base are those of the
  // previous one (e.g. only velocities or accelerations differ) leaves DART's kinematics cached.
  const dart::dynamics::Joint* root = impl_->skel->getRootJoint();
  for (std::size_t i = 0; i < 6; ++i) q(static_cast<Eigen::Index>(i)) = root->getPosition(i);
  setPositions(q);
  const auto& f = impl_->frame(frame);
  const BodyNode* chain[64];
  int depth = 0;
  for (const BodyNode* b = f.body; b->getParentBodyNode() != nullptr; b = b->getParentBodyNode()) {
    if (depth == 64)
      throw InputError("anchorBase: the frame is more than 64 bodies below the base");
    chain[depth++] = b;
  }
  Eigen::Isometry3d X_BF = Eigen::Isometry3d::Identity();
  for (int i = depth - 1; i >= 0; --i) X_BF = X_BF * chain[i]->getRelativeTransform();
  X_BF = X_BF * f.X_BF;
  q.head<6>() = dart::dynamics::FreeJoint::convertToPositions(X_WF * X_BF.inverse());
  setPositions(q);
  Eigen::MatrixXd& J = impl_->jacobian;
  frameJacobian(frame, J);
  const Eigen::PartialPivLU<Eigen::Matrix<double, 6, 6>> Jb(J.leftCols<6>());
  v.head<6>().setZero();
  Vector6d Jv;
  Jv.noalias() = J * v;
  v.head<6>() = -Jb.solve(Jv);
  a.head<6>().setZero();
  setVelocities(v);
  setAccelerations(a);
  a.head<6>() = -Jb.solve(frameAcceleration(frame));
  setAccelerations(a);
}

bool WholeBodyModel::hasFrame(const std::string& name) const {
  return impl_->frame_index.count(name) != 0;
}

int WholeBodyModel::frameIndex(const std::string& name) const {
  auto it = impl_->frame_index.find(name);
  if (it == impl_->frame_index.end()) {
    throw InputError("unknown frame or link '" + name + "' in robot '" + impl_->desc.name + "'");
  }
  return it->second;
}

Eigen::Isometry3d WholeBodyModel::framePose(int frame) const {
  const auto& f = impl_->frame(frame);
  return f.body->getWorldTransform() * f.X_BF;
}

Eigen::Isometry3d WholeBodyModel::jointPose(const std::string& joint) const {
  const dart::dynamics::Joint* j = impl_->skel->getJoint(joint);
  if (!j) throw InputError("unknown joint '" + joint + "' in robot '" + impl_->desc.name + "'");
  return j->getChildBodyNode()->getWorldTransform() * j->getTransformFromChildBodyNode();
}

Eigen::MatrixXd WholeBodyModel::frameJacobian(int frame) const {
  Eigen::MatrixXd J;
  frameJacobian(frame, J);
  return J;
}

void WholeBodyModel::frameJacobian(int frame, Eigen::MatrixXd& J) const {
  const auto& f = impl_->frame(frame);
  impl_->pointJacobian(f.body, f.X_BF.translation(), J);
}

Vector6d WholeBodyModel::frameVelocity(int frame) const {
  const auto& f = impl_->frame(frame);
  Vector6d v;
  v.head<3>() = f.body->getAngularVelocity(Frame::World(), Frame::World());
  v.tail<3>() = f.body->getLinearVelocity(f.X_BF.translation(), Frame::World(), Frame::World());
  return v;
}

Vector6d WholeBodyModel::frameAcceleration(int frame) const {
  const auto& f = impl_->frame(frame);
  Vector6d a;
  a.head<3>() = f.body->getAngularAcceleration(Frame::World(), Frame::World());
  a.tail<3>() = f.body->getLinearAcceleration(f.X_BF.translation(), Frame::World(), Frame::World());
  return a;
}

Eigen::Vector3d WholeBodyModel::com() const { return impl_->skel->getCOM(); }
Eigen::Vector3d WholeBodyModel::comVelocity() const { return impl_->skel->getCOMLinearVelocity(); }
Eigen::Vector3d WholeBodyModel::comAcceleration() const {
  return impl_->skel->getCOMLinearAcceleration();
}
Eigen::MatrixXd WholeBodyModel::comJacobian() const {
  return impl_->colsFromDart(impl_->skel->getCOMLinearJacobian());
}

double WholeBodyModel::massBelow(int frame, Eigen::Vector3d* com_world) const {
  const BodyNode* top = impl_->frame(frame).body;
  double m = 0.0;
  Eigen::Vector3d mc = Eigen::Vector3d::Zero();
  std::vector<const BodyNode*> stack;
  for (std::size_t c = 0; c < top->getNumChildBodyNodes(); ++c)
    stack.push_back(top->getChildBodyNode(c));
  while (!stack.empty()) {
    const BodyNode* b = stack.back();
    stack.pop_back();
    m += b->getMass();
    mc += b->getMass() * b->getCOM();
    for (std::size_t c = 0; c < b->getNumChildBodyNodes(); ++c)
      stack.push_back(b->getChildBodyNode(c));
  }
  if (com_world) *com_world = m > 0.0 ? Eigen::Vector3d(mc / m) : Eigen::Vector3d::Zero();
  return m;
}

Vector6d WholeBodyModel::centroidalMomentum() const {
  const Eigen::Vector3d c = com();
  Vector6d h = Vector6d::Zero();
  for (std::size_t i = 0; i < impl_->skel->getNumBodyNodes(); ++i) {
    BodyNode* b = impl_->skel->getBodyNode(i);
    const Eigen::Vector6d hb = b->getSpatialInertia() * b->getSpatialVelocity();  // body frame
    const Eigen::Isometry3d& X = b->getWorldTransform();
    const Eigen::Vector3d lin = X.linear() * hb.tail<3>();
    h.head<3>() += lin;
    h.tail<3>() += X.linear() * hb.head<3>() + (X.translation() - c).cross(lin);
  }
  return h;
}

Eigen::MatrixXd WholeBodyModel::massMatrix(bool with_rotor) const {
  const Eigen::MatrixXd& Md = impl_->skel->getMassMatrix();
  const int n = impl_->n;
  Eigen::MatrixXd M(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) M(i, j) = Md(impl_->perm[i], impl_->perm[j]);
  if (with_rotor) M.diagonal() += impl_->reflected;
  return M;
}

Eigen::VectorXd WholeBodyModel::nonlinearEffects() const {
  Eigen::VectorXd h = impl_->fromDart(impl_->skel->getCoriolisAndGravityForces());
  const Eigen::VectorXd q = positions();
  const Eigen::VectorXd v = velocities();
  h += impl_->stiffness.cwiseProduct(q) + impl_->damping.cwiseProduct(v);
  return h;
}

Eigen::VectorXd WholeBodyModel::inverseDynamics() const {
  Eigen::VectorXd tau;
  inverseDynamics(tau);
  return tau;
}

void WholeBodyModel::inverseDynamics(Eigen::VectorXd& tau) const {
  // Springs and dampers are added here, not by DART: DART's inverse dynamics evaluates the spring
  // at q + dt qdot (its implicit-integration form), which is not the model's k q.
  impl_->skel->computeInverseDynamics(false, false, false);
  tau.resize(impl_->n);
  for (int i = 0; i < impl_->n; ++i) {
    const dart::dynamics::DegreeOfFreedom* dof =
        impl_->skel->getDof(static_cast<std::size_t>(impl_->perm[i]));
    tau(i) = dof->getForce() +
             (impl_->reflected(i) * dof->getAcceleration() +
              impl_->stiffness(i) * dof->getPosition() + impl_->damping(i) * dof->getVelocity());
  }
}

Eigen::VectorXd WholeBodyModel::torquesInContact(const Eigen::VectorXd& tau_id,
                                                 const std::vector<FrameWrench>& contacts) const {
  impl_->checkSize(tau_id, "torques");
  Eigen::VectorXd tau = tau_id;
  for (const auto& c : contacts) {
    assert(c.wrench.axes == core::Axes::kWorld && "torquesInContact: world-axes wrenches");
    const core::Vector6d w = c.wrench.about(framePose(c.frame).translation()).spatial();
    tau.noalias() -= frameJacobian(c.frame).transpose() * w;
  }
  return tau;
}

core::Wrench WholeBodyModel::contactWrenchFromBase(const Eigen::VectorXd& tau) const {
  if (impl_->nb != 6) throw InputError("contactWrenchFromBase needs a floating-base robot");
  BodyNode* base = impl_->skel->getRootBodyNode();
  const Eigen::Vector3d origin_in_base =
      base->getWorldTransform().inverse() * Eigen::Vector3d::Zero();
  // The base's world Jacobian at the world origin: its six columns are the base coordinates.
  Eigen::MatrixXd& J = impl_->jacobian;
  impl_->pointJacobian(base, origin_in_base, J);
  const Eigen::Matrix<double, 6, 6> Jb = J.leftCols<6>();
  return core::Wrench::fromSpatial(Jb.transpose().partialPivLu().solve(tau.head<6>()),
                                   core::Axes::kWorld);
}

Eigen::Vector2d WholeBodyModel::zmpFromMotion(double ground_z) const {
  return core::zmpFromWrench(contactWrenchFromBase(inverseDynamics()), ground_z);
}

Eigen::Vector2d WholeBodyModel::tableCartZmp(double ground_z) const {
  return core::tableCartZmp(com(), comAcceleration(), impl_->desc.gravity, ground_z);
}

Eigen::MatrixXd WholeBodyModel::contactJacobian(
    const std::vector<ContactConstraint>& contacts) const {
  int rows = 0;
  for (const auto& c : contacts) rows += c.type == ContactConstraint::Type::Flat ? 6 : 3;
  Eigen::MatrixXd J(rows, impl_->n);
  int r = 0;
  for (const auto& c : contacts) {
    const Eigen::MatrixXd Jf = frameJacobian(c.frame);
    if (c.type == ContactConstraint::Type::Flat) {
      J.middleRows(r, 6) = Jf;
      r += 6;
    } else {
      J.middleRows(r, 3) = Jf.bottomRows(3);
      r += 3;
    }
  }
  return J;
}

Eigen::VectorXd WholeBodyModel::impactMap(const Eigen::VectorXd& v_minus,
                                          const std::vector<ContactConstraint>& contacts,
                                          Eigen::VectorXd* impulse) const {
  impl_->checkSize(v_minus, "velocities");
  const Eigen::MatrixXd M = massMatrix(true);
  const Eigen::MatrixXd J = contactJacobian(contacts);
  const Eigen::LDLT<Eigen::MatrixXd> Mf(M);
  const Eigen::MatrixXd MinvJt = Mf.solve(J.transpose());
  const Eigen::MatrixXd A = J * MinvJt;
  // A is singular for redundant contact sets: the minimum-norm impulse is the physical one.
  const Eigen::VectorXd L = A.completeOrthogonalDecomposition().solve(-J * v_minus);
  if (impulse) *impulse = L;
  return v_minus + MinvJt * L;
}

}  // namespace overstep::robots
