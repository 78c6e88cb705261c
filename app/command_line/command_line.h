#pragma once
// Argument parsing shared by netlab's subcommands: positional arguments, `--flag`, `--key VALUE`
// (or `--key=VALUE`), and repeated keys. Unknown options are an error naming them.

#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/progress.h"
#include "libnetsim/scenario/scenario_override.h"

namespace netlab::app {

// A usage error: the command prints it with its --help hint and exits with status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CommandLine {
 public:
  // `flags` take no value; `options` take one value each (and may repeat).
  CommandLine(const std::vector<std::string>& args, const std::vector<std::string>& flags,
              const std::vector<std::string>& options);

  bool Flag(const std::string& name) const;
  std::optional<std::string> Option(const std::string& name) const;  // last given value
  std::vector<std::string> Options(const std::string& name) const;   // every value, in order
  std::string Required(const std::string& name) const;
  // An integer option in [min, max], or `fallback` when absent; UsageError naming it otherwise.
  int IntOption(const std::string& name, int fallback, int min, int max) const;
  // A number in [min, max], or `fallback` when absent.
  double DoubleOption(const std::string& name, double fallback, double min, double max) const;
  const std::vector<std::string>& positional() const { return positional_; }
  // A net's shape given as ROWSxCOLS (e.g. 11x11) in option `name`, required; 2..1000 knots a side.
  void Knots(const std::string& name, int* rows, int* cols) const;
  // A frame range A:B (inclusive, 0 <= A <= B) in option `name`: false (first, last untouched)
  // when the option is absent, UsageError naming it when malformed.
  bool FrameRange(const std::string& name, int* first, int* last) const;
  // Every PATH=VALUE of option `name` (`--set`), in order; UsageError for a malformed one.
  std::vector<netsim::ScenarioOverride> Overrides(const std::string& name) const;

 private:
  std::map<std::string, std::vector<std::string>> values_;
  std::map<std::string, bool> flags_;
  std::vector<std::string> positional_;
};

// The exit status of a command stopped by a broken invariant of netlab itself (a bug).
inline constexpr int kInternalErrorStatus = 3;
// The exit status of a command stopped by Ctrl+C (128 + SIGINT, as a shell reports it).
inline constexpr int kCancelledStatus = 130;

// The token Ctrl+C sets: the first call installs a SIGINT handler that cancels it, so a command's
// long call (given a reporter with this token) stops within about a second and throws Cancelled.
// A second Ctrl+C while the call winds down kills the process as SIGINT does by default.
const CancelToken& InterruptToken();

// Runs a subcommand's body and turns what it throws into the exit status and message every
// command has (docs/architecture.md, "Errors"):
//   UsageError                      "netlab NAME: <what>" and "(see netlab NAME --help)", status 2
//   InputError, a failed run (any   "netlab NAME: error: <what>", status 1
//     other std::exception, out of
//     memory, std::invalid_argument
//     and std::out_of_range)
//   std::logic_error (an invariant) "netlab NAME: internal error: <what>" and a line saying it is
//                                   a bug of netlab's, status kInternalErrorStatus
//   Cancelled (Ctrl+C)              "netlab NAME: cancelled", status kCancelledStatus
// Otherwise the body's status.
int RunGuarded(const char* name, const std::function<int()>& body);

}  // namespace netlab::app
