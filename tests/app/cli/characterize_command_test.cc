// `netlab characterize` run as a user runs it on the shipped examples (scenarios/bench/): each
// exits 0, its material file reads back through ReadMaterialFile with the values and sigmas the
// JSON summary printed, and the values are the generating ones (synthetic_bench.h) within 3 sigma.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "libnetsim/characterization/material_file.h"
#include "libnetsim/characterization/synthetic_bench.h"
#include "tests/app/cli/run_netlab.h"

namespace netlab::testing {
namespace {

const std::string kBench = std::string(NETLAB_SOURCE_DIR) + "/scenarios/bench/";

class CharacterizeCommand : public CommandTest {
 protected:
  CharacterizeCommand() : CommandTest("characterize_command") {}

  // Runs the example `name` and checks its output; returns the estimates read back.
  std::vector<netsim::ParameterEstimate> Run(const std::string& name, size_t parameters) {
    const std::string out = Path("material.yaml");
    const NetlabResult r =
        RunNetlab("characterize " + kBench + name + ".yaml --out " + out + " --json");
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find(name + " test from " + name + ".yaml"), std::string::npos) << r.out;
    const Json json = LastJson(r.out);
    EXPECT_EQ(json["material"].string(), "nylon_1mm");
    EXPECT_EQ(json["test"].string(), name);
    EXPECT_TRUE(json["fit"].has("points"));
    const std::vector<netsim::ParameterEstimate> read = netsim::ReadMaterialFile(out);
    EXPECT_EQ(read.size(), parameters);
    EXPECT_EQ(json["parameters"].object().size(), parameters);
    for (const netsim::ParameterEstimate& e : read) {
      SCOPED_TRACE(name + ": " + e.key);
      const Json& printed = json["parameters"][e.key];
      EXPECT_NEAR(printed["value"].number(), e.value, 1e-8 * e.value);
      EXPECT_NEAR(printed["sigma"].number(), e.sigma, 1e-8 * e.sigma);
      EXPECT_EQ(printed["test"].string(), e.test);
      EXPECT_EQ(e.source, name + ".yaml");
      EXPECT_EQ(e.material, "nylon_1mm");
      EXPECT_LT(std::abs(e.value - netsim::MaterialValue(netsim::BenchNylon(), e.key)), 3 * e.sigma)
          << e.value << " +- " << e.sigma << ", generated with "
          << netsim::MaterialValue(netsim::BenchNylon(), e.key);
    }
    return read;
  }
};

TEST_F(CharacterizeCommand, TensileExampleGivesStretchParametersAndDensity) {
  const auto read = Run("tensile", 3);
  EXPECT_EQ(read[0].key, "linear_density");
  EXPECT_EQ(read[0].test, "weighing");
  EXPECT_EQ(read[1].key, "stretch_stiffness");
  EXPECT_EQ(read[1].test, "tensile");
}

TEST_F(CharacterizeCommand, CantileverExampleGivesBendParameters) {
  const auto read = Run("cantilever", 3);
  EXPECT_EQ(read[1].key, "bend_stiffness");
  EXPECT_EQ(read[2].key, "bend_damping");
}

TEST_F(CharacterizeCommand, TorsionExampleGivesTwistParameters) {
  const auto read = Run("torsion", 3);
  EXPECT_EQ(read[1].key, "twist_stiffness");
  EXPECT_EQ(read[2].key, "twist_damping");
}

TEST_F(CharacterizeCommand, HelpNamesEveryTest) {
  const NetlabResult r = RunNetlab("characterize --help");
  EXPECT_EQ(r.status, 0);
  for (const char* test : {"tensile", "cantilever", "torsion", "weighing", "--out", "--json"})
    EXPECT_NE(r.out.find(test), std::string::npos) << test;
}

}  // namespace
}  // namespace netlab::testing
