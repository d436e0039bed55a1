#pragma once
/// \file
/// Error tiers and process exit codes shared by every overstep module.
///
/// - Bad user input (files, flags, messages) throws InputError; front ends exit with kExitBadInput.
/// - An infeasible request (no valid plan, impossible obstacle) throws InfeasibleError ->
/// kExitInfeasible.
/// - The fixed-rate path never throws: it returns a status and falls back to a safe command.

#include <stdexcept>
#include <string>

namespace overstep {

/// Process exit codes of every `overstep` subcommand.
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,    ///< a bug or an unexpected failure
  kExitBadInput = 2,    ///< malformed/invalid input: files, flags, values
  kExitInfeasible = 3,  ///< the request was understood but cannot be satisfied
  kExitHeld = 4,        ///< a run ended holding after a fault (overstep replay)
  kExitInterrupted = 130,
};

/// Invalid user input. The message is one line: "where: expected X, got Y[, hint: ...]".
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

/// A well-formed request that cannot be satisfied (e.g. no valid plan exists).
class InfeasibleError : public std::runtime_error {
 public:
  explicit InfeasibleError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace overstep
