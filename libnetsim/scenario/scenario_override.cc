#include "libnetsim/scenario/scenario_override.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::vector<std::string> Split(const std::string& path) {
  std::vector<std::string> parts;
  std::stringstream in(path);
  for (std::string part; std::getline(in, part, '.');) parts.push_back(part);
  if (!path.empty() && path.back() == '.') parts.emplace_back();
  return parts;
}

// A copy of `n` made of new nodes: no marks, so an error about the value names no line of the
// file it never came from.
YAML::Node Fresh(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Scalar: return YAML::Node(n.Scalar());
    case YAML::NodeType::Sequence: {
      YAML::Node out(YAML::NodeType::Sequence);
      for (const YAML::Node& item : n) out.push_back(Fresh(item));
      return out;
    }
    case YAML::NodeType::Map: {
      YAML::Node out(YAML::NodeType::Map);
      for (auto it = n.begin(); it != n.end(); ++it) out[it->first.Scalar()] = Fresh(it->second);
      return out;
    }
    default: return YAML::Node(YAML::NodeType::Null);
  }
}

bool IsNumber(const YAML::Node& n) {
  if (!n.IsScalar()) return false;
  double v;
  return YAML::convert<double>::decode(n, v);
}

bool IsBool(const YAML::Node& n) {
  if (!n.IsScalar()) return false;
  bool v;
  return YAML::convert<bool>::decode(n, v);
}

std::string Keys(const YAML::Node& map) {
  std::string list;
  for (auto it = map.begin(); it != map.end(); ++it)
    list += (list.empty() ? "" : ", ") + it->first.as<std::string>();
  return list;
}

std::string Kind(const YAML::Node& n) {
  if (n.IsSequence())
    return "a list of " + std::to_string(n.size()) + (n.size() == 1 ? " item" : " items");
  if (n.IsMap()) return "a section";
  if (IsNumber(n)) return "a number";
  if (IsBool(n)) return "true or false";
  return "'" + YamlMap::Shown(n.Scalar()) + "'";
}

// The entry `part` of a list, by index or by its name; `where` and `walked` (the path to the list)
// are for the error.
YAML::Node EntryOf(const YAML::Node& list, const std::string& part, const std::string& where,
                   const std::string& walked) {
  char* end = nullptr;
  const long i = std::strtol(part.c_str(), &end, 10);
  if (end != part.c_str() && *end == '\0') {
    if (i >= 0 && i < static_cast<long>(list.size())) return list[static_cast<size_t>(i)];
  } else {
    for (const YAML::Node& item : list)
      if (item.IsMap() && item["name"] && item["name"].Scalar() == part) return item;
  }
  throw InputError(where + "'" + part + "' is not an entry of " + walked + " (" +
                   std::to_string(list.size()) + (list.size() == 1 ? " entry" : " entries") +
                   ": an index 0.." + std::to_string(static_cast<long>(list.size()) - 1) +
                   ", or a name)");
}

}  // namespace

ScenarioOverride ParseOverride(const std::string& arg) {
  const size_t eq = arg.find('=');
  ScenarioOverride o;
  if (eq != std::string::npos) {
    o.path = Trim(arg.substr(0, eq));
    o.value = Trim(arg.substr(eq + 1));
  }
  if (o.path.empty() || o.value.empty())
    throw InputError("--set '" + YamlMap::Shown(arg) +
                     "': expected PATH=VALUE, e.g. integrator.type=implicit or "
                     "materials.nylon_1mm.bend_stiffness=2e-4");
  return o;
}

void ApplyOverride(const ScenarioOverride& o, const std::string& origin, YAML::Node root) {
  const std::string where = origin + ": --set " + YamlMap::Shown(o.Text()) + ": ";
  const std::vector<std::string> parts = Split(o.path);
  YAML::Node node;
  node.reset(root);
  std::string walked;  // the path so far
  const auto entry = [&](const YAML::Node& list, const std::string& part) {
    return EntryOf(list, part, where, walked);
  };
  for (size_t p = 0; p < parts.size(); ++p) {
    const std::string& part = parts[p];
    if (part.empty()) throw InputError(where + "the path has an empty key");
    const bool last = p + 1 == parts.size();
    const std::string here = walked.empty() ? part : walked + "." + part;
    YAML::Node child;
    bool found = true;
    if (node.IsMap()) {
      const YAML::Node& map = node;
      if (map[part]) {
        child.reset(map[part]);
      } else if (!last && walked.empty()) {
        // A section the file leaves at its defaults (integrator, drag): the parser checks it.
        node[part] = YAML::Node(YAML::NodeType::Map);
        child.reset(node[part]);
      } else if (!last) {
        throw InputError(where + "'" + here + "' is not in the scenario (" +
                         (walked.empty() ? std::string("it has") : walked + " has") + ": " +
                         Keys(node) + ")");
      } else {
        found = false;
      }
    } else if (node.IsSequence()) {
      child.reset(entry(node, part));
    } else {
      throw InputError(where + "'" + walked + "' is a value, not a section with keys");
    }
    if (!last) {
      node.reset(child);
      walked = here;
      continue;
    }
    YAML::Node value;
    try {
      // Checked as a file is (a key twice, a tag, an alias bomb) before Fresh expands it.
      value = Fresh(LoadYamlString(o.value, "the value"));
    } catch (const YAML::Exception& e) {
      throw InputError(where + "the value is not YAML (" + e.msg + ")");
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw InputError(where + (what.find("YAML syntax error") != std::string::npos
                                    ? "the value is not YAML (" + what + ")"
                                    : what));
    }
    if (found) {
      // The kind the scenario has there.
      if (child.IsMap())
        throw InputError(where + "'" + here + "' is a section; set one of its keys (" +
                         Keys(child) + ")");
      const bool kind_ok = child.IsSequence()
                               ? value.IsSequence() && value.size() == child.size()
                               : value.IsScalar() && (!IsNumber(child) || IsNumber(value)) &&
                                     (!IsBool(child) || IsNumber(child) || IsBool(value));
      if (!kind_ok)
        throw InputError(where + "expected " + Kind(child) + " as the scenario has there, got " +
                         Kind(value));
      if (node.IsMap()) {
        node[part] = value;
      } else {
        child = value;
      }
    } else {
      node[part] = value;  // a key the file leaves at its default: checked when parsed
    }
  }
}

Scenario LoadScenario(const std::string& path, const std::vector<ScenarioOverride>& overrides) {
  if (overrides.empty()) return LoadScenario(path);
  const std::string file_text = ReadScenarioText(path);
  const std::string base_dir = std::filesystem::path(path).parent_path().string();
  YAML::Node tree = LoadYamlString(file_text, path);
  if (!tree.IsMap()) return ParseScenarioTree(tree, file_text, path, base_dir);  // its own error
  std::string set;
  for (const ScenarioOverride& o : overrides) {
    ApplyOverride(o, path, tree);
    set += " --set " + YamlMap::Shown(o.Text());
  }
  YAML::Emitter out;
  out << tree;
  const std::string text = "# " + path + " with" + set + "\n" + out.c_str() + "\n";
  try {
    Scenario s = ParseScenarioTree(tree, text, path, base_dir);
    s.source_path = path;
    return s;
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + " (the scenario as changed by" + set + ")");
  }
}

YAML::Node ScenarioValue(const std::string& path, const std::vector<ScenarioOverride>& overrides,
                         const std::string& dotted) {
  YAML::Node tree = LoadYamlString(ReadScenarioText(path), path);
  for (const ScenarioOverride& o : overrides) ApplyOverride(o, path, tree);
  const std::string where = path + ": '" + dotted + "': ";
  YAML::Node node;
  node.reset(tree);
  std::string walked;
  for (const std::string& part : Split(dotted)) {
    YAML::Node child;
    if (node.IsMap() && node[part]) {
      child.reset(node[part]);
    } else if (node.IsSequence()) {
      child.reset(EntryOf(node, part, where, walked));
    } else {
      throw InputError(where + "the scenario does not give '" +
                       (walked.empty() ? part : walked + "." + part) + "' (" +
                       (node.IsMap() ? (walked.empty() ? std::string("it has") : walked + " has") +
                                           ": " + Keys(node) + "; "
                                     : std::string()) +
                       "a value left at its default has no start: give it with --set)");
    }
    node.reset(child);
    walked = walked.empty() ? part : walked + "." + part;
  }
  return node;
}

std::string ScenarioKeyUnits(const std::string& dotted) {
  // The last key that is not a list index: nets.0.velocity.1 -> velocity.
  std::string key;
  for (size_t start = 0; start <= dotted.size();) {
    const size_t dot = std::min(dotted.find('.', start), dotted.size());
    const std::string part = dotted.substr(start, dot - start);
    if (!part.empty() && part.find_first_not_of("0123456789") != std::string::npos) key = part;
    start = dot + 1;
  }
  static const std::map<std::string, std::string> kUnits = {
      {"duration", "s"},
      {"output_interval", "s"},
      {"dt", "s"},
      {"safety", "1"},
      {"coupling_stiffness_ratio", "1"},
      {"contact_frequency_ratio", "1"},
      {"max_speed", "m/s"},
      {"threads", "1"},
      {"gravity", "m/s^2"},
      {"air_density", "kg/m^3"},
      {"drag_coefficient", "1"},
      {"tangential_coefficient", "1"},
      {"angular_velocity", "rad/s"},
      {"diameter", "m"},
      {"linear_density", "kg/m"},
      {"stretch_stiffness", "N"},
      {"stretch_damping", "N s"},
      {"bend_stiffness", "N m^2"},
      {"twist_stiffness", "N m^2"},
      {"bend_damping", "N m^2 s"},
      {"twist_damping", "N m^2 s"},
      {"start", "m"},
      {"end", "m"},
      {"segments", "1"},
      {"velocity", "m/s"},
      {"mass", "kg"},
      {"inertia", "kg m^2"},
      {"knots", "1"},
      {"mesh", "m"},
      {"segments_per_link", "1"},
      {"center", "m"},
      {"normal", "1"},
      {"x_axis", "1"},
      {"knot_mass", "kg"},
      {"corner_mass", "kg"},
      {"corner_radius", "m"},
      {"corner_velocities", "m/s"},
      {"spread", "1"},
      {"radius", "m"},
      {"size", "m"},
      {"orientation", "1"},
      {"point", "m"},
      {"friction", "1"},
      {"stiffness", "N/m"},
      {"damping_ratio", "1"},
      {"force", "N"},
      {"node", "1"},
      {"knot", "1"},
  };
  const auto it = kUnits.find(key);
  return it == kUnits.end() ? "" : it->second;
}

}  // namespace netlab::netsim
