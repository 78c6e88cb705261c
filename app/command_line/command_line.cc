#include "app/command_line/command_line.h"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <new>

#include "common/errors.h"
#include "common/memory.h"
#include "common/yaml_util.h"

namespace netlab::app {

CommandLine::CommandLine(const std::vector<std::string>& args,
                         const std::vector<std::string>& flags,
                         const std::vector<std::string>& options) {
  auto is = [](const std::vector<std::string>& list, const std::string& name) {
    return std::find(list.begin(), list.end(), name) != list.end();
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg.rfind("--", 0) != 0 || arg == "--") {
      positional_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2), value;
    bool has_value = false;
    if (const size_t eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    if (is(flags, name)) {
      if (has_value) throw UsageError("--" + name + " takes no value");
      flags_[name] = true;
    } else if (is(options, name)) {
      if (!has_value) {
        if (i + 1 >= args.size()) throw UsageError("--" + name + " needs a value");
        value = args[++i];
      }
      // An empty value (--out '', a variable that was never set) would run the whole job and
      // then fail to write, or write nothing: refused before any work.
      if (value.empty()) throw UsageError("--" + name + " needs a non-empty value");
      values_[name].push_back(value);
    } else {
      throw UsageError("unknown option --" + YamlMap::Shown(name));
    }
  }
}

bool CommandLine::Flag(const std::string& name) const { return flags_.count(name) > 0; }

std::optional<std::string> CommandLine::Option(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end() || it->second.empty()) return std::nullopt;
  return it->second.back();
}

std::vector<std::string> CommandLine::Options(const std::string& name) const {
  const auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

std::string CommandLine::Required(const std::string& name) const {
  const auto value = Option(name);
  if (!value) throw UsageError("--" + name + " is required");
  return *value;
}

int CommandLine::IntOption(const std::string& name, int fallback, int min, int max) const {
  const auto value = Option(name);
  if (!value) return fallback;
  size_t used = 0;
  long parsed = 0;
  try {
    parsed = std::stol(*value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value->size() || parsed < min || parsed > max)
    throw UsageError("--" + name + " expects an integer in " + std::to_string(min) + ".." +
                     std::to_string(max) + ", got '" + YamlMap::Shown(*value) + "'");
  return static_cast<int>(parsed);
}

double CommandLine::DoubleOption(const std::string& name, double fallback, double min,
                                 double max) const {
  const auto value = Option(name);
  if (!value) return fallback;
  size_t used = 0;
  double parsed = 0.0;
  try {
    parsed = std::stod(*value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value->size() || !(parsed >= min && parsed <= max)) {
    char range[96];
    std::snprintf(range, sizeof(range), "[%g, %g]", min, max);
    throw UsageError("--" + name + " expects a number in " + range + ", got '" +
                     YamlMap::Shown(*value) + "'");
  }
  return parsed;
}

void CommandLine::Knots(const std::string& name, int* rows, int* cols) const {
  const std::string text = Required(name);
  const size_t x = text.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument("no x");
    size_t used_r = 0, used_c = 0;
    *rows = std::stoi(text.substr(0, x), &used_r);
    *cols = std::stoi(text.substr(x + 1), &used_c);
    if (used_r != x || used_c != text.size() - x - 1) throw std::invalid_argument("junk");
  } catch (const std::exception&) {
    throw UsageError("--" + name + " expects ROWSxCOLS, e.g. 11x11, got '" + YamlMap::Shown(text) +
                     "'");
  }
  if (*rows < 2 || *cols < 2 || *rows > 1000 || *cols > 1000)
    throw UsageError("--" + name + " " + text + ": need 2..1000 knots per side");
}

std::vector<netsim::ScenarioOverride> CommandLine::Overrides(const std::string& name) const {
  std::vector<netsim::ScenarioOverride> overrides;
  for (const std::string& text : Options(name)) {
    try {
      overrides.push_back(netsim::ParseOverride(text));
    } catch (const InputError& e) {
      throw UsageError(e.what());
    }
  }
  return overrides;
}

bool CommandLine::FrameRange(const std::string& name, int* first, int* last) const {
  const auto value = Option(name);
  if (!value) return false;
  const std::string& text = *value;
  const size_t colon = text.find(':');
  int a = 0, b = 0;
  try {
    if (colon == std::string::npos) throw std::invalid_argument("no colon");
    size_t used_a = 0, used_b = 0;
    a = std::stoi(text.substr(0, colon), &used_a);
    b = std::stoi(text.substr(colon + 1), &used_b);
    if (used_a != colon || used_b != text.size() - colon - 1) throw std::invalid_argument("junk");
  } catch (const std::exception&) {
    throw UsageError("--" + name + " expects A:B (first and last frame), got '" +
                     YamlMap::Shown(text) + "'");
  }
  if (a < 0 || b < a) throw UsageError("--" + name + " " + text + ": need 0 <= A <= B");
  *first = a;
  *last = b;
  return true;
}

namespace {

std::atomic<bool>* interrupt_flag = nullptr;

extern "C" void OnInterrupt(int) {
  if (interrupt_flag != nullptr) interrupt_flag->store(true, std::memory_order_relaxed);
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl+C ends the process at once
}

}  // namespace

const CancelToken& InterruptToken() {
  static const CancelToken token = [] {
    CancelToken t;
    interrupt_flag = t.flag();
    std::signal(SIGINT, OnInterrupt);
    return t;
  }();
  return token;
}

int RunGuarded(const char* name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const Cancelled&) {
    std::fprintf(stderr, "netlab %s: cancelled\n", name);
    return kCancelledStatus;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "netlab %s: %s\n(see netlab %s --help)\n", name, e.what(), name);
    return 2;
  } catch (const std::bad_alloc&) {
    // The commands size their jobs before allocating (common/memory.h); this is the last line.
    const std::optional<double> available = AvailableMemoryBytes();
    std::fprintf(stderr,
                 "netlab %s: error: out of memory: the job is larger than this machine can hold "
                 "(%s available); try a smaller input or option range\n",
                 name, available ? FormatBytes(*available).c_str() : "unknown");
    return 1;
  } catch (const std::logic_error& e) {
    // std::invalid_argument and std::out_of_range are a library's checks of the values it is
    // given (and std::stoi's); the values are the user's, so they read as bad input.
    if (dynamic_cast<const std::invalid_argument*>(&e) == nullptr &&
        dynamic_cast<const std::out_of_range*>(&e) == nullptr) {
      std::fprintf(stderr,
                   "netlab %s: internal error: %s\n(a broken invariant of netlab's, not a fault "
                   "in the input: please report it with the command line)\n",
                   name, e.what());
      return kInternalErrorStatus;
    }
    std::fprintf(stderr, "netlab %s: error: %s\n", name, e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "netlab %s: error: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace netlab::app
