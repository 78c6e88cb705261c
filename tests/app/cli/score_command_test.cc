// `netlab score` end to end, as a user runs it: exit status, the --json contract on stdout, the
// messages on stderr, score.h5 and the report.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "common/hdf5_util.h"
#include "common/tracks/track_file.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::KnotTracks;
using netlab::testing::LastJson;
using netlab::testing::RunNetlab;

// A 6 x 6 net flying along x and opening, stored at 179 fps from t0 (m, s).
KnotTracks Flight(int rows, int cols, int frames, double t0, double noise_m, std::mt19937* rng) {
  KnotTracks tracks;
  tracks.source = "test";
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) tracks.grid.push_back({r, c});
  std::normal_distribution<double> normal(0.0, noise_m);
  for (int i = 0; i < frames; ++i) {
    const double t = t0 + i / 179.0;
    tracks.time.push_back(i / 179.0);
    const double open = 1.0 + 0.4 * t - 0.3 * t * t;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        Eigen::Vector3d p(0.6 * t + 0.02 * std::sin(4 * t + r), (c - 2.5) * 0.1 * open,
                          (r - 2.5) * 0.1 * open);
        if (rng) p += Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
        tracks.position.push_back(p);
        tracks.valid.push_back(1);
        if (rng) tracks.covariance.push_back(Eigen::Matrix3d::Identity() * noise_m * noise_m);
      }
  }
  return tracks;
}

class ScoreCommand : public netlab::testing::CommandTest {
 protected:
  ScoreCommand() : CommandTest("score_command") {}
};

TEST_F(ScoreCommand, HelpNamesEveryOptionOfTheContract) {
  const auto r = RunNetlab("score --help");
  EXPECT_EQ(r.status, 0);
  for (const char* option : {"--measured", "--sim", "--out", "--report", "--align", "--json",
                             "none|time|rigid|time+rigid"})
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  EXPECT_NE(RunNetlab("--help").out.find("score"), std::string::npos);
}

TEST_F(ScoreCommand, ScoresAShiftedNoisyMeasurementAsConsistentWithTheContractFields) {
  std::mt19937 rng(5);
  // The measurement starts 12.3 ms into the simulation: the offset the command must find.
  netlab::WriteKnotTracks(Path("tracks.h5"), Flight(6, 6, 120, 0.0123, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 6, 160, 0.0, 0.0, nullptr));
  const auto r =
      RunNetlab("score --measured " + Path("tracks.h5") + " --sim " + Path("sim.h5") + " --out " +
                Path("score.h5") + " --report " + Path("report.html") + " --align time --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);
  for (const char* key : {"frames", "knots", "points", "rms_mm", "rms_percent_of_side", "max_mm",
                          "mean_d2", "dof", "p_value", "verdict", "time_offset_s",
                          "time_offset_sigma_s", "skill", "per_class", "wall_s"})
    EXPECT_TRUE(json.has(key)) << key;
  EXPECT_EQ(json["frames"].number(), 120);
  EXPECT_EQ(json["knots"].number(), 36);
  EXPECT_EQ(json["points"].number(), 120 * 36);
  EXPECT_EQ(json["verdict"].string(), "consistent");
  EXPECT_NEAR(json["time_offset_s"].number(), 0.0123, 2e-4);
  EXPECT_LT(json["time_offset_sigma_s"].number(), 1e-3);
  EXPECT_NEAR(json["mean_d2"].number(), 3.0, 0.3);
  EXPECT_EQ(json["dof"].number(), 3 * 120 * 36 - 1);
  EXPECT_NEAR(json["rms_mm"].number(), 0.5 * std::sqrt(3.0), 0.1);
  EXPECT_GT(json["skill"].number(), 0.9);
  for (const char* c : {"corner", "edge", "inner"})
    EXPECT_GT(json["per_class"][c].number(), 0.0) << c;
  EXPECT_NE(r.err.find("verdict: consistent"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(Path("score.h5")));
  EXPECT_FALSE(std::filesystem::exists(Path("score.h5.partial")));
  EXPECT_TRUE(std::filesystem::exists(Path("report.html")));

  // score.h5 holds the same summary, with units.
  netlab::h5::Id file = netlab::h5::OpenFileReadOnly(Path("score.h5"));
  EXPECT_EQ(netlab::h5::ReadStringAttribute(file.get(), "verdict"), "consistent");
  double offset = 0;
  netlab::h5::ReadDataset(file.get(), "/alignment/time_offset_s", H5T_NATIVE_DOUBLE, &offset);
  EXPECT_NEAR(offset, json["time_offset_s"].number(), 1e-10);  // JSON has 10 digits
  EXPECT_EQ(netlab::h5::DatasetDims(file.get(), "/residual"), (std::vector<hsize_t>{120, 36, 3}));
}

TEST_F(ScoreCommand, AGridMismatchIsAnErrorNamingTheFiles) {
  std::mt19937 rng(5);
  netlab::WriteKnotTracks(Path("tracks.h5"), Flight(6, 6, 20, 0.0, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 5, 40, 0.0, 0.0, nullptr));
  const auto r = RunNetlab("score --measured " + Path("tracks.h5") + " --sim " + Path("sim.h5") +
                           " --out " + Path("score.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("grid mismatch: knot (0,5)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(Path("sim.h5")), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("score.h5")));
}

TEST_F(ScoreCommand, AMissingFileAndABadAlignmentAreNamed) {
  auto r = RunNetlab("score --measured " + Path("none.h5") + " --sim " + Path("none.h5") +
                     " --out " + Path("score.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("none.h5"), std::string::npos) << r.err;
  r = RunNetlab("score --measured a.h5 --sim b.h5 --out c.h5 --align sideways");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--align expects none, time, rigid or time+rigid"), std::string::npos);
  r = RunNetlab("score --measured a.h5 --out c.h5");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("sim"), std::string::npos) << r.err;
}

}  // namespace

namespace {

// --sim-ensemble: a comma list of runs gives Sigma_sim (ensemble_members, per phase sigma_sim_mm
// beside rms_mm); one member, or a member of another net, is refused naming the file, and nothing
// is left under --out or --report.
TEST_F(ScoreCommand, AnEnsembleGivesSigmaSimPerPhaseAndABadOneIsRefused) {
  std::mt19937 rng(9);
  netlab::WriteKnotTracks(Path("tracks.h5"), Flight(6, 6, 60, 0.0, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 6, 80, 0.0, 0.0, nullptr));
  std::string list;
  for (int m = 0; m < 3; ++m) {
    std::mt19937 member_rng(100 + m);
    KnotTracks run = Flight(6, 6, 80, 0.0, 2e-3, &member_rng);
    run.covariance.clear();
    const std::string path = Path("run" + std::to_string(m) + ".h5");
    netlab::WriteKnotTracks(path, run);
    list += (list.empty() ? "" : ",") + path;
  }
  const std::string head = "score --measured " + Path("tracks.h5") + " --sim " + Path("sim.h5") +
                           " --out " + Path("score.h5") + " --report " + Path("report.html");
  auto r = RunNetlab(head + " --sim-ensemble " + list + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  auto json = LastJson(r.out);
  EXPECT_EQ(json["ensemble_members"].number(), 3);
  EXPECT_NE(json["sim_uncertainty"].string().find("3 ensemble runs"), std::string::npos);
  bool some_phase = false;
  for (const auto& phase : json["phases"].array()) {
    if (phase["points"].number() == 0) continue;
    some_phase = true;
    // Three runs 2 mm apart per axis: 2 S (sigma_sim^2 = 2 x 3 x 4e-6 m^2 on average) ~ 4.9 mm.
    EXPECT_GT(phase["sigma_sim_mm"].number(), 3.0);
    EXPECT_LT(phase["sigma_sim_mm"].number(), 7.0);
    EXPECT_NEAR(phase["sigma_meas_mm"].number(), 0.5 * std::sqrt(3.0), 1e-6);
    EXPECT_TRUE(phase.has("rms_mm"));
  }
  EXPECT_TRUE(some_phase);
  std::filesystem::remove(Path("score.h5"));
  std::filesystem::remove(Path("report.html"));

  r = RunNetlab(head + " --sim-ensemble " + Path("run0.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("1 member (" + Path("run0.h5") + ")"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("at least 2 runs"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("score.h5")));
  EXPECT_FALSE(std::filesystem::exists(Path("report.html")));

  netlab::WriteKnotTracks(Path("other.h5"), Flight(6, 5, 80, 0.0, 0.0, nullptr));
  r = RunNetlab(head + " --sim-ensemble " + Path("run0.h5") + "," + Path("other.h5"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(Path("other.h5") + ": 30 knots"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("same net"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("score.h5")));
  EXPECT_FALSE(std::filesystem::exists(Path("report.html")));
}

}  // namespace
