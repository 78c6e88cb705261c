#include "libnetsim/sweep/sweep_grid.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>
#include <sstream>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

constexpr int kMaxCount = 10000;
constexpr long kMaxRuns = 100000;

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

// A whole string as a finite number; false otherwise.
bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(*value);
}

}  // namespace

std::vector<double> SweepParameter::Values() const {
  std::vector<double> values(count);
  for (int i = 0; i < count; ++i) {
    const double v = count == 1 ? from : from + i * (to - from) / (count - 1);
    // To 12 significant digits: the values as a person types them (2e-4, not
    // 0.00019999999999999998), so that `simulate --set` of the value runs the same bits.
    char text[32];
    std::snprintf(text, sizeof(text), "%.12g", v);
    values[i] = std::strtod(text, nullptr);
  }
  values.front() = from;  // the ends exactly as named
  values.back() = count == 1 ? from : to;
  return values;
}

std::string SweepParameter::Text() const {
  if (!given.empty()) return given;
  return path + "=" + ValueText(from) + ":" + ValueText(to) + ":" + std::to_string(count);
}

std::string ValueText(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

SweepParameter ParseVary(const std::string& arg) {
  const std::string where = "--vary '" + arg + "': ";
  const size_t eq = arg.find('=');
  SweepParameter p;
  if (eq == std::string::npos || Trim(arg.substr(0, eq)).empty())
    throw InputError(where +
                     "expected PATH=a:b:n, e.g. "
                     "materials.nylon_1mm.bend_stiffness=1e-4:4e-4:4");
  p.path = Trim(arg.substr(0, eq));
  std::vector<std::string> parts;
  std::stringstream in(arg.substr(eq + 1));
  for (std::string part; std::getline(in, part, ':');) parts.push_back(Trim(part));
  if (!arg.empty() && arg.back() == ':') parts.emplace_back();
  if (parts.size() != 3)
    throw InputError(where + "expected a:b:n after '=' (from a to b in n values), got " +
                     std::to_string(parts.size()) + (parts.size() == 1 ? " field" : " fields"));
  if (!ParseNumber(parts[0], &p.from))
    throw InputError(where + "a = '" + parts[0] + "' is not a number");
  if (!ParseNumber(parts[1], &p.to))
    throw InputError(where + "b = '" + parts[1] + "' is not a number");
  char* end = nullptr;
  const long n = std::strtol(parts[2].c_str(), &end, 10);
  if (parts[2].empty() || *end != '\0')
    throw InputError(where + "n = '" + parts[2] + "' is not a whole number");
  if (n < 1) throw InputError(where + "n = " + parts[2] + ": need at least 1 value");
  if (n > kMaxCount)
    throw InputError(where + "n = " + parts[2] + ": at most " + std::to_string(kMaxCount));
  if (n == 1 && p.from != p.to)
    throw InputError(where + "n = 1 takes the one value a; give a:a:1 (or n >= 2 to vary it)");
  p.count = static_cast<int>(n);
  p.given = Trim(arg);
  return p;
}

void CheckSweepParameters(const std::string& scenario_path,
                          const std::vector<ScenarioOverride>& fixed,
                          const std::vector<SweepParameter>& parameters) {
  YAML::Node tree = LoadYamlString(ReadScenarioText(scenario_path), scenario_path);
  if (!tree.IsMap()) throw InputError(scenario_path + ": the scenario is not a YAML mapping");
  for (const ScenarioOverride& o : fixed) ApplyOverride(o, scenario_path, tree);
  std::set<std::string> seen;
  for (const SweepParameter& p : parameters) {
    if (!seen.insert(p.path).second)
      throw InputError("--vary " + p.Text() + ": " + p.path + " is varied twice");
    const ScenarioOverride o{p.path, ValueText(p.from)};
    try {
      ApplyOverride(o, scenario_path, tree);
    } catch (const InputError& e) {
      // Name the --vary the user wrote rather than the --set it became.
      std::string message = e.what();
      const std::string set = scenario_path + ": --set " + o.Text() + ": ";
      if (message.rfind(set, 0) == 0) message = message.substr(set.size());
      throw InputError(scenario_path + ": --vary " + p.Text() + ": " + message);
    }
  }
  // A key the scenario does not know (nets.0.knotz) passes the override, whose last key may be
  // one the file leaves at its default, and then failed every run alike, the sweep exiting 0. It
  // is refused here; a value out of range stays a failure of the runs it falls in.
  try {
    const std::string text = ReadScenarioText(scenario_path);
    ParseScenarioTree(tree, text, scenario_path,
                      std::filesystem::path(scenario_path).parent_path().string());
  } catch (const InputError& e) {
    if (std::string(e.what()).find("unknown key") != std::string::npos) throw;
  }
}

std::vector<SweepPoint> SweepGrid(const std::vector<ScenarioOverride>& fixed,
                                  const std::vector<SweepParameter>& parameters) {
  long total = 1;
  for (const SweepParameter& p : parameters) {
    total *= p.count;
    if (total > kMaxRuns)
      throw InputError("--vary: the grid has more than " + std::to_string(kMaxRuns) + " runs");
  }
  std::vector<std::vector<double>> values;
  for (const SweepParameter& p : parameters) values.push_back(p.Values());
  std::vector<SweepPoint> grid(total);
  for (long i = 0; i < total; ++i) {
    SweepPoint& point = grid[i];
    point.index = static_cast<int>(i);
    point.overrides = fixed;
    point.value_index.resize(parameters.size());
    point.values.resize(parameters.size());
    // Row-major: the last parameter varies fastest.
    long rest = i;
    for (size_t q = parameters.size(); q-- > 0;) {
      point.value_index[q] = static_cast<int>(rest % parameters[q].count);
      rest /= parameters[q].count;
    }
    for (size_t q = 0; q < parameters.size(); ++q) {
      point.values[q] = values[q][point.value_index[q]];
      point.overrides.push_back({parameters[q].path, ValueText(point.values[q])});
    }
  }
  return grid;
}

std::vector<SweepPoint> SweepEnsemble(const std::vector<ScenarioOverride>& fixed,
                                      const std::vector<SweepParameter>& parameters, int runs) {
  if (runs < 2 || runs > kMaxRuns)
    throw InputError("--ensemble: " + std::to_string(runs) + " runs; a spread needs 2 to " +
                     std::to_string(kMaxRuns));
  std::vector<SweepPoint> points(runs);
  for (int i = 0; i < runs; ++i) {
    points[i].index = i;
    points[i].overrides = fixed;
    points[i].value_index.resize(parameters.size());
    points[i].values.resize(parameters.size());
  }
  for (size_t q = 0; q < parameters.size(); ++q) {
    const std::vector<double> values = parameters[q].Values();
    std::vector<int> order(runs);
    for (int i = 0; i < runs; ++i) order[i] = i % parameters[q].count;
    std::mt19937 rng(static_cast<unsigned>(1000 + q));
    std::shuffle(order.begin(), order.end(), rng);
    for (int i = 0; i < runs; ++i) {
      points[i].value_index[q] = order[i];
      points[i].values[q] = values[order[i]];
    }
  }
  for (SweepPoint& point : points)
    for (size_t q = 0; q < parameters.size(); ++q)
      point.overrides.push_back({parameters[q].path, ValueText(point.values[q])});
  return points;
}

}  // namespace netlab::netsim
