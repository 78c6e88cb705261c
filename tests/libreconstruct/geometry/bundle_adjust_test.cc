#include "libreconstruct/geometry/bundle_adjust.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/errors.h"

namespace netlab::recon {
namespace {

constexpr int kRows = 5, kCols = 5, kFrames = 30;
constexpr double kLink = 0.1, kFps = 179.0;

// A flat 5 x 5 net, 10 cm links, flying along +x at 0.5 m/s and slowly turning: every link keeps
// its length and the motion is smooth.
Eigen::Vector3d KnotAt(int t, int k) {
  const double s = t / kFps;
  const double angle = 0.3 * s;
  const Eigen::Vector3d local(0.0, (k % kCols - 2) * kLink, (k / kCols - 2) * kLink);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return Eigen::Vector3d(1.0 + 0.5 * s, 0.1, -0.05) + turn * local;
}

// The same net over 3.3 s (every 20th frame of 600), flying 1.7 m and folding: a volume that
// pins down the cameras' relative poses, which one flat patch at one place does not.
Eigen::Vector3d FoldingKnotAt(int t, int k) {
  const double s = 20 * t / kFps;
  const Eigen::Vector3d flat = KnotAt(0, k) - Eigen::Vector3d(1.0, 0.1, -0.05);
  const double fold = 0.4 * std::sin(1.5 * s) * (flat.y() * flat.y() - flat.z() * flat.z()) / kLink;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.6 * s, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()).toRotationMatrix();
  return Eigen::Vector3d(0.2 + 0.5 * s, 0.1 * std::sin(s), -0.05) +
         turn * (flat + Eigen::Vector3d(fold, 0.0, 0.0));
}

LabelSet LabelAll(const calib::Rig& rig, double sigma, uint64_t seed,
                  Eigen::Vector3d (*knot_at)(int, int) = KnotAt) {
  std::vector<std::string> names;
  for (const auto& c : rig.cameras) names.push_back(c.name);
  std::vector<int> frames(kFrames);
  for (int t = 0; t < kFrames; ++t) frames[t] = 100 + t;
  LabelSet labels = LabelSet::Empty(kRows, kCols, names, frames);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (size_t c = 0; c < names.size(); ++c)
    for (int t = 0; t < kFrames; ++t)
      for (int k = 0; k < kRows * kCols; ++k) {
        Label& l = labels.at(static_cast<int>(c), t, k);
        l.px = rig.cameras[c].ProjectWorld(knot_at(t, k)) + Eigen::Vector2d(noise(rng), noise(rng));
        l.source = LabelSource::kManual;
        l.confidence = 1.0f;
        l.state = LabelState::kAccepted;
      }
  return labels;
}

double RmsError(const SequenceResult& r, Eigen::Vector3d (*knot_at)(int, int) = KnotAt) {
  double ss = 0.0;
  int n = 0;
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) {
      const size_t i = static_cast<size_t>(t) * kRows * kCols + k;
      if (!r.valid[i]) continue;
      ss += (r.position[i] - knot_at(t, k)).squaredNorm();
      ++n;
    }
  return std::sqrt(ss / n);
}

TEST(ReconstructSequence, TriangulatesEveryKnotAndEstimatesTheNoise) {
  const calib::Rig rig = calib::PaperRig();
  const LabelSet labels = LabelAll(rig, 0.3, 1);
  SequenceOptions o;
  o.adjustment = Adjustment::kNone;
  const SequenceResult r = ReconstructSequence(rig, labels, o);
  EXPECT_EQ(r.triangulated, kFrames * kRows * kCols);
  EXPECT_EQ(r.candidates, r.triangulated);
  EXPECT_TRUE(r.outliers.empty());
  EXPECT_TRUE(r.sigma_estimated);
  EXPECT_NEAR(r.sigma_px, 0.3, 0.02);
  EXPECT_EQ(r.frame_index.front(), 100);
  // Errors agree with the reported covariances (mean squared Mahalanobis norm 3).
  double m2 = 0.0;
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) {
      const size_t i = static_cast<size_t>(t) * kRows * kCols + k;
      const Eigen::Vector3d e = r.position[i] - KnotAt(t, k);
      m2 += e.dot(r.covariance[i].ldlt().solve(e));
    }
  EXPECT_NEAR(m2 / (kFrames * kRows * kCols), 3.0, 0.3);
  EXPECT_LT(RmsError(r), 1e-3);
}

TEST(ReconstructSequence, AMislabeledObservationIsReportedWithItsFrameKnotAndCamera) {
  const calib::Rig rig = calib::PaperRig();
  LabelSet labels = LabelAll(rig, 0.2, 2);
  labels.at(2, 7, 12).px += Eigen::Vector2d(40.0, 10.0);
  SequenceOptions o;
  o.adjustment = Adjustment::kNone;
  const SequenceResult r = ReconstructSequence(rig, labels, o);
  ASSERT_EQ(r.outliers.size(), 1u);
  EXPECT_EQ(r.outliers[0].frame, 107);
  EXPECT_EQ(r.outliers[0].knot, 12);
  EXPECT_EQ(r.outliers[0].camera, 2);
  EXPECT_GT(r.outliers[0].residual_px, 30.0);
  const size_t i = 7 * kRows * kCols + 12;
  ASSERT_TRUE(r.valid[i]);
  EXPECT_LT((r.position[i] - KnotAt(7, 12)).norm(), 1e-3);
}

TEST(ReconstructSequence, OneViewLeavesAKnotUntriangulatedAndUnknownCamerasAreNamed) {
  const calib::Rig rig = calib::PaperRig();
  LabelSet labels = LabelAll(rig, 0.2, 3);
  for (int c = 1; c < 4; ++c) labels.at(c, 3, 4) = Label{};
  labels.at(3, 5, 6).state = LabelState::kNeedsReview;
  SequenceOptions o;
  o.adjustment = Adjustment::kNone;
  const SequenceResult r = ReconstructSequence(rig, labels, o);
  EXPECT_EQ(r.single_view, 1);
  EXPECT_FALSE(r.valid[3 * kRows * kCols + 4]);
  EXPECT_EQ(r.unreviewed_skipped, 1);
  EXPECT_EQ(r.triangulated, kFrames * kRows * kCols - 1);

  // A knot seen by cameras 0 and 1, with labels placed from theirs in 2 and 3: two views, not
  // four (those labels repeat the two), and they are counted apart.
  for (int c = 2; c < 4; ++c) labels.at(c, 4, 7).source = LabelSource::kProjected;
  const SequenceResult placed = ReconstructSequence(rig, labels, o);
  EXPECT_EQ(placed.projected_skipped, 2);
  EXPECT_EQ(placed.two_view, r.two_view + 1);
  EXPECT_EQ(placed.triangulated, r.triangulated);

  labels.cameras[1] = "cam7";
  try {
    ReconstructSequence(rig, labels, o);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cam7"), std::string::npos) << e.what();
  }
}

// Camera 1 turned (its distance to camera 0 is the gauge's scale and stays), cameras 2 and 3
// moved and turned, as a knock on the far stereo pair would.
calib::Rig Knocked(const calib::Rig& truth) {
  calib::Rig rig = truth;
  auto knock = [](calib::Camera* cam, const Eigen::Vector3d& axis, double deg,
                  const Eigen::Vector3d& shift) {
    const Eigen::Vector3d centre = cam->Center() + shift;
    const Eigen::Quaterniond r =
        Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180, axis.normalized())) *
        cam->cam_from_world.rotation;
    cam->cam_from_world = calib::Rigid3d(r, -(r * centre));
  };
  knock(&rig.cameras[1], {0, 0, 1}, 0.15, Eigen::Vector3d::Zero());
  knock(&rig.cameras[2], {1, 1, 0}, 0.2, {0.004, -0.003, 0.002});
  knock(&rig.cameras[3], {0, 1, 1}, -0.1, {-0.002, 0.005, 0.0});
  return rig;
}

void ExpectRigNear(const calib::Rig& got, const calib::Rig& truth, double deg, double m) {
  for (int c = 0; c < 4; ++c) {
    EXPECT_LT(got.cameras[c].cam_from_world.rotation.angularDistance(
                  truth.cameras[c].cam_from_world.rotation) *
                  180 / M_PI,
              deg)
        << c;
    EXPECT_LT((got.cameras[c].Center() - truth.cameras[c].Center()).norm(), m) << c;
  }
}

TEST(ReconstructSequence, RigAdjustmentRecoversDisturbedExtrinsicsExactlyWithoutNoise) {
  const calib::Rig truth = calib::PaperRig();
  SequenceOptions o;
  o.adjustment = Adjustment::kRig;
  const SequenceResult r =
      ReconstructSequence(Knocked(truth), LabelAll(truth, 0.0, 4, FoldingKnotAt), o);
  ASSERT_TRUE(r.rig_adjusted);
  ExpectRigNear(r.rig, truth, 1e-6, 1e-8);
  EXPECT_LT(r.rig_rms_after_px, 1e-6);
  EXPECT_LT(RmsError(r, FoldingKnotAt), 1e-8);
}

TEST(ReconstructSequence, RigAdjustmentWithNoiseFitsToTheNoiseAndHoldsTheGauge) {
  const calib::Rig truth = calib::PaperRig();
  const calib::Rig knocked = Knocked(truth);
  const LabelSet labels = LabelAll(truth, 0.2, 4, FoldingKnotAt);
  SequenceOptions o;
  o.adjustment = Adjustment::kNone;
  o.triangulation.outlier_threshold_px = 1e3;  // every view, as the knocked rig would say
  const double before = RmsError(ReconstructSequence(knocked, labels, o), FoldingKnotAt);
  o = SequenceOptions{};
  o.adjustment = Adjustment::kRig;
  const SequenceResult r = ReconstructSequence(knocked, labels, o);
  ASSERT_TRUE(r.rig_adjusted);
  EXPECT_GT(r.rig_rms_before_px, 5 * r.rig_rms_after_px);
  // Four views of 2 residuals each fit 3 point coordinates: E|r|^2 = (8 - 3) / 4 sigma^2.
  EXPECT_NEAR(r.rig_rms_after_px, 0.2 * std::sqrt(1.25), 0.015);
  // Narrow lenses 3-5 m from the net trade a camera's position against its turn: millimetres.
  ExpectRigNear(r.rig, truth, 0.01, 3e-3);
  // The held camera and the scale did not move.
  EXPECT_LT((r.rig.cameras[0].Center() - truth.cameras[0].Center()).norm(), 1e-12);
  EXPECT_NEAR((r.rig.cameras[1].Center() - r.rig.cameras[0].Center()).norm(),
              (truth.cameras[1].Center() - truth.cameras[0].Center()).norm(), 1e-9);
  EXPECT_LT(RmsError(r, FoldingKnotAt), before / 5);
  EXPECT_TRUE(r.outliers.empty());
}

TEST(ReconstructSequence, RigUncertaintyMatchesTheScatterAndAPoorSequenceKeepsTheRig) {
  const calib::Rig truth = calib::PaperRig();
  double z_centre = 0, z_rotation = 0;
  int n = 0;
  for (uint64_t seed = 10; seed < 30; ++seed) {
    SequenceOptions o;
    o.adjustment = Adjustment::kRig;
    const SequenceResult r =
        ReconstructSequence(Knocked(truth), LabelAll(truth, 0.2, seed, FoldingKnotAt), o);
    ASSERT_TRUE(r.rig_adjusted);
    for (int c = 1; c < 4; ++c) {
      const double centre = 1e3 * (r.rig.cameras[c].Center() - truth.cameras[c].Center()).norm();
      const double rotation = r.rig.cameras[c].cam_from_world.rotation.angularDistance(
                                  truth.cameras[c].cam_from_world.rotation) *
                              180 / M_PI;
      z_centre += std::pow(centre / r.rig_center_sigma_mm[c], 2);
      z_rotation += std::pow(rotation / r.rig_rotation_sigma_deg[c], 2);
      ++n;
    }
  }
  // (error / sigma)^2 averages 1 when the reported sigmas are right (measured: 0.74, 1.08).
  EXPECT_NEAR(z_centre / n, 1.0, 0.45);
  EXPECT_NEAR(z_rotation / n, 1.0, 0.45);

  // A flat patch 40 cm across moving 8 cm does not determine the far cameras: the calibrated
  // rig is kept, and the points are as good as without adjustment.
  SequenceOptions o;
  o.adjustment = Adjustment::kRig;
  const SequenceResult poor = ReconstructSequence(truth, LabelAll(truth, 0.2, 4), o);
  EXPECT_FALSE(poor.rig_adjusted);
  EXPECT_GT(poor.rig_center_sigma_mm[2], o.rig_max_center_sigma_mm);
  for (int c = 0; c < 4; ++c) EXPECT_EQ(poor.rig.cameras[c].Center(), truth.cameras[c].Center());
  o.adjustment = Adjustment::kNone;
  EXPECT_EQ(RmsError(poor), RmsError(ReconstructSequence(truth, LabelAll(truth, 0.2, 4), o)));
}

TEST(ReconstructSequence, PriorsPullTowardsTheTruthAndSayHowFar) {
  // Two distant views only (cam0 and cam1, 3 m away): depth is poorly determined, which the
  // link-length and smoothness priors help with.
  calib::Rig rig = calib::PaperRig();
  rig.cameras.resize(2);
  const LabelSet labels = LabelAll(rig, 0.5, 5);
  SequenceOptions o;
  o.adjustment = Adjustment::kPoints;
  const SequenceResult plain = ReconstructSequence(rig, labels, o);
  const double e0 = RmsError(plain);
  EXPECT_EQ(plain.link_shift_rms_m, 0.0);

  o.link_length_m = kLink;
  o.link_sigma_m = 0.0005;
  const SequenceResult link = ReconstructSequence(rig, labels, o);
  EXPECT_LT(RmsError(link), 0.8 * e0);
  EXPECT_GT(link.link_shift_rms_m, 0.0);
  EXPECT_GT(link.link_shift_max_m, link.link_shift_rms_m);

  o.link_length_m = 0.0;
  o.smoothness_sigma_m = 1e-5;  // constant velocity up to the slow turn: ~1e-6 m per frame^2
  const SequenceResult smooth = ReconstructSequence(rig, labels, o);
  EXPECT_LT(RmsError(smooth), 0.5 * e0);
  EXPECT_GT(smooth.smoothness_shift_rms_m, 0.0);
  // The covariances carry the prior's information over the whole run of frames: errors stay
  // within them (mean squared Mahalanobis norm near 3, none beyond 6 sigma).
  double m2 = 0.0, worst = 0.0;
  for (int t = 0; t < kFrames; ++t)
    for (int k = 0; k < kRows * kCols; ++k) {
      const size_t i = static_cast<size_t>(t) * kRows * kCols + k;
      const Eigen::Vector3d e = smooth.position[i] - KnotAt(t, k);
      const double d2 = e.dot(smooth.covariance[i].ldlt().solve(e));
      m2 += d2;
      worst = std::max(worst, d2);
    }
  // Measured 2.2 (the motion is smoother than the prior's sigma allows), worst 11.
  EXPECT_NEAR(m2 / (kFrames * kRows * kCols), 3.0, 1.5);
  EXPECT_LT(worst, 36.0);

  o.link_length_m = kLink;
  const SequenceResult both = ReconstructSequence(rig, labels, o);
  EXPECT_LT(RmsError(both), RmsError(smooth) * 1.05);
  EXPECT_NEAR(both.link_shift_rms_m, link.link_shift_rms_m, 1e-12);
  // A prior's information makes the reported uncertainty smaller.
  const size_t mid = 15 * kRows * kCols + 12;
  EXPECT_LT(both.covariance[mid].trace(), plain.covariance[mid].trace());
}

// Two views cannot see a mislabel along their epipolar line; the knot's track can: the
// smoothness prior pulls the point back and leaves its labels far off, so it is left out and
// its views reported.
TEST(ReconstructSequence, TheSmoothnessPriorCatchesATwoViewMislabelGeometryCannotSee) {
  calib::Rig rig = calib::PaperRig();
  rig.cameras.resize(2);
  LabelSet labels = LabelAll(rig, 0.2, 6);
  const int t = 14, k = 7;
  const Eigen::Vector3d c0 = rig.cameras[0].Center();
  const Eigen::Vector3d on_ray = c0 + 0.97 * (KnotAt(t, k) - c0);  // 8 cm nearer cam0
  labels.at(1, t, k).px = rig.cameras[1].ProjectWorld(on_ray);
  ASSERT_GT((labels.at(1, t, k).px - rig.cameras[1].ProjectWorld(KnotAt(t, k))).norm(), 15.0);
  SequenceOptions o;
  o.adjustment = Adjustment::kPoints;
  const SequenceResult plain = ReconstructSequence(rig, labels, o);
  const size_t i = static_cast<size_t>(t) * kRows * kCols + k;
  ASSERT_TRUE(plain.valid[i]);  // geometry alone accepts it, 8 cm off
  EXPECT_GT((plain.position[i] - KnotAt(t, k)).norm(), 0.05);

  o.smoothness_sigma_m = 1e-5;
  const SequenceResult smooth = ReconstructSequence(rig, labels, o);
  EXPECT_FALSE(smooth.valid[i]);
  EXPECT_EQ(smooth.track_outliers, 1);
  EXPECT_EQ(smooth.prior_disagreements, 0);
  int reported = 0;
  for (const auto& outlier : smooth.outliers)
    reported += outlier.frame == 100 + t && outlier.knot == k;
  EXPECT_EQ(reported, 2);  // both views: either may be the wrong one
  EXPECT_LT(RmsError(smooth), 0.5 * RmsError(plain));
}

TEST(SequenceWarnings, NoneWhenAllIsWell) {
  SequenceResult r;
  r.candidates = 100;
  r.triangulated = 90;  // 90 %: not fewer
  r.sigma_px = 0.5;
  r.sigma_estimated = true;
  r.outlier_threshold_px = 2.0;  // four times the noise: not less
  EXPECT_TRUE(SequenceWarnings(r).empty());
  // A given noise is the user's own: no warning about it, whatever the threshold.
  r.sigma_estimated = false;
  r.outlier_threshold_px = 0.5;
  EXPECT_TRUE(SequenceWarnings(r).empty());
  // Nothing seen twice: nothing to warn about.
  EXPECT_TRUE(SequenceWarnings(SequenceResult{}).empty());
}

TEST(SequenceWarnings, NameTheNoiseThePriorAndTheUntriangulatedInThatOrder) {
  SequenceResult r;
  r.sigma_px = 0.5;
  r.sigma_estimated = true;
  r.outlier_threshold_px = 1.9;
  r.prior_disagreements = 3;
  r.candidates = 100;
  r.triangulated = 89;
  const std::vector<std::string> w = SequenceWarnings(r);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_EQ(w[0],
            "the labelling noise (0.50 px) is more than a quarter of --outlier-px: good labels "
            "are being rejected; raise --outlier-px to ~5x the noise");
  EXPECT_EQ(w[1],
            "3 points seen by three or more cameras are pulled beyond the outlier threshold by the "
            "smoothness prior: --smooth-sigma may be too small for this motion");
  EXPECT_EQ(w[2], "11 of 100 knot-frames seen twice or more were not triangulated (see /outliers)");
}

}  // namespace
}  // namespace netlab::recon
