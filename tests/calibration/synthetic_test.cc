#include "calibration/synthetic.h"

#include <gtest/gtest.h>

#include "tests/calibration/synthetic_dataset.h"

namespace netlab::calib {
namespace {

// A chessboard 1 m ahead of the camera, facing it.
Rigid3d BoardAhead(const Camera& camera, double distance) {
  const Rigid3d world_from_cam = camera.cam_from_world.Inverse();
  return Rigid3d(world_from_cam.rotation, world_from_cam * Eigen::Vector3d(-0.2, -0.15, distance));
}

TEST(Synthetic, RaysAreTheUndistortedPixelCorners) {
  const Rig rig = PaperRig(0.25);
  const CameraRays rays(rig.cameras[0].intrinsics);
  for (const auto& [u, v] : {std::pair{0, 0}, std::pair{100, 300}, std::pair{512, 512}}) {
    const Eigen::Vector2d expected =
        UndistortPoint(rig.cameras[0].intrinsics, Eigen::Vector2d(u - 0.5, v - 0.5));
    EXPECT_LT((rays.Corner(u, v) - expected).norm(), 1e-6);
  }
}

TEST(Synthetic, ABoardSeenFromBehindIsNotDrawn) {
  const Rig rig = PaperRig(0.25);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.05));
  const auto prints = MakeTargetPrints(board);
  const CameraRays rays(rig.cameras[0].intrinsics);
  Rigid3d pose = BoardAhead(rig.cameras[0], 1.0);
  RenderOptions options;
  cv::Mat front = RenderTarget(rig.cameras[0], rays, prints, pose, options);
  double min_value, max_value;
  cv::minMaxLoc(front, &min_value, &max_value);
  EXPECT_LE(min_value, options.black + 1);
  EXPECT_GE(max_value, options.white - 1);
  // Turned around its own y axis: the camera now faces the back of the print.
  pose.rotation =
      pose.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  const cv::Mat back = RenderTarget(rig.cameras[0], rays, prints, pose, options);
  cv::minMaxLoc(back, &min_value, &max_value);
  EXPECT_EQ(min_value, options.background);
  EXPECT_EQ(max_value, options.background);
}

TEST(Synthetic, TheNearerPrintOccludesTheFarther) {
  const Rig rig = PaperRig(0.25);
  const BoardPattern pattern = BoardPattern::Chessboard(9, 6, 0.05);
  const auto print = MakeTargetPrints(CalibrationTarget::Board(pattern))[0].print;
  const Camera& camera = rig.cameras[0];
  const CameraRays rays(camera.intrinsics);
  const Rigid3d near = camera.cam_from_world * BoardAhead(camera, 1.0);
  const Rigid3d far = camera.cam_from_world * BoardAhead(camera, 2.0);
  const cv::Mat both =
      RenderPrints(rays, {{print.get(), far}, {print.get(), near}}, RenderOptions{});
  const cv::Mat only_near = RenderPrints(rays, {{print.get(), near}}, RenderOptions{});
  // Where the near board is, the image is the near board's.
  const Eigen::Vector2d centre = Project(camera.intrinsics, near * Eigen::Vector3d(0.2, 0.125, 0));
  const cv::Rect box(static_cast<int>(centre.x()) - 10, static_cast<int>(centre.y()) - 10, 20, 20);
  EXPECT_EQ(cv::norm(both(box), only_near(box), cv::NORM_INF), 0.0);
}

TEST(Synthetic, NoiseHasTheRequestedSigma) {
  const Rig rig = PaperRig(0.25);
  RenderOptions options;
  options.noise_sigma = 3.0;
  const cv::Mat image = RenderPrints(CameraRays(rig.cameras[0].intrinsics), {}, options);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  EXPECT_NEAR(mean[0], options.background, 0.1);
  EXPECT_NEAR(stddev[0], 3.0, 0.1);
}

TEST(Synthetic, RandomPosesAreSeenWhole) {
  const Rig rig = PaperRig(0.5);
  const CalibrationTarget foil =
      CalibrationTarget::Foil(BoardPattern::Chessboard(9, 6, 0.06), 0.001);
  std::mt19937 rng(1);
  const auto poses = RandomTargetPoses(rig, foil, {0, 1, 2, 3}, 5, Eigen::Vector3d(1.25, 0, 0.1),
                                       Eigen::Vector3d(0.3, 0.3, 0.2),
                                       testing::FacingPlusX(foil.faces[0].pattern), 0.5, rng);
  for (const Rigid3d& pose : poses)
    for (const Camera& camera : rig.cameras) {
      const auto seen = ProjectTarget(camera, foil, pose, 10.0);
      ASSERT_EQ(seen.size(), 1u);  // one side only
      EXPECT_EQ(seen[0].ids.size(), 54u);
    }
}

}  // namespace
}  // namespace netlab::calib
