// `netlab score` end to end, as a user runs it: exit status, the --json contract on stdout, the
// messages on stderr, score.h5 and the report.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
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

namespace {

// Repeats: three shots of one flight launched at their own times with their own noise. Each is
// scored on its own (its own offset), the test is pooled, the spread between them is the noise.
TEST_F(ScoreCommand, RepeatsAreScoredEachOnItsOwnAndPooled) {
  const double t0[3] = {0.0123, 0.0057, 0.0201};
  std::string list;
  for (int i = 0; i < 3; ++i) {
    std::mt19937 rng(40 + i);
    const std::string path = Path("shot" + std::to_string(i) + ".h5");
    netlab::WriteKnotTracks(path, Flight(6, 6, 100, t0[i], 5e-4, &rng));
    list += (list.empty() ? "" : ",") + path;
  }
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 6, 160, 0.0, 0.0, nullptr));
  const auto r = RunNetlab("score --measured " + list + " --sim " + Path("sim.h5") + " --out " +
                           Path("score.h5") + " --report " + Path("report.html") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);
  ASSERT_TRUE(json.has("shots"));
  ASSERT_EQ(json["shots"].array().size(), 3u);
  double dof = 0.0;
  for (int i = 0; i < 3; ++i) {
    const auto& shot = json["shots"].array()[i];
    EXPECT_EQ(shot["path"].string(), Path("shot" + std::to_string(i) + ".h5"));
    EXPECT_EQ(shot["verdict"].string(), "consistent");
    EXPECT_NEAR(shot["time_offset_s"].number(), t0[i], 2e-4) << i;
    EXPECT_NEAR(shot["mean_d2"].number(), 3.0, 0.3) << i;
    EXPECT_NEAR(shot["rms_mm"].number(), 0.5 * std::sqrt(3.0), 0.1) << i;
    dof += shot["dof"].number();
  }
  const auto& pooled = json["pooled"];
  EXPECT_EQ(pooled["verdict"].string(), "consistent");
  EXPECT_EQ(pooled["dof"].number(), dof);
  EXPECT_EQ(pooled["dof"].number(), 3 * (3 * 100 * 36 - 1));
  EXPECT_GT(pooled["p_value"].number(), 0.01);
  // The top level's test is the pooled one; the rest is the first shot's.
  EXPECT_EQ(json["verdict"].string(), pooled["verdict"].string());
  EXPECT_EQ(json["mean_d2"].number(), pooled["mean_d2"].number());
  EXPECT_EQ(json["dof"].number(), pooled["dof"].number());
  EXPECT_EQ(json["p_value"].number(), pooled["p_value"].number());
  EXPECT_EQ(json["time_offset_s"].number(), json["shots"].array()[0]["time_offset_s"].number());
  // The spread: 0.5 mm per axis between shots, sqrt(3) x 0.5 mm in 3-D, in every phase measured.
  bool some_phase = false;
  for (const char* phase : {"ejection", "spreading", "opened", "contact"}) {
    ASSERT_TRUE(json["repeat_spread_mm"].has(phase)) << phase;
    if (json["repeat_spread_mm"][phase].is_null()) continue;
    some_phase = true;
    EXPECT_NEAR(json["repeat_spread_mm"][phase].number(), 0.5 * std::sqrt(3.0), 0.15) << phase;
  }
  EXPECT_TRUE(some_phase);
  EXPECT_NEAR(json["repeat_spread_all_mm"].number(), 0.5 * std::sqrt(3.0), 0.08);
  EXPECT_NE(r.err.find("pooled:"), std::string::npos) << r.err;

  // score.h5: the first shot's tables, the pooled verdict, and /repeats.
  netlab::h5::Id file = netlab::h5::OpenFileReadOnly(Path("score.h5"));
  EXPECT_EQ(netlab::h5::ReadStringAttribute(file.get(), "verdict"), "consistent");
  EXPECT_EQ(netlab::h5::DatasetDims(file.get(), "/residual"), (std::vector<hsize_t>{100, 36, 3}));
  EXPECT_EQ(netlab::h5::DatasetDims(file.get(), "/repeats/shots/time_offset_s"),
            (std::vector<hsize_t>{3}));
  double offsets[3];
  netlab::h5::ReadDataset(file.get(), "/repeats/shots/time_offset_s", H5T_NATIVE_DOUBLE, offsets);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(offsets[i], t0[i], 2e-4) << i;
  EXPECT_TRUE(netlab::h5::Exists(file.get(), "/repeats/shot_2/per_phase/rms_m"));
  EXPECT_TRUE(netlab::h5::Exists(file.get(), "/repeats/spread/per_phase/rms_m"));
  EXPECT_TRUE(netlab::h5::Exists(file.get(), "/repeats/pooled/p_value"));

  // The report's Repeats section: a row per shot and the pooled one.
  std::ifstream in(Path("report.html"));
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t section = html.find("<h2 id=\"repeats\">Repeats</h2>");
  ASSERT_NE(section, std::string::npos);
  const size_t table = html.find("<table id=\"repeat-shots\">", section);
  const size_t end = html.find("</table>", table);
  ASSERT_NE(table, std::string::npos);
  const std::string shots = html.substr(table, end - table);
  for (int i = 0; i < 3; ++i)
    EXPECT_NE(shots.find("<td>" + Path("shot" + std::to_string(i) + ".h5") + "</td>"),
              std::string::npos)
        << i;
  EXPECT_NE(shots.find("<td><b>pooled</b></td>"), std::string::npos);
  EXPECT_NE(html.find("<table id=\"repeat-spread\">", end), std::string::npos);
}

// One measured file: no repeats fields.
TEST_F(ScoreCommand, OneMeasuredFileHasNoRepeats) {
  std::mt19937 rng(7);
  netlab::WriteKnotTracks(Path("tracks.h5"), Flight(6, 6, 40, 0.01, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 6, 80, 0.0, 0.0, nullptr));
  const auto r =
      RunNetlab("score --measured " + Path("tracks.h5") + " --sim " + Path("sim.h5") + " --out " +
                Path("score.h5") + " --report " + Path("report.html") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = LastJson(r.out);
  EXPECT_FALSE(json.has("shots"));
  EXPECT_FALSE(json.has("pooled"));
  EXPECT_FALSE(json.has("repeat_spread_mm"));
  netlab::h5::Id file = netlab::h5::OpenFileReadOnly(Path("score.h5"));
  EXPECT_FALSE(netlab::h5::Exists(file.get(), "/repeats"));
  std::ifstream in(Path("report.html"));
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(html.find("id=\"repeats\""), std::string::npos);
}

// Bad repeats: an empty item, a file twice, another net, a shot outside the simulation's time;
// each named, and nothing left under --out or --report.
TEST_F(ScoreCommand, BadRepeatsAreRefusedNamingTheFile) {
  std::mt19937 rng(11);
  netlab::WriteKnotTracks(Path("a.h5"), Flight(6, 6, 40, 0.0, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("b.h5"), Flight(6, 6, 40, 0.005, 5e-4, &rng));
  netlab::WriteKnotTracks(Path("sim.h5"), Flight(6, 6, 80, 0.0, 0.0, nullptr));
  netlab::WriteKnotTracks(Path("other.h5"), Flight(6, 5, 40, 0.0, 5e-4, &rng));
  KnotTracks late = Flight(6, 6, 40, 0.0, 5e-4, &rng);
  for (double& t : late.time) t += 5.0;
  netlab::WriteKnotTracks(Path("late.h5"), late);
  const std::string tail = " --sim " + Path("sim.h5") + " --out " + Path("score.h5") +
                           " --report " + Path("report.html");
  auto refused = [&](const std::string& list, int status, const std::vector<std::string>& words) {
    const auto r = RunNetlab("score --measured " + list + tail);
    EXPECT_EQ(r.status, status) << list << "\n" << r.err;
    for (const std::string& word : words)
      EXPECT_NE(r.err.find(word), std::string::npos) << list << ": " << word << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(Path("score.h5"))) << list;
    EXPECT_FALSE(std::filesystem::exists(Path("report.html"))) << list;
    EXPECT_FALSE(std::filesystem::exists(Path("score.h5.partial"))) << list;
  };
  refused(Path("a.h5") + ",," + Path("b.h5"), 2, {"--measured", "an empty file name", "item 2"});
  refused(Path("a.h5") + "," + Path("b.h5") + ",", 2, {"an empty file name", "item 3"});
  refused(Path("a.h5") + "," + Path("b.h5") + "," + Path("a.h5"), 1,
          {Path("a.h5") + " (item 3) is item 1 again"});
  refused(Path("a.h5") + "," + Path("b.h5") + "," + dir_.string() + "/./a.h5", 1,
          {"(item 3) is " + Path("a.h5") + ", item 1 again"});
  refused(Path("a.h5") + "," + Path("other.h5"), 1,
          {Path("other.h5") + " is not a repeat of " + Path("a.h5"), "30 knots", "36"});
  refused(Path("a.h5") + "," + Path("late.h5"), 1,
          {"no overlap in time", Path("late.h5") + " spans 5"});
}

}  // namespace
