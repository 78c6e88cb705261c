// The simulation's own spread from an ensemble (libnetsim/validation/sim_ensemble.h): a model that
// parts from the truth after "contact" as much as its own runs part from each other is rejected
// with Sigma_sim = 0 and consistent with the ensemble's spread; the ensemble is refused when it
// has one member, another net, or does not cover the simulation's time.

#include "libnetsim/validation/sim_ensemble.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "common/errors.h"
#include "common/hdf5_util.h"
#include "libnetsim/validation/score.h"
#include "score_test_data.h"

namespace netlab::netsim {
namespace {

constexpr double kContact = 0.6;  // s: the deviations start here

// The truth plus a smooth deviation per knot that grows after kContact (a random direction and
// amplitude of about `size_m`, slowly turning): one run of a chaotic phase.
KnotTracks Chaotic(const KnotTracks& truth, double size_m, std::mt19937* rng) {
  KnotTracks out = truth;
  std::normal_distribution<double> normal(0.0, 1.0);
  const int knots = truth.knots();
  for (int k = 0; k < knots; ++k) {
    const Eigen::Vector3d a(normal(*rng), normal(*rng), normal(*rng));
    const Eigen::Vector3d b(normal(*rng), normal(*rng), normal(*rng));
    for (int f = 0; f < truth.frames(); ++f) {
      const double s = std::max(0.0, truth.time[f] - kContact) / 0.3;
      out.position[static_cast<size_t>(f) * knots + k] +=
          size_m * std::min(s, 1.0) * (std::cos(3 * s) * a + std::sin(3 * s) * b) / std::sqrt(2.0);
    }
  }
  return out;
}

struct Twin {
  KnotTracks measured, model;
  std::vector<EnsembleMember> members;
};

Twin MakeTwin(int members) {
  std::mt19937 rng(5);
  Twin twin;
  const KnotTracks truth = testing::SmallFlight(180, 0.0, 0.0, nullptr);
  twin.measured = Chaotic(truth, 0.02, &rng);  // the measured shot: one more chaotic draw
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (size_t i = 0; i < twin.measured.position.size(); ++i) {
    twin.measured.position[i] += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    twin.measured.covariance.push_back(Eigen::Matrix3d::Identity() * 1e-6);
  }
  twin.model = Chaotic(truth, 0.02, &rng);
  for (int m = 0; m < members; ++m)
    twin.members.push_back({"member " + std::to_string(m), Chaotic(truth, 0.02, &rng)});
  return twin;
}

ScoreOptions Options() {
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  options.contact_time_s = kContact;
  return options;
}

const ScoreRow& Phase(const ScoreSummary& s, const std::string& name) {
  for (const auto& row : s.per_phase)
    if (row.name == name) return row;
  ADD_FAILURE() << "no phase " << name;
  return s.per_phase.front();
}

TEST(SimEnsembleTest, TheSpreadMakesTheChaoticPhaseConsistent) {
  const Twin twin = MakeTwin(40);
  const ScoreResult bare = Score(twin.measured, twin.model, Options());
  EXPECT_EQ(bare.summary.verdict, Verdict::kInconsistent);
  EXPECT_GT(Phase(bare.summary, "contact").mean_d2, 50.0);
  EXPECT_EQ(Phase(bare.summary, "contact").sigma_sim_m, 0.0);

  double max_sigma = 0;
  const KnotTracks with = AddEnsembleCovariance(twin.model, "model", twin.members, &max_sigma);
  EXPECT_GT(max_sigma, 0.01);
  const ScoreResult scored = Score(twin.measured, with, Options());
  const ScoreRow& contact = Phase(scored.summary, "contact");
  EXPECT_EQ(scored.summary.verdict, Verdict::kConsistent) << scored.summary.mean_d2;
  EXPECT_LT(contact.mean_d2, 4.0);
  // Both contributions stated: the spread in contact is centimetres, before it nothing.
  EXPECT_GT(contact.sigma_sim_m, 0.01);
  EXPECT_NEAR(contact.sigma_meas_m, std::sqrt(3e-6), 1e-9);
  EXPECT_LT(Phase(scored.summary, "ejection").sigma_sim_m, 1e-9);
}

TEST(SimEnsembleTest, AWrongModelStaysRejectedBeforeTheChaos) {
  Twin twin = MakeTwin(40);
  // 5 mm off in every frame before contact: the spread there is zero, so nothing excuses it.
  for (int f = 0; f < twin.model.frames(); ++f)
    if (twin.model.time[f] < kContact)
      for (int k = 0; k < twin.model.knots(); ++k)
        twin.model.position[static_cast<size_t>(f) * twin.model.knots() + k].y() += 0.005;
  const KnotTracks with = AddEnsembleCovariance(twin.model, "model", twin.members);
  const ScoreResult scored = Score(twin.measured, with, Options());
  EXPECT_EQ(scored.summary.verdict, Verdict::kInconsistent);
  EXPECT_GT(Phase(scored.summary, "ejection").mean_d2, 20.0);
}

TEST(SimEnsembleTest, RefusesOneMemberAnotherNetAndAShortRun) {
  Twin twin = MakeTwin(2);
  std::vector<EnsembleMember> one = {twin.members[0]};
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", one);
    FAIL() << "one member accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 2 runs"), std::string::npos) << e.what();
  }
  std::vector<EnsembleMember> other = twin.members;
  other[1].tracks.grid[3] = {9, 9};
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", other);
    FAIL() << "another net accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("member 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("same net"), std::string::npos) << e.what();
  }
  std::vector<EnsembleMember> short_run = twin.members;
  KnotTracks& t = short_run[0].tracks;
  t.time.resize(90);
  t.position.resize(90 * t.knots());
  t.valid.resize(90 * t.knots());
  try {
    AddEnsembleCovariance(twin.model, "sim.h5", short_run);
    FAIL() << "a short run accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("member 0: covers"), std::string::npos) << e.what();
  }
}

// A sweep file of two finished runs of a 2-knot net, 3 frames each: run 0 in metres and seconds,
// run 1 the same motion in millimetres and milliseconds; `time_frames` the length of run 1's
// /time (3: as its positions).
std::string WriteSweep(const std::string& name, hsize_t time_frames) {
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / ("sim_ensemble_" + name + ".h5")).string();
  std::lock_guard<std::mutex> lock(h5::Mutex());
  const h5::Id file = h5::CreateFile(path);
  h5::WriteStringAttribute(file.get(), "format", "netlab-sweep");
  h5::Id knots = h5::CreateGroup(file.get(), "knots");
  const int grid[2][2] = {{0, 0}, {0, 1}};
  h5::WriteDataset(knots.get(), "grid", H5T_NATIVE_INT, {2, 2}, grid);
  h5::Id tracks = h5::CreateGroup(file.get(), "tracks");
  for (int run = 0; run < 2; ++run) {
    const double to_unit = run == 0 ? 1.0 : 1e3;
    h5::Id g = h5::CreateGroup(tracks.get(), std::to_string(run));
    h5::WriteStringAttribute(g.get(), "status", "ok");
    const hsize_t frames = run == 0 ? 3 : time_frames;
    std::vector<double> time(frames);
    for (hsize_t f = 0; f < frames; ++f) time[f] = 0.01 * static_cast<double>(f) * to_unit;
    h5::WriteDataset(g.get(), "time", H5T_NATIVE_DOUBLE, {frames}, time.data());
    h5::SetUnits(g.get(), "time", run == 0 ? "s" : "ms");
    h5::Id k = h5::CreateGroup(g.get(), "knots");
    std::vector<double> position(3 * 2 * 3);
    for (int f = 0; f < 3; ++f)
      for (int knot = 0; knot < 2; ++knot)
        for (int axis = 0; axis < 3; ++axis)
          position[(f * 2 + knot) * 3 + axis] = (0.1 * knot + 0.02 * f + 0.001 * axis) * to_unit;
    h5::WriteDataset(k.get(), "position", H5T_NATIVE_DOUBLE, {3, 2, 3}, position.data());
    h5::SetUnits(k.get(), "position", run == 0 ? "m" : "mm");
  }
  return path;
}

// A sweep's runs are read in the units the file states, and a run whose /time does not match its
// positions' frames is refused by name before anything is read into memory.
TEST(SimEnsembleTest, ReadsASweepsRunsInTheirUnitsAndRefusesATimeOfAnotherLength) {
  const std::vector<EnsembleMember> members = ReadEnsemble(WriteSweep("units", 3));
  ASSERT_EQ(members.size(), 2u);
  for (int f = 0; f < 3; ++f) {
    EXPECT_NEAR(members[1].tracks.time[f], members[0].tracks.time[f], 1e-12) << "frame " << f;
    for (int k = 0; k < 2; ++k)
      EXPECT_LT(
          (members[1].tracks.position[f * 2 + k] - members[0].tracks.position[f * 2 + k]).norm(),
          1e-12)
          << "frame " << f << " knot " << k;
  }
  EXPECT_NEAR(members[0].tracks.position[5].x(), 0.14, 1e-12);  // frame 2, knot 1, in metres
  try {
    ReadEnsemble(WriteSweep("long_time", 1000));
    FAIL() << "a /time of 1000 frames for 3 frames of positions accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/tracks/1/time: missing or not [3]"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace netlab::netsim
