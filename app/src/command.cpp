#include "overstep/cli/command.hpp"

#include <csignal>
#include <exception>
#include <filesystem>
#include <iostream>

#include "overstep/core/error.hpp"

namespace overstep::cli {

void Registry::add(CLI::App* sub, Runner run) { commands_.emplace_back(sub, std::move(run)); }

int Registry::runSelected() const {
  for (const auto& [sub, run] : commands_) {
    if (sub->parsed()) return guarded(sub->get_name(), run);
  }
  printError("", "no subcommand given (see overstep --help)");
  return kExitBadInput;
}

void printError(const std::string& command, const std::string& message) {
  std::string line = message;
  for (char& c : line)
    if (c == '\n') c = ' ';
  std::cerr << "overstep" << (command.empty() ? "" : " " + command) << ": error: " << line << "\n";
}

int guarded(const std::string& command, const Runner& fn) {
  try {
    return fn();
  } catch (const InputError& e) {
    printError(command, e.what());
    return kExitBadInput;
  } catch (const InfeasibleError& e) {
    printError(command, e.what());
    return kExitInfeasible;
  } catch (const std::exception& e) {
    printError(command, std::string("internal error: ") + e.what());
    return kExitInternal;
  }
}

namespace {
extern "C" void onStopSignal(int) { StopSignals::flag().store(true); }
}  // namespace

std::atomic<bool>& StopSignals::flag() {
  static std::atomic<bool> stop{false};
  return stop;
}

StopSignals::StopSignals(bool also_sigterm) : sigterm_(also_sigterm) {
  flag().store(false);
  prev_int_ = std::signal(SIGINT, onStopSignal);
  if (sigterm_) prev_term_ = std::signal(SIGTERM, onStopSignal);
}

StopSignals::~StopSignals() {
  std::signal(SIGINT, prev_int_);
  if (sigterm_) std::signal(SIGTERM, prev_term_);
}

std::string defaultRobotPath() {
  const std::string local = "robots/hrp2/hrp2.yaml";
  std::error_code ec;
  if (std::filesystem::is_regular_file(local, ec)) return local;
  return std::string(OVERSTEP_DATA_DIR) + "/" + local;
}

}  // namespace overstep::cli
