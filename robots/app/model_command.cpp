// `overstep model`: loads the robot model and prints its summary.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "overstep/cli/command.hpp"
#include "overstep/core/error.hpp"
#include "overstep/robots/whole_body_model.hpp"

namespace overstep {
namespace {

struct ModelOptions {
  std::string robot;
  bool json = false;
};

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

int runModel(const ModelOptions& o) {
  robots::WholeBodyModel model = robots::WholeBodyModel::fromFile(o.robot);
  const auto& d = model.description();
  const Eigen::VectorXd q = model.halfSitting();
  model.setPositions(q);
  model.setVelocities(Eigen::VectorXd::Zero(model.dofs()));
  const Eigen::Vector3d com = model.com();
  nlohmann::json feet = nlohmann::json::object();
  for (const auto& f : d.feet) {
    const Eigen::Isometry3d X = model.framePose(model.frameIndex(f.sole_frame));
    const Eigen::Vector2d c = f.centre();
    feet[f.side] = vec(X * Eigen::Vector3d(c.x(), c.y(), 0.0));
  }
  constexpr double kDeg = 180.0 / M_PI;
  if (o.json) {
    nlohmann::json j;
    j["robot"] = d.name;
    j["robot_file"] = d.yaml_path;
    j["hash"] = d.hashHex();
    j["dofs"] = model.dofs();
    j["base"] = model.baseDofs();
    j["actuated"] = model.actuatedCount();
    j["elastic"] = model.elasticCount();
    j["mass"] = model.totalMass();
    j["com"] = vec(com);
    j["feet"] = feet;
    nlohmann::json joints = nlohmann::json::array();
    for (std::size_t i = 0; i < d.actuated.size(); ++i) {
      const auto& a = d.actuated[i];
      joints.push_back({{"name", a.name},
                        {"coordinate", model.actuatedCoordinate(static_cast<int>(i))},
                        {"lower", a.lower},
                        {"upper", a.upper},
                        {"safe_lower", a.safeLower()},
                        {"safe_upper", a.safeUpper()},
                        {"velocity", a.velocity},
                        {"torque", a.torque},
                        {"gear_ratio", a.gear_ratio},
                        {"reflected_inertia", a.reflectedInertia()},
                        {"half_sitting", d.half_sitting(static_cast<Eigen::Index>(i))}});
    }
    j["joints"] = joints;
    nlohmann::json el = nlohmann::json::array();
    for (std::size_t i = 0; i < d.elastic.size(); ++i) {
      el.push_back({{"name", d.elastic[i].name},
                    {"coordinate", model.elasticCoordinate(static_cast<int>(i))},
                    {"stiffness", d.elastic[i].stiffness},
                    {"damping", d.elastic[i].damping}});
    }
    j["elastic_joints"] = el;
    std::cout << j.dump(2) << "\n";
    return kExitOk;
  }
  std::printf("robot       %s (%s, hash %s)\n", d.name.c_str(), d.yaml_path.c_str(),
              d.hashHex().c_str());
  std::printf("coordinates %d total = %d floating base + %d actuated + %d elastic\n", model.dofs(),
              model.baseDofs(), model.actuatedCount(), model.elasticCount());
  std::printf("mass        %.3f kg\n", model.totalMass());
  std::printf("CoM         [%.4f, %.4f, %.4f] m (half-sitting, soles on z = 0)\n", com.x(), com.y(),
              com.z());
  for (const auto& [side, p] : feet.items()) {
    std::printf("%-5s sole  [%.4f, %.4f, %.4f] m (sole-rectangle centre)\n", side.c_str(),
                p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  }
  std::printf("\n %-3s %-14s %9s %9s %9s %7s %7s %5s %8s\n", "#", "joint", "min deg", "max deg",
              "half deg", "rad/s", "N m", "gear", "N^2Im");
  for (std::size_t i = 0; i < d.actuated.size(); ++i) {
    const auto& a = d.actuated[i];
    std::printf(" %-3d %-14s %9.1f %9.1f %9.1f %7.2f %7.1f %5.0f %8.4f\n",
                model.actuatedCoordinate(static_cast<int>(i)), a.name.c_str(), a.lower * kDeg,
                a.upper * kDeg, d.half_sitting(static_cast<Eigen::Index>(i)) * kDeg, a.velocity,
                a.torque, a.gear_ratio, a.reflectedInertia());
  }
  std::printf("\n %-3s %-18s %12s %14s\n", "#", "elastic joint", "k N m/rad", "d N m s/rad");
  for (std::size_t i = 0; i < d.elastic.size(); ++i) {
    std::printf(" %-3d %-18s %12.1f %14.1f\n", model.elasticCoordinate(static_cast<int>(i)),
                d.elastic[i].name.c_str(), d.elastic[i].stiffness, d.elastic[i].damping);
  }
  return kExitOk;
}

}  // namespace

void registerModelCommand(CLI::App& app, cli::Registry& registry) {
  auto opts = std::make_shared<ModelOptions>();
  opts->robot = cli::defaultRobotPath();
  CLI::App* sub = app.add_subcommand("model", "Load the robot model and print its summary");
  sub->add_option("--robot", opts->robot, "Robot YAML (URDF path inside it)")
      ->capture_default_str();
  sub->add_flag("--json", opts->json, "Print one JSON object instead of tables");
  sub->footer(
      "Examples:\n"
      "  overstep model\n"
      "  overstep model --json | jq .com\n"
      "  overstep model --robot robots/hrp2/hrp2.yaml");
  registry.add(sub, [opts] { return runModel(*opts); });
}

}  // namespace overstep
