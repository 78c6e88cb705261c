#include "libnetsim/identification/fit_parameters.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

// Units by the path's last key (docs/scenarios.md).
std::string UnitsOf(const std::string& path) {
  static const std::map<std::string, std::string> units = {{"diameter", "m"},
                                                           {"linear_density", "kg/m"},
                                                           {"stretch_stiffness", "N"},
                                                           {"stretch_damping", "N s"},
                                                           {"bend_stiffness", "N m^2"},
                                                           {"bend_damping", "N m^2 s"},
                                                           {"twist_stiffness", "N m^2"},
                                                           {"twist_damping", "N m^2 s"},
                                                           {"drag_coefficient", "1"},
                                                           {"air_density", "kg/m^3"},
                                                           {"velocity", "m/s"},
                                                           {"corner_velocities", "m/s"},
                                                           {"corner_mass", "kg"},
                                                           {"knot_mass", "kg"},
                                                           {"mesh", "m"},
                                                           {"center", "m"},
                                                           {"friction", "1"}};
  std::istringstream parts(path);
  std::string part;
  std::string found;
  while (std::getline(parts, part, '.'))
    if (units.count(part)) found = units.at(part);
  return found;
}

bool IsScale(const std::string& path) {
  return path.rfind("materials.", 0) == 0 || path.rfind("drag.", 0) == 0;
}

bool IsVelocity(const std::string& path) {
  return path.find(".velocity") != std::string::npos ||
         path.find(".corner_velocities") != std::string::npos;
}

// One parameter per number under `node` (a scalar or lists of numbers), named by its path.
void AddScalars(const YAML::Node& node, const std::string& path, const std::string& scenario_path,
                std::vector<FitParameter>* out) {
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i)
      AddScalars(node[i], path + "." + std::to_string(i), scenario_path, out);
    return;
  }
  const std::string where = scenario_path + ": --free " + path + ": ";
  if (!node.IsScalar())
    throw InputError(where + "is a section, not a number (free one of its values)");
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(where + "'" + node.Scalar() + "' is not a number");
  }
  FitParameter p;
  p.name = path;
  p.path = path;
  p.start = value;
  p.units = UnitsOf(path);
  p.log = IsScale(path);
  if (p.log && !(value > 0))
    throw InputError(where + "starts at " + node.Scalar() +
                     ": a material or drag value is fitted on a log scale and must start "
                     "positive (give a start with --set " +
                     path + "=...)");
  p.spread = p.log ? 0.5 : IsVelocity(path) ? 0.1 : std::max(0.5 * std::abs(value), 1e-12);
  out->push_back(p);
}

}  // namespace

double FitParameter::Value(double x) const { return log ? std::exp(x) : x; }
double FitParameter::Coordinate(double value) const { return log ? std::log(value) : value; }

namespace {

// The parameters one item of --free names in the scenario in `scenario_path`.
std::vector<FitParameter> ItemParameters(const std::string& item, const std::string& scenario_path,
                                         const std::vector<ScenarioOverride>& set,
                                         double time_offset_start) {
  std::vector<FitParameter> parameters;
  // Aggregates, not member assignments: GCC 12 warns of a false -Wrestrict on `p.units = "s"`.
  if (item == "time_offset") {
    parameters.push_back(
        {item, FitParameter::Kind::kTimeOffset, 0, false, time_offset_start, 0.01, "s", item});
  } else if (item == "frame") {
    static const char* kAxes[6] = {"wx", "wy", "wz", "tx", "ty", "tz"};
    for (int a = 0; a < 6; ++a) {
      const std::string name = std::string("frame.") + kAxes[a];
      parameters.push_back(
          {name, FitParameter::Kind::kFrame, a, false, 0.0, 0.01, a < 3 ? "rad" : "m", name});
    }
  } else {
    AddScalars(ScenarioValue(scenario_path, set, item), item, scenario_path, &parameters);
  }
  return parameters;
}

}  // namespace

std::vector<FitParameter> ParseFreeParameters(const std::string& free_list,
                                              const std::string& scenario_path,
                                              const std::vector<ScenarioOverride>& set,
                                              double time_offset_start) {
  return ParseFreeParameters(free_list, std::vector<std::string>{scenario_path}, set,
                             time_offset_start);
}

std::vector<FitParameter> ParseFreeParameters(const std::string& free_list,
                                              const std::vector<std::string>& scenario_paths,
                                              const std::vector<ScenarioOverride>& set,
                                              double time_offset_start) {
  std::vector<FitParameter> parameters;
  const int shots = static_cast<int>(scenario_paths.size());
  // getline yields no item after a trailing comma: that empty name is refused as the others are.
  const size_t last = free_list.find_last_not_of(" \t");
  if (last != std::string::npos && free_list[last] == ',')
    throw InputError("--free '" + free_list + "': an empty name in the list (a trailing comma)");
  std::istringstream items(free_list);
  std::string item;
  while (std::getline(items, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (item.empty()) throw InputError("--free '" + free_list + "': an empty name in the list");
    if (IsScale(item)) {  // the thread and the air: one parameter for every shot
      for (FitParameter& p : ItemParameters(item, scenario_paths[0], set, time_offset_start))
        parameters.push_back(p);
      continue;
    }
    for (int shot = 0; shot < shots; ++shot)
      for (FitParameter& p : ItemParameters(item, scenario_paths[shot], set, time_offset_start)) {
        p.shot = shot;
        if (shots > 1) p.name = std::to_string(shot + 1) + ":" + p.name;
        parameters.push_back(p);
      }
  }
  if (parameters.empty()) throw InputError("--free: no parameter named");
  std::set<std::string> seen;
  for (const FitParameter& p : parameters)
    if (!seen.insert(p.name).second)
      throw InputError("--free '" + free_list + "': " + p.name + " is named twice");
  return parameters;
}

std::vector<ScenarioOverride> ScenarioOverrides(const std::vector<FitParameter>& parameters,
                                                const std::vector<double>& x, int shot) {
  std::vector<ScenarioOverride> overrides;
  for (size_t i = 0; i < parameters.size(); ++i) {
    if (parameters[i].kind != FitParameter::Kind::kScenario || !Moves(parameters[i], shot))
      continue;
    char value[32];
    std::snprintf(value, sizeof value, "%.17g", parameters[i].Value(x[i]));
    overrides.push_back({parameters[i].path, value});
  }
  return overrides;
}

}  // namespace netlab::netsim
