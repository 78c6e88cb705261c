#pragma once
// Scenario overrides: one value of a scenario changed from the command line, by its dotted path
// into the file (`simulate --set`, and the parameters `sweep --vary` and `fit --free` name).
//
//   integrator.type=implicit                       a key of a section
//   materials.nylon_1mm.bend_stiffness=2e-4        a key of a named entry
//   nets.0.velocity=[0.8,0,0]                      an entry of a list, by index; a YAML value
//
// The path must lead through the scenario's own sections and entries; its last key, and a
// top-level section, may be one the file leaves at its defaults (parsed as if the file had it). The
// value must be of the kind already there: a number where the file has a number, a list (of as many
// items) where it has a list, a value (not a section) where it has one. Everything else about the
// value (its range, an unknown key) is checked as the file's own values are, when the scenario is
// parsed. Errors are InputErrors naming the override and the key.

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {

struct ScenarioOverride {
  std::string path;   // dotted: section.key, list.INDEX.key
  std::string value;  // YAML text: 2e-4, implicit, [0.8, 0, 0]
  std::string Text() const { return path + "=" + value; }
};

// "PATH=VALUE" as given to --set; InputError when there is no '=' or either side is empty.
ScenarioOverride ParseOverride(const std::string& arg);

// Sets the override's value in `root` (a scenario's YAML tree), checked as above; `origin` names
// the scenario in errors.
void ApplyOverride(const ScenarioOverride& o, const std::string& origin, YAML::Node root);

// The scenario in `path` with the overrides applied in order (a later one wins), then checked as
// LoadScenario checks a file. Its `text` is the YAML that ran, headed by the overrides.
Scenario LoadScenario(const std::string& path, const std::vector<ScenarioOverride>& overrides);

// The value at the dotted path `dotted` of the scenario in `path` with the overrides applied: a
// scalar, a list or a section. InputError naming the path when the file does not give it.
YAML::Node ScenarioValue(const std::string& path, const std::vector<ScenarioOverride>& overrides,
                         const std::string& dotted);

// The unit of the value at a dotted path ("nets.0.velocity.1": "m/s", "duration": "s",
// "materials.nylon.bend_stiffness": "N m^2"; "1" for a pure number such as a count, a ratio or a
// direction), as docs/scenarios.md gives it; "" for a path that holds no number. Sweep files
// store it beside each parameter.
std::string ScenarioKeyUnits(const std::string& dotted);

}  // namespace netlab::netsim
