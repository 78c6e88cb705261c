#include "libnetsim/validation/score.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "tests/libnetsim/validation/score_test_data.h"

namespace netlab::netsim {
namespace {

constexpr double kFps = 179.0;

// A smooth made-up flight of a rows x cols net (m, s): it translates along x, opens and closes,
// and ripples, so that a time shift changes the shape and is not only a translation.
Eigen::Vector3d Flight(int row, int col, double t) {
  const double open = 1.0 + 0.3 * t - 0.25 * t * t;
  return {0.5 * t + 0.02 * std::sin(3.0 * t + 0.3 * row),
          (col - 5) * 0.1 * open + 0.01 * std::cos(4.0 * t + col),
          (row - 5) * 0.1 * open + 0.01 * std::sin(5.0 * t + 0.2 * col)};
}

// Knot tracks of Flight at times t0 + i / fps, i < frames.
KnotTracks MakeTracks(int rows, int cols, int frames, double t0, double fps = kFps) {
  KnotTracks tracks;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) tracks.grid.push_back({r, c});
  for (int i = 0; i < frames; ++i) {
    tracks.time.push_back(t0 + i / fps);
    tracks.frame_index.push_back(i);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        tracks.position.push_back(Flight(r, c, tracks.time.back()));
        tracks.valid.push_back(1);
      }
  }
  return tracks;
}

// The measured tracks of the simulation `sim_of`: frames at i / fps, simulated time i / fps +
// tau, seen through meas_from_sim, with Gaussian noise of covariance `cov` (stored).
KnotTracks Measure(int rows, int cols, int frames, double tau,
                   const Eigen::Isometry3d& meas_from_sim, const Eigen::Matrix3d& cov,
                   std::mt19937* rng) {
  KnotTracks m = MakeTracks(rows, cols, frames, 0.0);
  const Eigen::Matrix3d l = cov.llt().matrixL();
  std::normal_distribution<double> normal;
  for (int i = 0; i < frames; ++i)
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        const size_t j = static_cast<size_t>(i) * rows * cols + r * cols + c;
        Eigen::Vector3d noise = Eigen::Vector3d::Zero();
        if (rng) noise = l * Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
        m.position[j] = meas_from_sim * Flight(r, c, m.time[i] + tau) + noise;
        m.covariance.push_back(cov);
      }
  return m;
}

TEST(Score, SimulationAgainstItselfIsZero) {
  const KnotTracks sim = MakeTracks(11, 11, 120, 0.0);
  ScoreOptions options;
  options.meas_sigma_m = 1e-3;
  const ScoreResult result = Score(sim, sim, options);
  const ScoreSummary& s = result.summary;
  EXPECT_EQ(s.points, 11 * 11 * 120);
  EXPECT_EQ(s.knots, 121);
  EXPECT_EQ(s.frames, 120);
  EXPECT_LT(s.rms_m, 1e-12);
  EXPECT_LT(s.max_m, 1e-12);
  EXPECT_LT(s.mean_d2, 1e-18);
  EXPECT_NEAR(s.time_offset_s, 0.0, 1e-9);
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
  EXPECT_NEAR(s.skill, 1.0, 1e-9);
  EXPECT_EQ(s.per_class[0].points, 4 * 120);
  EXPECT_EQ(s.per_class[1].points, 36 * 120);
  EXPECT_EQ(s.per_class[2].points, 81 * 120);
  EXPECT_NEAR(s.side_m, 1.0, 0.03);  // the ripple lengthens or shortens the first row
  EXPECT_EQ(s.sim_uncertainty, "zero");
}

TEST(Score, RecoversAKnownTimeShiftToAFractionOfAMillisecond) {
  const KnotTracks sim = MakeTracks(11, 11, 200, 0.0);
  const double tau = 0.0234;                                       // 4.19 frames: not a whole frame
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-8;  // 0.1 mm
  const KnotTracks meas = Measure(11, 11, 150, tau, Eigen::Isometry3d::Identity(), cov, nullptr);
  ScoreOptions options;
  options.alignment = Alignment::kTime;
  const ScoreSummary s = Score(meas, sim, options).summary;
  EXPECT_NEAR(s.time_offset_s, tau, 1e-5);
  EXPECT_GT(s.time_offset_sigma_s, 0.0);
  EXPECT_LT(s.rms_m, 1e-5);
  EXPECT_EQ(s.fitted_parameters, 1);
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
}

TEST(Score, RecoversAKnownRigidMotionAndTimeShift) {
  const KnotTracks sim = MakeTracks(11, 11, 200, 0.0);
  const double tau = -0.0171;
  Eigen::Isometry3d meas_from_sim = Eigen::Isometry3d::Identity();
  meas_from_sim.linear() =
      Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  meas_from_sim.translation() = Eigen::Vector3d(0.12, -0.04, 0.31);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-8;
  const KnotTracks meas = Measure(11, 11, 150, tau, meas_from_sim, cov, nullptr);
  ScoreOptions options;
  options.alignment = Alignment::kTimeAndRigid;
  options.time_offset_s = 0.0;
  const ScoreSummary s = Score(meas, sim, options).summary;
  EXPECT_NEAR(s.time_offset_s, tau, 1e-4);
  const Eigen::AngleAxisd rotation_error(s.rotation * meas_from_sim.linear().transpose());
  EXPECT_LT(rotation_error.angle(), 1e-5);
  EXPECT_LT((s.translation - meas_from_sim.translation()).norm(), 1e-4);
  EXPECT_LT(s.rms_m, 1e-5);
  EXPECT_EQ(s.fitted_parameters, 7);
  EXPECT_GT(s.rigid_covariance(0, 0), 0.0);
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
}

TEST(Score, GaussianNoiseOfKnownCovarianceGivesMeanD2ThreeAndConsistent) {
  const KnotTracks sim = MakeTracks(11, 11, 200, 0.0);
  Eigen::Matrix3d cov;  // anisotropic and correlated: 0.5 to 2 mm, as triangulation gives
  cov << 4.0, 1.0, 0.5, 1.0, 1.0, 0.2, 0.5, 0.2, 0.5;
  cov *= 1e-6;
  std::mt19937 rng(7);
  const KnotTracks meas = Measure(11, 11, 150, 0.01, Eigen::Isometry3d::Identity(), cov, &rng);
  ScoreOptions options;
  const ScoreSummary s = Score(meas, sim, options).summary;
  EXPECT_NEAR(s.mean_d2, 3.0, 0.05);  // sd of the mean: sqrt(6 / 18150) = 0.018
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
  EXPECT_NEAR(s.time_offset_s, 0.01, 1e-4);
  EXPECT_LT(s.tau_int, 1.5);
  EXPECT_LT(s.design_effect, 1.5);
  EXPECT_GT(s.p_value, 0.01);
}

// Noise of 1 mm stated as 2 mm: the simulation is not rejected, but the too-large covariances are
// said, with their factor (2 in standard deviation: 100 %); stated right, nothing is said.
TEST(Score, OverstatedCovariancesAreSaid) {
  const KnotTracks sim = MakeTracks(11, 11, 200, 0.0);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-6;
  std::mt19937 rng(5);
  KnotTracks meas = Measure(11, 11, 150, 0.0, Eigen::Isometry3d::Identity(), cov, &rng);
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  const ScoreSummary right = Score(meas, sim, options).summary;
  EXPECT_FALSE(right.covariance_too_large);
  for (auto& c : meas.covariance) c *= 4.0;
  const ScoreSummary s = Score(meas, sim, options).summary;
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
  EXPECT_NEAR(s.mean_d2, 0.75, 0.03);
  EXPECT_TRUE(s.covariance_too_large);
  bool said = false;
  for (const auto& note : s.notes) said = said || note.find("by about 100 %") != std::string::npos;
  EXPECT_TRUE(said);
}

// The contact phase starts at the simulation's own first contact (netlab simulate stores it),
// in measured time (the offset taken off); a given time overrides it; without either there is no
// contact phase.
TEST(Score, TheContactPhaseStartsAtTheSimulationsFirstContact) {
  KnotTracks sim = MakeTracks(5, 5, 200, 0.0);
  const KnotTracks meas = Measure(5, 5, 150, 0.01, Eigen::Isometry3d::Identity(),
                                  Eigen::Matrix3d::Identity() * 1e-8, nullptr);
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  options.time_offset_s = 0.01;
  auto contact = [](const ScoreSummary& s) { return s.per_phase.back(); };
  const ScoreSummary none = Score(meas, sim, options).summary;
  EXPECT_EQ(none.contact_from, ContactFrom::kNone);
  EXPECT_EQ(contact(none).points, 0);

  sim.contact_start_s = 0.5;
  const ScoreSummary from_sim = Score(meas, sim, options).summary;
  EXPECT_EQ(from_sim.contact_from, ContactFrom::kSimulation);
  EXPECT_EQ(from_sim.contact_time_s, 0.5);
  EXPECT_EQ(contact(from_sim).name, "contact");
  EXPECT_NEAR(contact(from_sim).start_s, 0.49, 1e-9);
  // Measured frames from 0.49 s to the last (149 / 179 s): 62 frames of 25 knots.
  EXPECT_EQ(contact(from_sim).points, 25 * (149 - static_cast<int>(std::ceil(0.49 * kFps)) + 1));

  options.contact_time_s = 0.3;
  const ScoreSummary given = Score(meas, sim, options).summary;
  EXPECT_EQ(given.contact_from, ContactFrom::kGiven);
  EXPECT_NEAR(contact(given).start_s, 0.29, 1e-9);
}

// The verdict's false-rejection rate is the stated significance: 200 noisy measurements of a right
// simulation at significance 0.1 are rejected 20 times on average (binomial sd 4.2).
TEST(Score, RejectsARightSimulationAtTheStatedRate) {
  const KnotTracks sim = MakeTracks(5, 5, 80, 0.0);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-6;
  std::mt19937 rng(11);
  ScoreOptions options;
  options.significance = 0.1;
  int rejected = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const KnotTracks meas = Measure(5, 5, 60, 0.02, Eigen::Isometry3d::Identity(), cov, &rng);
    rejected += Score(meas, sim, options).summary.verdict == Verdict::kInconsistent;
  }
  EXPECT_GE(rejected, 8);
  EXPECT_LE(rejected, 34);
}

TEST(Score, MissingKnotsAreMaskedNotFilled) {
  const KnotTracks sim = MakeTracks(11, 11, 100, 0.0);
  KnotTracks meas = Measure(11, 11, 80, 0.0, Eigen::Isometry3d::Identity(),
                            Eigen::Matrix3d::Identity() * 1e-8, nullptr);
  meas.valid[5 * 121 + 7] = 0;
  meas.position[5 * 121 + 7] = Eigen::Vector3d::Constant(std::nan(""));  // never read
  meas.valid[6 * 121 + 0] = 0;
  const ScoreResult r = Score(meas, sim, ScoreOptions{});
  EXPECT_EQ(r.summary.points, 80 * 121 - 2);
  EXPECT_EQ(r.summary.masked, 2);
  EXPECT_EQ(r.compared[5 * 121 + 7], 0);
  EXPECT_TRUE(std::isnan(r.d2[5 * 121 + 7]));
  EXPECT_TRUE(std::isnan(r.area_measured[6]));  // corner (0,0) missing
  EXPECT_TRUE(std::isfinite(r.area_simulated[6]));
}

// The demo's case: two points whose rays met head-on, with a sigma of metres and an error to
// match. d2 weighs them rightly; the errors in millimetres, the tables and the plots' series
// leave them out, and the headline says how many and why. Degenerate points of the file are
// masked and counted.
TEST(Score, PointsOfHugeSigmaLeaveTheErrorsInMillimetresButNotTheTest) {
  std::mt19937 rng(8);
  const KnotTracks sim = MakeTracks(11, 11, 100, 0.0);
  const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * 1e-8;  // 0.1 mm
  KnotTracks meas = Measure(11, 11, 80, 0.0, Eigen::Isometry3d::Identity(), cov, &rng);
  // Knot (10,0) of frame 1 and (10,10) of frame 2: 2.5 m sigma along x, 2 m off along x.
  const size_t a = 1 * 121 + 110, b = 2 * 121 + 120;
  Eigen::Matrix3d huge = cov;
  huge(0, 0) = 2.5 * 2.5;
  for (size_t i : {a, b}) {
    meas.covariance[i] = huge;
    meas.position[i].x() += 2.0;
  }
  // Knot (5,5) of frame 3 flagged degenerate by the triangulation.
  meas.degenerate.assign(meas.valid.size(), 0);
  meas.degenerate[3 * 121 + 60] = 1;
  meas.valid[3 * 121 + 60] = 0;
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  const ScoreResult r = Score(meas, sim, options);
  const ScoreSummary& s = r.summary;
  EXPECT_EQ(s.points, 80 * 121 - 1);
  EXPECT_EQ(s.left_out, 2);
  EXPECT_EQ(s.degenerate, 1);
  EXPECT_EQ(s.masked, 1);
  EXPECT_TRUE(r.compared[a]);
  EXPECT_FALSE(r.informative[a]);
  EXPECT_NEAR(s.median_sigma_m, 1e-4, 1e-9);
  EXPECT_NEAR(s.sigma_bound_m, 1e-3, 1e-8);
  EXPECT_NEAR(s.left_out_max_sigma_m, 2.5, 1e-9);
  // The errors are the noise's: 0.1 mm per axis.
  EXPECT_LT(s.rms_m, 2.5e-4);
  EXPECT_LT(s.max_m, 1e-3);
  EXPECT_LT(s.per_class[0].rms_m, 2.5e-4);  // (10,0) and (10,10) are corners
  EXPECT_EQ(s.per_class[0].left_out, 2);
  for (const auto& frame : r.rms_per_class) EXPECT_FALSE(frame[0] > 1e-3);
  EXPECT_LT(s.weighted_rms_m, 2.5e-4);
  // d2 keeps them, weighed by their covariance: consistent.
  EXPECT_EQ(s.verdict, Verdict::kConsistent);
  EXPECT_NEAR(s.mean_d2, 3.0, 0.2);
  EXPECT_NE(s.headline.find("over 9677 of the 9679 compared knot-frames; 2 left out of both "
                            "because their own sigma (up to 2500 mm) exceeds"),
            std::string::npos)
      << s.headline;
  EXPECT_NE(s.headline.find("they count in d2 only; 1 more flagged degenerate"), std::string::npos)
      << s.headline;
  EXPECT_NE(s.headline.find("covariance-weighted RMS"), std::string::npos) << s.headline;
  EXPECT_NE(s.BriefReport().find(s.headline), std::string::npos);

  // Without any such point the headline says all were used.
  const ScoreResult clean =
      Score(Measure(11, 11, 80, 0.0, Eigen::Isometry3d::Identity(), cov, &rng), sim, options);
  EXPECT_EQ(clean.summary.left_out, 0);
  EXPECT_NE(clean.summary.headline.find("over all 9680 compared knot-frames (every sigma within"),
            std::string::npos)
      << clean.summary.headline;
  EXPECT_EQ(clean.summary.headline.find("weighted"), std::string::npos) << clean.summary.headline;
}

// A wrong model: the real net (made by the simulator) against one with no air drag, measured
// with 0.3 mm noise.
TEST(Score, APerturbedSimulationIsRejectedAndTheRightOneIsNot) {
  const auto [right, wrong] = testing::SimulateDragModels();
  KnotTracks meas = right;
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 3e-4);
  for (auto& p : meas.position) p += Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  meas.covariance.assign(meas.position.size(), Eigen::Matrix3d::Identity() * 9e-8);
  const ScoreSummary good = Score(meas, right, ScoreOptions{}).summary;
  const ScoreSummary bad = Score(meas, wrong, ScoreOptions{}).summary;
  EXPECT_EQ(good.verdict, Verdict::kConsistent) << good.BriefReport();
  EXPECT_EQ(bad.verdict, Verdict::kInconsistent) << bad.BriefReport();
  EXPECT_LT(bad.margin, 0.0);
  EXPECT_GT(good.margin, 0.0);
  EXPECT_GT(good.skill, bad.skill);
}

std::string ErrorOf(const KnotTracks& meas, const KnotTracks& sim, ScoreOptions options = {}) {
  try {
    Score(meas, sim, options, "tracks.h5", "sim.h5");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Score, DifferentNetsAreAGridMismatchNamingTheKnot) {
  const KnotTracks sim = MakeTracks(11, 10, 100, 0.0);
  const KnotTracks meas = Measure(11, 11, 50, 0.0, Eigen::Isometry3d::Identity(),
                                  Eigen::Matrix3d::Identity() * 1e-6, nullptr);
  const std::string error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("grid mismatch"), std::string::npos) << error;
  EXPECT_NE(error.find("(0,10)"), std::string::npos) << error;
  EXPECT_NE(error.find("sim.h5"), std::string::npos) << error;
}

TEST(Score, NoOverlapInTimeSaysBothSpans) {
  const KnotTracks sim = MakeTracks(11, 11, 100, 5.0);
  const KnotTracks meas = Measure(11, 11, 50, 0.0, Eigen::Isometry3d::Identity(),
                                  Eigen::Matrix3d::Identity() * 1e-6, nullptr);
  const std::string error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("no overlap in time"), std::string::npos) << error;
  EXPECT_NE(error.find("tracks.h5 spans 0"), std::string::npos) << error;
  EXPECT_NE(error.find("sim.h5 5"), std::string::npos) << error;
}

TEST(Score, NaNInAValidMeasurementNamesFrameAndKnot) {
  const KnotTracks sim = MakeTracks(11, 11, 100, 0.0);
  KnotTracks meas = Measure(11, 11, 50, 0.0, Eigen::Isometry3d::Identity(),
                            Eigen::Matrix3d::Identity() * 1e-6, nullptr);
  meas.position[3 * 121 + 2 * 11 + 4].y() = std::nan("");
  const std::string error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("tracks.h5: /knots/position is not a number at frame 3"), std::string::npos)
      << error;
  EXPECT_NE(error.find("knot (2,4)"), std::string::npos) << error;
}

TEST(Score, NaNInTheSimulationNamesFrameAndKnot) {
  KnotTracks sim = MakeTracks(11, 11, 100, 0.0);
  sim.position[40 * 121 + 120].x() = std::nan("");
  const KnotTracks meas = Measure(11, 11, 50, 0.0, Eigen::Isometry3d::Identity(),
                                  Eigen::Matrix3d::Identity() * 1e-6, nullptr);
  const std::string error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("sim.h5: /knots/position is not a number at frame 40"), std::string::npos)
      << error;
  EXPECT_NE(error.find("knot (10,10)"), std::string::npos) << error;
}

TEST(Score, ACovarianceThatIsNotPositiveDefiniteNamesFrameAndKnot) {
  const KnotTracks sim = MakeTracks(11, 11, 100, 0.0);
  KnotTracks meas = Measure(11, 11, 50, 0.0, Eigen::Isometry3d::Identity(),
                            Eigen::Matrix3d::Identity() * 1e-6, nullptr);
  meas.covariance[7 * 121 + 1].diagonal() << 1e-6, -1e-6, 1e-6;
  std::string error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("tracks.h5: /knots/covariance is not symmetric positive definite at "
                       "frame 7"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("knot (0,1)"), std::string::npos) << error;
  meas.covariance[7 * 121 + 1] = Eigen::Matrix3d::Identity() * 1e-6;
  meas.covariance[9 * 121 + 1](0, 1) = 5e-7;  // not symmetric
  error = ErrorOf(meas, sim);
  EXPECT_NE(error.find("not symmetric positive definite at frame 9"), std::string::npos) << error;
}

TEST(Score, MeasuredTracksWithoutCovarianceNeedASigma) {
  const KnotTracks sim = MakeTracks(5, 5, 100, 0.0);
  const std::string error = ErrorOf(sim, sim);
  EXPECT_NE(error.find("tracks.h5: no /knots/covariance"), std::string::npos) << error;
}

TEST(Score, ASparseSimulationIsSaidToBe) {
  // Stored at 10 fps, measured at 179 fps with 0.01 mm noise: the cubic's error shows.
  const KnotTracks sim = MakeTracks(5, 5, 12, 0.0, 10.0);
  const KnotTracks meas = Measure(5, 5, 150, 0.0, Eigen::Isometry3d::Identity(),
                                  Eigen::Matrix3d::Identity() * 1e-10, nullptr);
  ScoreOptions options;
  options.alignment = Alignment::kNone;
  const ScoreSummary s = Score(meas, sim, options).summary;
  EXPECT_TRUE(s.sim_too_sparse);
  ASSERT_FALSE(s.notes.empty());
  EXPECT_NE(s.notes[0].find("too sparse"), std::string::npos);
}

TEST(Score, OptionsAreChecked) {
  ScoreOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error));
  options.significance = 1.5;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("significance"), std::string::npos);
  Alignment a;
  EXPECT_TRUE(ParseAlignment("time+rigid", &a));
  EXPECT_EQ(a, Alignment::kTimeAndRigid);
  EXPECT_FALSE(ParseAlignment("rigid+time", &a));
}

TEST(Chi2, MatchesPublishedQuantiles) {
  EXPECT_NEAR(Chi2Quantile(0.95, 3), 7.8147, 1e-3);  // chi^2 tables
  EXPECT_NEAR(Chi2Quantile(0.99, 10), 23.2093, 1e-3);
  EXPECT_NEAR(UpperGammaQ(1.5, 7.8147 / 2), 0.05, 1e-5);
  EXPECT_NEAR(UpperGammaQ(50, 124.342 / 2), 0.05, 1e-4);  // chi^2_100
  // Large dof: the normal limit, mean nu and sd sqrt(2 nu).
  const double nu = 1e6;
  EXPECT_NEAR(Chi2Quantile(0.8413447, nu), nu + std::sqrt(2 * nu), 5.0);
}

}  // namespace
}  // namespace netlab::netsim
