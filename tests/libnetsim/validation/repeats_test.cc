#include "libnetsim/validation/repeats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "common/errors.h"
#include "tests/libnetsim/validation/score_test_data.h"

namespace netlab::netsim {
namespace {

constexpr double kFps = 179.0;
constexpr double kNoise = 3e-4;  // m per axis

// The true net and the same one without air drag, simulated once for the whole file.
class Repeats : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    testing::DragModels models = testing::SimulateDragModels();
    right_ = new KnotTracks(std::move(models.right));
    wrong_ = new KnotTracks(std::move(models.wrong));
  }
  static void TearDownTestSuite() {
    delete right_;
    delete wrong_;
  }

  // A shot of the true net: its launch `tau` s after the simulation's t = 0 on the measured
  // clock (t_sim = t_meas + tau), measured with kNoise per axis from noise seed `seed`.
  static KnotTracks Shot(double tau, unsigned seed) {
    KnotTracks meas = *right_;
    for (double& t : meas.time) t -= tau;
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal(0.0, kNoise);
    for (auto& p : meas.position) p += Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    meas.covariance.assign(meas.position.size(), Eigen::Matrix3d::Identity() * kNoise * kNoise);
    return meas;
  }

  static KnotTracks* right_;
  static KnotTracks* wrong_;
};
KnotTracks* Repeats::right_ = nullptr;
KnotTracks* Repeats::wrong_ = nullptr;

// Three shots with their own launch times and noise seeds: the pooled test accepts the true model
// and rejects the one without drag; each shot's offset is its own; the spread between the shots
// is the noise put in, sqrt(3) x 0.3 mm.
TEST_F(Repeats, ThreeTwinsPoolTheTestFindTheirOwnOffsetsAndSpreadByTheirNoise) {
  const double taus[3] = {0.0, 3 / kFps, -2 / kFps};
  const KnotTracks shots[3] = {Shot(taus[0], 21), Shot(taus[1], 22), Shot(taus[2], 23)};
  const std::vector<const KnotTracks*> measured = {&shots[0], &shots[1], &shots[2]};
  const std::vector<std::string> names = {"a.h5", "b.h5", "c.h5"};

  const RepeatsResult good = ScoreRepeats(measured, names, *right_, ScoreOptions{}, "right.h5");
  const RepeatsResult bad = ScoreRepeats(measured, names, *wrong_, ScoreOptions{}, "wrong.h5");
  ASSERT_EQ(good.shots.size(), 3u);
  EXPECT_EQ(good.summary.verdict, Verdict::kConsistent) << good.combined.summary.BriefReport();
  EXPECT_EQ(bad.summary.verdict, Verdict::kInconsistent) << bad.combined.summary.BriefReport();
  EXPECT_GT(good.summary.margin, 0.0);
  EXPECT_LT(bad.summary.margin, 0.0);
  EXPECT_NEAR(good.summary.mean_d2, 3.0, 0.3);
  // The combined summary carries the pooled test; the rest is the first shot's.
  EXPECT_EQ(good.combined.summary.verdict, good.summary.verdict);
  EXPECT_EQ(good.combined.summary.dof, good.summary.dof);
  EXPECT_EQ(good.combined.summary.rms_m, good.shots[0].summary.rms_m);

  double dof = 0.0;
  int points = 0;
  for (int i = 0; i < 3; ++i) {
    const ScoreSummary& s = good.shots[i].summary;
    EXPECT_EQ(s.verdict, Verdict::kConsistent) << names[i] << "\n" << s.BriefReport();
    // Each shot's own offset, to a fraction of a millisecond (a frame is 5.6 ms).
    EXPECT_NEAR(s.time_offset_s, taus[i], 2e-4) << names[i];
    EXPECT_LT(std::abs(s.time_offset_s - taus[i]), 4 * s.time_offset_sigma_s + 2e-5) << names[i];
    dof += s.dof;
    points += s.points;
  }
  EXPECT_EQ(good.summary.dof, dof);
  EXPECT_EQ(good.summary.points, points);

  // The spread: noise only, sqrt(3) sigma in 3-D, over every knot-frame the shots share.
  const double expected = std::sqrt(3.0) * kNoise;
  EXPECT_GT(good.summary.spread.points, 0.9 * good.shots[0].summary.points);
  EXPECT_NEAR(good.summary.spread.rms_m, expected, 0.05 * expected);
  for (const SpreadRow& row : good.summary.spread_per_class)
    EXPECT_NEAR(row.rms_m, expected, 0.1 * expected) << row.name;
  ASSERT_EQ(good.summary.spread_per_phase.size(), good.shots[0].summary.per_phase.size());
  for (const SpreadRow& row : good.summary.spread_per_phase) {
    if (row.points >= 100) {
      EXPECT_NEAR(row.rms_m, expected, 0.15 * expected) << row.name;
    }
  }
  // The spread does not depend on the model scored against, the model's error does.
  EXPECT_NEAR(bad.summary.spread.rms_m, good.summary.spread.rms_m, 0.05 * expected);
  EXPECT_GT(bad.summary.spread.error_rms_m, 2 * good.summary.spread.error_rms_m);
}

// Shots moved apart along x by a known amount: the spread is that amount, not the noise.
TEST_F(Repeats, TheSpreadIsTheDistanceBetweenTheShots) {
  KnotTracks shots[3] = {Shot(0.0, 31), Shot(0.0, 32), Shot(0.0, 33)};
  const double shift = 5e-3;  // m: shot 1 at -shift, shot 2 at +shift along y
  for (auto& p : shots[1].position) p.y() -= shift;
  for (auto& p : shots[2].position) p.y() += shift;
  RepeatsSummary r;
  {
    std::vector<ScoreResult> scored;
    ScoreOptions options;
    options.alignment = Alignment::kNone;
    for (const KnotTracks& shot : shots) scored.push_back(Score(shot, *right_, options));
    r = PoolRepeats({&shots[0], &shots[1], &shots[2]}, {"a", "b", "c"}, scored, options);
  }
  // Offsets 0, -s, +s about their mean: sum of squares 2 s^2 over n - 1 = 2, plus the noise.
  const double expected = std::sqrt(shift * shift + 3 * kNoise * kNoise);
  EXPECT_NEAR(r.spread.rms_m, expected, 0.02 * expected);
  // Moved 5 mm, the shots are not the simulation: rejected together.
  EXPECT_EQ(r.verdict, Verdict::kInconsistent);
}

// Frames [first, last) of a shot.
KnotTracks Frames(const KnotTracks& shot, int first, int last) {
  KnotTracks cut = shot;
  const size_t k = static_cast<size_t>(shot.knots());
  auto slice = [&](auto& v) { v.assign(v.begin() + first * k, v.begin() + last * k); };
  cut.time.assign(shot.time.begin() + first, shot.time.begin() + last);
  slice(cut.position);
  slice(cut.valid);
  slice(cut.covariance);
  return cut;
}

// Shots filmed over other stretches of the flight, scored against the model without drag: its
// error grows over the flight, so each shot's fitted offset takes another share of it (0.9 ms
// apart on the demo's shots). The spread is taken with the shots aligned to each other, so it
// is their noise as against the true model, not the wrong model's offsets.
TEST_F(Repeats, TheSpreadOfShotsOverOtherStretchesDoesNotDependOnTheModel) {
  const int frames = right_->frames();
  const KnotTracks whole = Shot(0.0, 71);
  const KnotTracks shots[3] = {Frames(whole, 0, frames - 40),
                               Frames(Shot(0.0, 72), 20, frames - 20),
                               Frames(Shot(0.0, 73), 40, frames)};
  const std::vector<const KnotTracks*> measured = {&shots[0], &shots[1], &shots[2]};
  const std::vector<std::string> names = {"a.h5", "b.h5", "c.h5"};
  const RepeatsResult good = ScoreRepeats(measured, names, *right_, ScoreOptions{}, "right.h5");
  const RepeatsResult bad = ScoreRepeats(measured, names, *wrong_, ScoreOptions{}, "wrong.h5");
  const double expected = std::sqrt(3.0) * kNoise;
  EXPECT_NEAR(good.summary.spread.rms_m, expected, 0.05 * expected);
  EXPECT_NEAR(bad.summary.spread.rms_m, expected, 0.05 * expected);
  // The wrong model's offsets differ from shot to shot (by 2.8 frames); the shots' own
  // alignment does not.
  const double apart = bad.shots[2].summary.time_offset_s - bad.shots[0].summary.time_offset_s;
  EXPECT_GT(std::abs(apart), 1e-4);
  ASSERT_EQ(bad.summary.spread_time_offset_s.size(), 3u);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(bad.summary.spread_time_offset_s[i], 0.0, 5e-5) << names[i];
}

// A shot the model misses is not outvoted by one whose covariances are too large. Summing each
// shot's chi^2 over its own correlation inflation gave the well-behaved shot (uncorrelated
// noise, c ~ 1.3, its sigma stated twice too large: mean d2 0.77) the weight to cancel the
// other's excess (an error over the whole flight, c ~ 390: mean d2 14.7, p 2e-12): pooled p = 1.
// As on docs/score.md's repeats launched 1 % apart. Fisher's combination of the p-values
// rejects.
TEST_F(Repeats, AShotTheModelMissesIsNotOutvotedByOneWithTooLargeCovariances) {
  KnotTracks loose = Shot(0.0, 81);
  for (Eigen::Matrix3d& c : loose.covariance) c *= 4.0;
  // Launched a little faster sideways than the model: an error growing over the flight, the
  // same in every knot (3 mm/s, 1.8 mm at 0.6 s), correlated over time and across the net.
  KnotTracks shifted = Shot(0.0, 82);
  for (int t = 0; t < shifted.frames(); ++t)
    for (int k = 0; k < shifted.knots(); ++k)
      shifted.position[static_cast<size_t>(t) * shifted.knots() + k].y() += 3e-3 * shifted.time[t];
  const RepeatsResult r =
      ScoreRepeats({&loose, &shifted}, {"loose.h5", "shifted.h5"}, *right_, ScoreOptions{});
  ASSERT_EQ(r.shots.size(), 2u);
  EXPECT_EQ(r.shots[0].summary.verdict, Verdict::kConsistent);
  EXPECT_EQ(r.shots[1].summary.verdict, Verdict::kInconsistent);
  EXPECT_LT(r.shots[0].summary.mean_d2, 1.0);
  EXPECT_EQ(r.summary.verdict, Verdict::kInconsistent) << "pooled p " << r.summary.p_value;
  EXPECT_LT(r.summary.margin, 0.0);
  // Where the pooled test flips: every shot's d2 scaled alike to the critical mean d2 gives p at
  // the significance.
  EXPECT_GT(r.summary.critical_mean_d2, 0.0);
  EXPECT_LT(r.summary.critical_mean_d2, r.summary.mean_d2);
}

// One shot pooled is that shot's test.
TEST_F(Repeats, OneShotPooledIsItsOwnTest) {
  const KnotTracks shot = Shot(1 / kFps, 41);
  const std::vector<ScoreResult> scored = {Score(shot, *right_, ScoreOptions{})};
  const RepeatsSummary r = PoolRepeats({&shot}, {"a"}, scored, ScoreOptions{});
  const ScoreSummary& s = scored[0].summary;
  EXPECT_NEAR(r.p_value, s.p_value, 1e-12);
  EXPECT_NEAR(r.mean_d2, s.mean_d2, 1e-12);
  EXPECT_NEAR(r.critical_mean_d2, s.critical_mean_d2, 1e-9 * s.critical_mean_d2);
  EXPECT_EQ(r.verdict, s.verdict);
  EXPECT_EQ(r.spread.points, 0);
  EXPECT_TRUE(std::isnan(r.spread.rms_m));
}

std::string ErrorOf(const std::vector<const KnotTracks*>& measured, const KnotTracks& sim) {
  std::vector<std::string> names;
  for (size_t i = 0; i < measured.size(); ++i) names.push_back(std::string(1, 'a' + i) + ".h5");
  try {
    ScoreRepeats(measured, names, sim, ScoreOptions{}, "sim.h5");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST_F(Repeats, RepeatsOfDifferentNetsAreRefusedNamingBothFilesAndTheKnot) {
  const KnotTracks a = Shot(0.0, 51);
  KnotTracks b = Shot(0.0, 52);
  b.grid[7] = {9, 9};
  std::string error = ErrorOf({&a, &b}, *right_);
  EXPECT_NE(error.find("b.h5 is not a repeat of a.h5"), std::string::npos) << error;
  EXPECT_NE(error.find("knot 7 is (9,9) of net 0, in a.h5 (1,2) of net 0"), std::string::npos)
      << error;

  // Another net size.
  KnotTracks c = Shot(0.0, 53);
  c.grid.pop_back();
  c.valid.clear();
  std::vector<Eigen::Vector3d> positions;
  for (int t = 0; t < a.frames(); ++t)
    for (int k = 0; k < 24; ++k) {
      positions.push_back(a.Position(t, k));
      c.valid.push_back(1);
    }
  c.position = positions;
  c.covariance.resize(positions.size());
  error = ErrorOf({&a, &a, &c}, *right_);
  EXPECT_NE(error.find("c.h5 is not a repeat of a.h5: it has 24 knots, a.h5 25"), std::string::npos)
      << error;
}

TEST_F(Repeats, AShotOutsideTheSimulationsTimeIsRefusedNamingIt) {
  const KnotTracks a = Shot(0.0, 61);
  const KnotTracks b = Shot(-5.0, 62);  // launched 5 s after the simulation ends
  const std::string error = ErrorOf({&a, &b}, *right_);
  EXPECT_NE(error.find("no overlap in time"), std::string::npos) << error;
  EXPECT_NE(error.find("b.h5 spans 5"), std::string::npos) << error;
  EXPECT_NE(error.find("sim.h5 0"), std::string::npos) << error;
}

}  // namespace
}  // namespace netlab::netsim
