// Scenario overrides (--set PATH=VALUE): the named value changes and nothing else; every bad path
// or value is an error naming the override and what the scenario has there.

#include "libnetsim/scenario/scenario_override.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "common/errors.h"

namespace netlab::netsim {
namespace {

const std::string kFlight = std::string(NETLAB_SOURCE_DIR) + "/scenarios/net_a_0.5.yaml";

std::vector<ScenarioOverride> Sets(const std::vector<std::string>& args) {
  std::vector<ScenarioOverride> sets;
  for (const std::string& a : args) sets.push_back(ParseOverride(a));
  return sets;
}

// The issue's own examples on a flight scenario: each value changes, the rest of the scenario is
// as the file has it.
TEST(ScenarioOverride, ChangesTheNamedValuesAndNothingElse) {
  const Scenario plain = LoadScenario(kFlight);
  const Scenario changed =
      LoadScenario(kFlight, Sets({"integrator.type=implicit", "integrator.dt=1e-5",
                                  "materials.nylon_1mm.bend_stiffness=2e-4",
                                  "nets.0.velocity=[0.8,0,0]", "drag.drag_coefficient=1.0"}));
  EXPECT_EQ(changed.simulation.integrator, IntegratorType::kImplicit);
  EXPECT_EQ(changed.simulation.dt, 1e-5);
  EXPECT_EQ(plain.simulation.dt, 0.0);  // auto in the file
  ASSERT_EQ(changed.materials.size(), 1u);
  EXPECT_EQ(changed.materials[0].bend_stiffness, 2e-4);
  EXPECT_EQ(changed.nets[0].velocity, Vector3d(0.8, 0, 0));
  ASSERT_TRUE(changed.drag.has_value());
  EXPECT_EQ(changed.drag->drag_coefficient, 1.0);
  // The rest as in the file.
  EXPECT_EQ(changed.materials[0].stretch_stiffness, plain.materials[0].stretch_stiffness);
  EXPECT_EQ(changed.materials[0].twist_damping, plain.materials[0].twist_damping);
  EXPECT_EQ(changed.drag->air_density, plain.drag->air_density);
  EXPECT_EQ(changed.nets[0].rows, plain.nets[0].rows);
  EXPECT_EQ(changed.nets[0].corner_velocities, plain.nets[0].corner_velocities);
  EXPECT_EQ(changed.duration, plain.duration);
  EXPECT_EQ(changed.bodies.size(), plain.bodies.size());
  EXPECT_EQ(changed.source_path, kFlight);
  // The text stored with the results is what ran: it names the overrides and parses to the same.
  EXPECT_NE(changed.text.find("--set nets.0.velocity=[0.8,0,0]"), std::string::npos);
  const Scenario again =
      ParseScenario(changed.text, "stored", std::string(NETLAB_SOURCE_DIR) + "/scenarios");
  EXPECT_EQ(again.materials[0].bend_stiffness, 2e-4);
  EXPECT_EQ(again.nets[0].velocity, Vector3d(0.8, 0, 0));
  EXPECT_EQ(again.simulation.dt, 1e-5);
}

// A list's entry by its name as well as by its index; a later override of the same value wins;
// a key the file leaves at its default may be set.
TEST(ScenarioOverride, NamesEntriesLaterOnesWinAndDefaultsCanBeSet) {
  const Scenario s =
      LoadScenario(kFlight, Sets({"nets.net.velocity=[0.6,0,0]", "bodies.target.friction=0.5",
                                  "nets.0.velocity=[0.7, 0, 0.1]", "integrator.safety=0.5",
                                  "drag.tangential_coefficient=0.1"}));
  EXPECT_EQ(s.nets[0].velocity, Vector3d(0.7, 0, 0.1));
  EXPECT_EQ(s.bodies[0].friction, 0.5);
  EXPECT_EQ(s.simulation.safety, 0.5);
  EXPECT_EQ(s.drag->tangential_coefficient, 0.1);
}

// Every kind of bad override: the message names the override (or, for a value the scenario's
// own checks refuse, the key and the overrides) and what was expected.
TEST(ScenarioOverride, BadOverridesAreErrorsNamingThem) {
  struct Case {
    std::string set;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      {"materials.nylon_2mm.bend_stiffness=1",
       {"--set materials.nylon_2mm.bend_stiffness=1",
        "'materials.nylon_2mm' is not in the "
        "scenario",
        "nylon_1mm"}},
      {"integrator.typo.x=1", {"'integrator.typo' is not in the scenario", "type, dt"}},
      {"integrater.dt=1e-5", {"integrater: unknown key", "integrator"}},
      {"nets.3.velocity=[1,0,0]", {"'3' is not an entry of nets", "1 entry", "0..0"}},
      {"nets.other.velocity=[1,0,0]", {"'other' is not an entry of nets"}},
      {"nets.0.velocity=0.8", {"expected a list of 3 items", "got a number"}},
      {"nets.0.velocity=[0.8,0]", {"expected a list of 3 items", "got a list of 2 items"}},
      {"materials.nylon_1mm.bend_stiffness=abc", {"expected a number", "got 'abc'"}},
      {"materials.nylon_1mm.bend_stiffness=[1,2]", {"expected a number", "got a list of 2"}},
      {"materials=1", {"'materials' is a section", "nylon_1mm"}},
      {"duration.x=1", {"'duration' is a value, not a section"}},
      {"drag..air_density=1", {"empty key"}},
      {"drag.air_density=[1,", {"not YAML"}},
      {"materials.nylon_1mm.bend_stiffness=-1",
       {"materials.nylon_1mm.bend_stiffness: must be > 0",
        "changed by --set materials.nylon_1mm.bend_stiffness=-1"}},
      {"materials.nylon_1mm.bend_stifness=1",
       {"materials.nylon_1mm.bend_stifness: unknown key", "bend_stiffness"}},
      {"integrator.type=rk4", {"unknown integrator 'rk4'"}},
  };
  for (const Case& c : cases) {
    try {
      LoadScenario(kFlight, Sets({c.set}));
      ADD_FAILURE() << c.set << ": accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(kFlight, 0), 0u) << what;  // leads with the file
      for (const std::string& f : c.fragments)
        EXPECT_NE(what.find(f), std::string::npos) << c.set << " -> " << what;
    }
  }
  for (const std::string bad : {"novalue", "=3", "path=", " = "}) {
    try {
      ParseOverride(bad);
      ADD_FAILURE() << "'" << bad << "' accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("expected PATH=VALUE"), std::string::npos) << e.what();
    }
  }
  // A value with '=' in it is the value's.
  EXPECT_EQ(ParseOverride("name=a=b").value, "a=b");
}

// A file that is no scenario gives its own error before any override is looked at.
TEST(ScenarioOverride, TheFilesOwnErrorsComeFirst) {
  const std::string dir = ::testing::TempDir();
  const std::string list = dir + "/override_list.yaml", empty = dir + "/override_empty.yaml";
  std::ofstream(list) << "- a\n- b\n";
  std::ofstream(empty) << "";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {list, "(root): expected a mapping of keys"},
      {empty, "file is empty"},
      {dir + "/override_missing.yaml", "cannot open scenario file"}};
  for (const auto& [file, fragment] : cases) {
    try {
      LoadScenario(file, Sets({"duration=1"}));
      ADD_FAILURE() << file << ": accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  }
}

// The unit of a dotted path's value, by its last key (list indices skipped).
TEST(ScenarioKeyUnits, NamesTheUnitOfEachKey) {
  EXPECT_EQ(ScenarioKeyUnits("duration"), "s");
  EXPECT_EQ(ScenarioKeyUnits("integrator.dt"), "s");
  EXPECT_EQ(ScenarioKeyUnits("nets.0.velocity.1"), "m/s");
  EXPECT_EQ(ScenarioKeyUnits("nets.0.knots.0"), "1");
  EXPECT_EQ(ScenarioKeyUnits("materials.nylon.stretch_stiffness"), "N");
  EXPECT_EQ(ScenarioKeyUnits("materials.nylon.bend_damping"), "N m^2 s");
  EXPECT_EQ(ScenarioKeyUnits("gravity.2"), "m/s^2");
  EXPECT_EQ(ScenarioKeyUnits("bodies.0.stiffness"), "N/m");
  EXPECT_EQ(ScenarioKeyUnits("name"), "");
}

}  // namespace
}  // namespace netlab::netsim
