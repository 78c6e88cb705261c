// `netlab fit` end to end, as a user runs it on the digital twin: a small shot simulated with
// known parameters, measured with 1 mm of noise, fitted from a wrong start; the --json contract,
// fit.yaml, priors from a material file, and the bad inputs.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/libnetsim/identification/twin_shot.h"

namespace {

using netlab::testing::LastJson;
using netlab::testing::RunNetlab;

// A material file as `netlab characterize` writes it (libnetsim/characterization/material_file.h).
constexpr char kPrior[] = R"(# netlab characterize: torsion test from torsion.yaml
materials:
  nylon: {twist_stiffness: 7.0e-05, twist_damping: 6.0e-11}
uncertainty:
  nylon:
    twist_stiffness: {sigma: 2.0e-06, test: torsion, source: torsion.yaml}
    twist_damping: {sigma: 1.0e-11, test: torsion, source: torsion.yaml}
)";

class FitCommand : public netlab::testing::CommandTest {
 protected:
  FitCommand() : CommandTest("fit_command") {}
  void SetUp() override {
    CommandTest::SetUp();
    std::ofstream(Path("shot.yaml")) << netlab::testing::kTwinShot;
    std::ofstream(Path("prior.yaml")) << kPrior;
    ASSERT_EQ(RunNetlab("simulate " + Path("shot.yaml") + " --out " + Path("truth.h5")).status, 0);
    // Measured: the truth with 1 mm of noise and its covariance, as triangulate writes it.
    netlab::KnotTracks m = netlab::ReadKnotTracks(Path("truth.h5"));
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 1e-3);
    for (Eigen::Vector3d& p : m.position) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    m.covariance.assign(m.position.size(), Eigen::Matrix3d::Identity() * 1e-6);
    netlab::WriteKnotTracks(Path("measured.h5"), m);
  }
  std::string Fit(const std::string& more) const {
    return "fit " + Path("shot.yaml") + " --measured " + Path("measured.h5") + " --out " +
           Path("fit.yaml") + " " + more;
  }
};

TEST_F(FitCommand, FitsTheTwinAndKeepsTheJsonContract) {
  const auto r =
      RunNetlab(Fit("--free drag.drag_coefficient,nets.0.velocity,time_offset "
                    "--set drag.drag_coefficient=2.4 --set nets.0.velocity=[0.25,0,0] "
                    "--json"));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);
  for (const char* key : {"parameters", "cost_initial", "cost_final", "simulations", "wall_s"})
    EXPECT_TRUE(json.has(key)) << key;
  const auto& drag = json["parameters"]["drag.drag_coefficient"];
  EXPECT_LT(std::abs(drag["value"].number() - 1.2), 3 * drag["sigma"].number());
  EXPECT_TRUE(drag["identified"].boolean());
  const auto& vx = json["parameters"]["nets.0.velocity.0"];
  EXPECT_LT(std::abs(vx["value"].number() - 0.5), 3 * vx["sigma"].number());
  EXPECT_EQ(json["parameters"].object().size(), 5u);
  EXPECT_LT(json["cost_final"].number(), 0.01 * json["cost_initial"].number());
  EXPECT_GT(json["simulations"].number(), 5);
  EXPECT_GT(json["wall_s"].number(), 0);
  // Progress and the table on stderr.
  EXPECT_NE(r.err.find("fit: iteration"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("determined by"), std::string::npos) << r.err;
  // fit.yaml: the same estimates, readable by any YAML reader, and the --set lines to rerun it.
  const YAML::Node file = YAML::LoadFile(Path("fit.yaml"));
  EXPECT_NEAR(file["parameters"]["drag.drag_coefficient"]["value"].as<double>(),
              drag["value"].number(), 1e-5 * drag["value"].number());
  ASSERT_EQ(file["set"].size(), 5u);  // drag, velocity's 3, the held step
  EXPECT_EQ(file["set"][4].as<std::string>().rfind("integrator.dt=", 0), 0u);
  EXPECT_GT(file["dt_s"].as<double>(), 0.0);
  EXPECT_EQ(file["correlation"].size(), 5u);
  EXPECT_TRUE(json["notes"].array().empty());
  EXPECT_EQ(file["notes"].size(), 0u);
  EXPECT_FALSE(std::filesystem::exists(Path("fit.yaml.partial")));
}

// A free EI on a net whose links are too coarse to show it (the twin's 5 cm segments): said before
// the fit starts, after the table, in fit.yaml and in the JSON, with the --set that refines them.
TEST_F(FitCommand, SaysWhenTheLinksAreTooCoarseForTheBendingStiffness) {
  const auto r =
      RunNetlab(Fit("--free drag.drag_coefficient,materials.nylon.bend_stiffness --json"));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);
  ASSERT_EQ(json["notes"].array().size(), 1u);
  const std::string note = json["notes"].array()[0].string();
  EXPECT_NE(note.find("net 'net'"), std::string::npos) << note;
  EXPECT_NE(note.find("5 cm segments (2 per link)"), std::string::npos) << note;
  EXPECT_NE(note.find("--set nets.0.segments_per_link=8"), std::string::npos) << note;
  const size_t first = r.err.find("note: " + note);
  ASSERT_NE(first, std::string::npos) << r.err;
  EXPECT_LT(first, r.err.find("fitting 2 parameters")) << r.err;
  EXPECT_NE(r.err.find("  note: " + note), std::string::npos) << r.err;  // after the table
  // The progress's cost is where the fit stands: within a stage it never rises, though EI's rough
  // cost makes Levenberg-Marquardt reject steps here (Ceres reports their costs).
  std::istringstream lines(r.err);
  std::string line, stage;
  double last = std::numeric_limits<double>::infinity();
  int compared = 0;
  while (std::getline(lines, line)) {
    const size_t at = line.find(", iteration "), cost = line.find("cost ");
    if (line.rfind("fit: stage ", 0) != 0 || at == std::string::npos) continue;
    const double value = std::stod(line.substr(cost + 5));
    if (line.substr(0, at) == stage) {
      EXPECT_LE(value, last) << line;
      ++compared;
    }
    stage = line.substr(0, at);
    last = value;
  }
  EXPECT_GT(compared, 5) << r.err;
  const YAML::Node file = YAML::LoadFile(Path("fit.yaml"));
  ASSERT_EQ(file["notes"].size(), 1u);
  EXPECT_EQ(file["notes"][0].as<std::string>(), note);
}

TEST_F(FitCommand, APriorDeterminesWhatTheFlightCannot) {
  const auto r =
      RunNetlab(Fit("--free drag.drag_coefficient,materials.nylon.twist_damping --prior " +
                    Path("prior.yaml") + " --json --quiet"));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);  // kept: a reference into a temporary would dangle
  const auto& damping = json["parameters"]["materials.nylon.twist_damping"];
  EXPECT_FALSE(damping["identified"].boolean());
  EXPECT_EQ(damping["determined_by"].string(), "prior");
  EXPECT_NEAR(damping["prior_sigma"].number(), 1e-11, 1e-20);
}

TEST_F(FitCommand, BadInputsAreNamed) {
  std::ofstream(Path("zero_sigma.yaml"))
      << std::string(kPrior).replace(std::string(kPrior).find("sigma: 1.0e-11"), 14, "sigma: 0");
  std::ofstream(Path("huge_sigma.yaml")) << std::string(kPrior).replace(
      std::string(kPrior).find("sigma: 1.0e-11"), 14, "sigma: 1e300");
  ASSERT_EQ(RunNetlab("simulate " + Path("shot.yaml") + " --set nets.0.knots=[4,4] --out " +
                      Path("other_net.h5"))
                .status,
            0);
  // The measurement on another clock: 100 s after the launch, in s and (converted) in ms.
  netlab::KnotTracks late = netlab::ReadKnotTracks(Path("measured.h5"));
  for (double& t : late.time) t += 100.0;
  netlab::WriteKnotTracks(Path("late.h5"), late);
  for (double& t : late.time) t *= 1e3;
  netlab::WriteKnotTracks(Path("late_ms.h5"), late);
  {
    netlab::h5::Id file = netlab::h5::OpenFileReadWrite(Path("late_ms.h5"));
    netlab::h5::SetUnits(file.get(), "time", "ms");
  }
  const std::string shot = "fit {dir}/shot.yaml --out {dir}/fit.yaml ";
  const std::string free = " --free time_offset";
  const std::vector<netlab::testing::BadInput> outputs_and_time = {
      // These simulated 100 s of flight for every trial, for hours, before any message.
      {"a measurement 100 s after the launch",
       shot + "--measured {dir}/late.h5" + free,
       1,
       {"{dir}/late.h5: /time spans 100 .. 100.", "no overlap", "--time-offset"}},
      {"a measurement in ms, 100 s after the launch",
       shot + "--measured {dir}/late_ms.h5" + free,
       1,
       {"{dir}/late_ms.h5: /time spans 100 .. 100.", "no overlap"}},
      {"--out is the scenario",
       "fit {dir}/shot.yaml --measured {dir}/measured.h5 --out {dir}/shot.yaml" + free,
       1,
       {"--out {dir}/shot.yaml", "the scenario file {dir}/shot.yaml"},
       {"{dir}/shot.yaml"}},
      {"--out is the measured file",
       "fit {dir}/shot.yaml --measured {dir}/measured.h5 --out {dir}/measured.h5" + free,
       1,
       {"--out {dir}/measured.h5", "the --measured file {dir}/measured.h5"},
       {"{dir}/measured.h5"}},
      {"--out is the prior",
       shot.substr(0, shot.find("--out")) +
           "--out {dir}/prior.yaml --measured "
           "{dir}/measured.h5 --prior {dir}/prior.yaml --free materials.nylon.twist_damping",
       1,
       {"--out {dir}/prior.yaml", "the --prior file {dir}/prior.yaml"},
       {"{dir}/prior.yaml"}},
  };
  const auto start = std::chrono::steady_clock::now();
  netlab::testing::ExpectBadInputs(outputs_and_time, dir_.string());
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 60.0);
  const std::vector<netlab::testing::BadInput> table = {
      {"no --free", shot + "--measured {dir}/measured.h5", 2, {"--free"}},
      {"an unknown parameter",
       shot + "--measured {dir}/measured.h5 --free "
              "materials.nylon.bend_stifness",
       1,
       {"shot.yaml", "bend_stifness"}},
      {"a section",
       shot + "--measured {dir}/measured.h5 --free materials.nylon",
       1,
       {"materials.nylon", "is a section"}},
      {"a missing measured file",
       shot + "--measured {dir}/nowhere.h5 --free time_offset",
       1,
       {"nowhere.h5"}},
      {"another net",
       shot + "--measured {dir}/other_net.h5 --meas-sigma 0.001 --free time_offset",
       1,
       {"grid mismatch", "other_net.h5"}},
      {"tracks without covariance",
       shot + "--measured {dir}/truth.h5 --free time_offset",
       1,
       {"truth.h5", "--meas-sigma"}},
      {"a missing prior file",
       shot + "--measured {dir}/measured.h5 --free time_offset "
              "--prior {dir}/none.yaml",
       1,
       {"none.yaml"}},
      {"a prior without uncertainty",
       shot + "--measured {dir}/measured.h5 --free "
              "materials.nylon.twist_damping --prior {dir}/zero_sigma.yaml",
       1,
       {"zero_sigma.yaml", "twist_damping", "sigma > 0"}},
      {"--free with a trailing comma",
       shot + "--measured {dir}/measured.h5 --free time_offset,",
       1,
       {"--free 'time_offset,'", "an empty name"}},
      {"--measured with a trailing comma",
       shot + "--measured {dir}/measured.h5, --free time_offset",
       2,
       {"--measured '{dir}/measured.h5,'", "an empty file name"}},
      {"a prior of sigma 1e300",
       shot + "--measured {dir}/measured.h5 --free "
              "materials.nylon.twist_damping --prior {dir}/huge_sigma.yaml",
       1,
       {"{dir}/huge_sigma.yaml: uncertainty.nylon.twist_damping.sigma", "over 100 times"}},
      {"fewer track files than shots",
       "fit {dir}/shot.yaml {dir}/shot.yaml --out {dir}/fit.yaml "
       "--measured {dir}/measured.h5 --free time_offset",
       2,
       {"--measured", "one per shot"}},
      {"an empty output",
       "fit {dir}/shot.yaml --measured {dir}/measured.h5 --free time_offset "
       "--out ''",
       2,
       {"--out"}},
      {"a start the simulation cannot take",
       shot + "--measured {dir}/measured.h5 --free "
              "materials.nylon.stretch_stiffness --set materials.nylon.stretch_stiffness=-5",
       1,
       {"stretch_stiffness"}},
  };
  netlab::testing::ExpectBadInputs(table, dir_.string());
}

}  // namespace
