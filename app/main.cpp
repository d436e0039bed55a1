// overstep: the single git-style front end. Each subcommand lives in its module's app/ code.
#include <CLI/CLI.hpp>
#include <iostream>

#include "overstep/cli/command.hpp"
#include "overstep/core/error.hpp"

namespace overstep {
void registerModelCommand(CLI::App& app, cli::Registry& registry);
void registerPlanCommands(CLI::App& app, cli::Registry& registry);
void registerSimCommand(CLI::App& app, cli::Registry& registry);
void registerReplayCommand(CLI::App& app, cli::Registry& registry);
void registerDemoCommand(CLI::App& app, cli::Registry& registry);
void registerMonitorCommands(CLI::App& app, cli::Registry& registry);
void registerIdentifyCommand(CLI::App& app, cli::Registry& registry);
}  // namespace overstep

int main(int argc, char** argv) {
  CLI::App app{
      "overstep: plans, executes and checks a whole-body humanoid motion stepping over a large\n"
      "obstacle on an HRP-2-class robot with elastic ankles."};
  app.require_subcommand(1);
  app.footer(
      "Examples:\n"
      "  overstep demo                       # plan, simulate and replay the overstep\n"
      "  overstep model                      # print the HRP-2-class model summary\n"
      "  overstep model --json               # the same as one JSON object\n"
      "  overstep plan --out plan.json       # plan the 20 cm x 11 cm overstep\n"
      "  overstep check plan.json            # re-verify a plan on a 1 kHz grid\n"
      "  overstep sim --realtime             # the simulated robot on LCM\n"
      "  overstep replay plan.json --start   # stream a plan through the stabilizer\n"
      "  overstep monitor                    # terminal view of the bus (or of a log)\n"
      "  overstep report runs/<run>          # figures: plan vs measurement\n"
      "  overstep identify LOG --plan P      # what effect the model lacks\n"
      "  overstep <subcommand> --help        # options of one subcommand\n"
      "Exit codes: 0 ok, 1 internal error, 2 bad input, 3 infeasible request,\n4 a replay ended "
      "holding after a fault, 5 a component is not installed, 130 interrupted.");
  overstep::cli::Registry registry;
  overstep::registerModelCommand(app, registry);
  overstep::registerPlanCommands(app, registry);
  overstep::registerSimCommand(app, registry);
  overstep::registerReplayCommand(app, registry);
  overstep::registerDemoCommand(app, registry);
  overstep::registerMonitorCommands(app, registry);
  overstep::registerIdentifyCommand(app, registry);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    overstep::cli::printError("", e.what());
    return overstep::kExitBadInput;
  }
  return registry.runSelected();
}
