// A point on a straight path at constant velocity fitted to its views over several frames: its
// place in a frame one camera sees it in, an undetermined path, a jerk, and the covariance
// against the scatter of noisy draws.

#include "libreconstruct/geometry/point_motion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace netlab::recon {
namespace {

// A knot of the paper's rig crossing the view at 0.8 m/s (179 frames/s: 4.5 mm a frame).
const Eigen::Vector3d kAtZero(1.2, 0.15, -0.1);
const Eigen::Vector3d kVelocity = Eigen::Vector3d(0.8, 0.1, -0.05) / 179.0;  // m per frame

Eigen::Vector3d At(double t) { return kAtZero + t * kVelocity; }

// Views of `place(t)` by `cameras` in each frame of `frames`, with noise of `sigma` px.
std::vector<TimedObservation> Views(const calib::Rig& rig,
                                    const std::function<Eigen::Vector3d(double)>& place,
                                    const std::vector<std::pair<int, std::vector<int>>>& frames,
                                    double sigma, std::mt19937_64* rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<TimedObservation> views;
  for (const auto& [t, cameras] : frames)
    for (const int c : cameras) {
      Eigen::Vector2d px = rig.cameras[c].ProjectWorld(place(t));
      if (rng) px += Eigen::Vector2d(noise(*rng), noise(*rng));
      views.push_back({static_cast<double>(t), {c, px}});
    }
  return views;
}

// The near pair saw the knot in frames -4 to -1; in frame 0 one camera of the far pair does.
const std::vector<std::pair<int, std::vector<int>>> kOneViewNow = {
    {-4, {0, 1}}, {-3, {0, 1}}, {-2, {0, 1, 2}}, {-1, {0, 1}}, {0, {2}}};

TEST(FitConstantVelocity, PlacesAPointOneCameraSeesWhereItsPathTakesIt) {
  const calib::Rig rig = calib::PaperRig();
  const PointEstimate e = FitConstantVelocity(rig, Views(rig, At, kOneViewNow, 0, nullptr), 0);
  ASSERT_TRUE(e.valid) << e.why;
  EXPECT_LT((e.position - At(0)).norm(), 1e-9);
  EXPECT_LT(e.rms_px, 1e-6);
  EXPECT_EQ(e.residual_px.size(), 10u);
  // Anywhere on the path: in a frame none of the views is from.
  const PointEstimate later = FitConstantVelocity(rig, Views(rig, At, kOneViewNow, 0, nullptr), 2);
  ASSERT_TRUE(later.valid) << later.why;
  EXPECT_LT((later.position - At(2)).norm(), 1e-9);
}

TEST(FitConstantVelocity, OneCameraAloneDoesNotFixThePath) {
  const calib::Rig rig = calib::PaperRig();
  // A path twice as far at twice the speed looks the same to one camera.
  const PointEstimate e = FitConstantVelocity(
      rig, Views(rig, At, {{-3, {0}}, {-2, {0}}, {-1, {0}}, {0, {0}}}, 0, nullptr), 0);
  EXPECT_FALSE(e.valid);
  EXPECT_FALSE(e.why.empty());
  EXPECT_FALSE(FitConstantVelocity(rig, Views(rig, At, {{-1, {0, 1}}}, 0, nullptr), 0).valid)
      << "two views do not fix a velocity";
}

// Stopped by the target at frame -1 (the flight's 4.5 mm a frame gone). Across the cameras'
// lines of sight the stop shows in the residuals, far beyond what 0.3 px of label noise explains
// (chi^2 of 14 degrees of freedom: 36.1 at 99.9 %). Along them (the flight's direction, the
// depth of both pairs) the views hardly see it, nor is the place they fit seen off by much.
TEST(FitConstantVelocity, AJerkShowsInTheResidualsWhereItShowsInTheImages) {
  const calib::Rig rig = calib::PaperRig();
  for (const bool across : {true, false}) {
    const Eigen::Vector3d v =
        (across ? Eigen::Vector3d(0.1, 0.8, 0.0) : Eigen::Vector3d(0.8, 0.1, -0.05)) / 179.0;
    const auto stopped = [&](double t) { return kAtZero + std::min(t, -1.0) * v; };
    const PointEstimate e =
        FitConstantVelocity(rig, Views(rig, stopped, kOneViewNow, 0, nullptr), 0);
    ASSERT_TRUE(e.valid) << e.why;
    const double chi2 = e.sum_squares_px2 / (0.3 * 0.3);
    if (across) {
      EXPECT_GT(chi2, 100.0);
      continue;
    }
    EXPECT_LT(chi2, 36.1);
    for (int c = 0; c < 4; ++c)
      EXPECT_LT((rig.cameras[c].ProjectWorld(e.position) - rig.cameras[c].ProjectWorld(stopped(0)))
                    .norm(),
                1.0)
          << "camera " << c;
  }
}

TEST(FitConstantVelocity, ItsCovarianceIsTheScatterOfNoisyDraws) {
  const calib::Rig rig = calib::PaperRig();
  std::mt19937_64 rng(7);
  const double sigma = 0.3;
  double mahalanobis2 = 0.0, chi2 = 0.0;
  const int draws = 2000;
  for (int i = 0; i < draws; ++i) {
    const PointEstimate e = FitConstantVelocity(rig, Views(rig, At, kOneViewNow, sigma, &rng), 0);
    ASSERT_TRUE(e.valid) << e.why;
    const Eigen::Vector3d d = e.position - At(0);
    mahalanobis2 += d.dot((sigma * sigma * e.unit_covariance).inverse() * d);
    chi2 += e.sum_squares_px2 / (sigma * sigma);
  }
  // Three coordinates: a mean squared Mahalanobis distance of 3; 20 - 6 degrees of freedom
  // left in the residuals.
  EXPECT_NEAR(mahalanobis2 / draws, 3.0, 0.25);
  EXPECT_NEAR(chi2 / draws, 14.0, 0.8);
}

}  // namespace
}  // namespace netlab::recon
