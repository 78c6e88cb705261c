// Detection against the synthetic generator's truth: sub-pixel accuracy, canonical order, and no
// false positives.

#include "calibration/detect.h"

#include <gtest/gtest.h>

#include <map>

#include "calibration/synthetic.h"
#include "tests/calibration/synthetic_dataset.h"

namespace netlab::calib {
namespace {

struct Accuracy {
  int matched = 0;
  double rms = 0.0, worst = 0.0;
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
};

Accuracy Measure(const PatternDetection& found, const FaceProjection& truth) {
  std::map<int, Eigen::Vector2d> expected;
  for (size_t i = 0; i < truth.ids.size(); ++i) expected[truth.ids[i]] = truth.pixels[i];
  Accuracy a;
  double sum = 0.0;
  for (size_t i = 0; i < found.ids.size(); ++i) {
    const auto it = expected.find(found.ids[i]);
    if (it == expected.end()) continue;
    const Eigen::Vector2d e = found.pixels[i] - it->second;
    sum += e.squaredNorm();
    a.bias += e;
    a.worst = std::max(a.worst, e.norm());
    ++a.matched;
  }
  if (a.matched) {
    a.rms = std::sqrt(sum / a.matched);
    a.bias /= a.matched;
  }
  return a;
}

void ExpectAccurate(const CalibrationTarget& target, double noise, double max_rms,
                    double max_bias) {
  const Rig rig = PaperRig(0.5);
  std::mt19937 rng(11);
  const auto poses = RandomTargetPoses(rig, target, {0}, 6, Eigen::Vector3d(0.8, 0.0, 0.2),
                                       Eigen::Vector3d(0.3, 0.3, 0.2),
                                       testing::FacingPlusX(target.faces[0].pattern), 0.6, rng);
  const auto prints = MakeTargetPrints(target);
  const CameraRays rays(rig.cameras[0].intrinsics);
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < poses.size(); ++i) {
    RenderOptions options;
    options.noise_sigma = noise;
    options.seed = i;
    const cv::Mat image = RenderTarget(rig.cameras[0], rays, prints, poses[i], options);
    const PatternDetection found = DetectPattern(image, target.faces[0].pattern);
    const auto truth = ProjectTarget(rig.cameras[0], target, poses[i]);
    ASSERT_EQ(truth.size(), 1u);
    ASSERT_EQ(found.ids.size(), truth[0].ids.size()) << "view " << i;
    const Accuracy a = Measure(found, truth[0]);
    ASSERT_EQ(a.matched, static_cast<int>(truth[0].ids.size()));
    EXPECT_LT(a.rms, max_rms) << "view " << i;
    EXPECT_LT(a.worst, 4.0 * max_rms) << "view " << i;  // ids in the right order: no swaps
    bias += a.bias / poses.size();
  }
  EXPECT_LT(bias.norm(), max_bias);
}

TEST(Detect, ChessboardCornersAreSubPixelAndInCanonicalOrder) {
  ExpectAccurate(CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06)), 2.0, 0.12, 0.03);
}

// OpenCV 4.6 returns ChArUco corners half a pixel off; the refinement removes the bias.
TEST(Detect, CharucoCornersAreSubPixelAndUnbiased) {
  ExpectAccurate(
      CalibrationTarget::Board(BoardPattern::Charuco(10, 7, 0.06, 0.045, "DICT_5X5_100")), 2.0,
      0.25, 0.05);
}

// A ChArUco board half out of the image still gives its visible corners, with the right ids.
TEST(Detect, PartlyVisibleCharucoBoardsStillCount) {
  const CalibrationTarget board =
      CalibrationTarget::Board(BoardPattern::Charuco(10, 7, 0.06, 0.045, "DICT_5X5_100"));
  const Rig rig = PaperRig(0.5);
  // Centred on the image's right edge at 2.5 m: about half the board is outside.
  const Camera& camera = rig.cameras[0];
  const Rigid3d world_from_cam = camera.cam_from_world.Inverse();
  const double half_width = camera.intrinsics.cx / camera.intrinsics.fx * 2.5;
  // Face axes along the camera's (x right, y down), turned about x when the print's y is up.
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  if (board.faces[0].pattern.viewer_z > 0) turn = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Rigid3d face_pose(world_from_cam.rotation * Eigen::Quaterniond(turn),
                          world_from_cam * Eigen::Vector3d(half_width - 0.3, -0.2, 2.5));
  const cv::Mat image = RenderTarget(camera, CameraRays(camera.intrinsics), MakeTargetPrints(board),
                                     face_pose, RenderOptions{});
  const PatternDetection found = DetectPattern(image, board.faces[0].pattern);
  const auto truth = ProjectTarget(camera, board, face_pose, 3.0);
  ASSERT_EQ(truth.size(), 1u);
  EXPECT_LT(truth[0].ids.size(), 54u);  // part of the board is outside
  EXPECT_GE(found.ids.size(), 10u);
  const Accuracy a = Measure(found, truth[0]);
  EXPECT_EQ(a.matched, static_cast<int>(found.ids.size()));  // every id found is a true one
  EXPECT_LT(a.rms, 0.25);
}

TEST(Detect, ArucoMarkerCornersAreFoundWithTheirIds) {
  std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>> markers;
  for (int i = 0; i < 6; ++i)
    markers.emplace_back(
        i * 3, MarkerCorners(Eigen::Vector3d(0.0, 0.15 * (i % 3) - 0.15, 0.15 * (i / 3) - 0.075),
                             Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(-1, 0, 0), 0.1));
  const CalibrationTarget map = CalibrationTarget::MarkerMap("DICT_4X4_50", markers);
  const Rig rig = PaperRig(0.5);
  const Rigid3d pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.0, 0.1));
  const cv::Mat image = RenderTarget(rig.cameras[0], CameraRays(rig.cameras[0].intrinsics),
                                     MakeTargetPrints(map), pose, RenderOptions{});
  const PatternDetection found = DetectPattern(image, map.faces[0].pattern);
  const auto truth = ProjectTarget(rig.cameras[0], map, pose);
  ASSERT_EQ(found.ids.size(), 24u);
  const Accuracy a = Measure(found, truth[0]);
  EXPECT_EQ(a.matched, 24);
  EXPECT_LT(a.rms, 0.2);
}

// Seen from the far side of the board, the rotation of the order is resolved by the colours.
TEST(Detect, ChessboardOrderHoldsFromBothSidesOfAFoil) {
  const BoardPattern pattern = BoardPattern::Chessboard(9, 6, 0.06);
  const CalibrationTarget foil = CalibrationTarget::Foil(pattern, 0.001);
  const Rig rig = PaperRig(0.5);
  std::mt19937 rng(4);
  const auto poses =
      RandomTargetPoses(rig, foil, {0, 2}, 3, Eigen::Vector3d(1.25, 0.0, 0.1),
                        Eigen::Vector3d(0.2, 0.2, 0.2), testing::FacingPlusX(pattern), 0.5, rng);
  const auto prints = MakeTargetPrints(foil);
  for (int c : {0, 2}) {
    const CameraRays rays(rig.cameras[c].intrinsics);
    for (const Rigid3d& pose : poses) {
      const cv::Mat image = RenderTarget(rig.cameras[c], rays, prints, pose, RenderOptions{});
      const PatternDetection found = DetectPattern(image, pattern);
      const auto truth = ProjectTarget(rig.cameras[c], foil, pose);
      ASSERT_EQ(truth.size(), 1u);
      EXPECT_EQ(truth[0].face, c == 0 ? 0 : 1);
      const Accuracy a = Measure(found, truth[0]);
      EXPECT_EQ(a.matched, 54);
      EXPECT_LT(a.worst, 0.3) << "camera " << c;
    }
  }
}

TEST(Detect, NothingIsFoundInAnEmptyImage) {
  cv::Mat noise(512, 512, CV_8U);
  cv::randu(noise, 0, 255);
  // A plain grey background with faint noise: OpenCV's classic detector searched it for minutes.
  cv::Mat plain(1024, 1024, CV_8U, cv::Scalar(90));
  cv::Mat faint(1024, 1024, CV_8S);
  cv::randn(faint, 0, 1);
  cv::add(plain, faint, plain, cv::noArray(), CV_8U);
  EXPECT_TRUE(DetectPattern(plain, BoardPattern::Chessboard(9, 6, 0.05)).empty());
  EXPECT_TRUE(DetectPattern(noise, BoardPattern::Chessboard(9, 6, 0.05)).empty());
  EXPECT_TRUE(
      DetectPattern(noise, BoardPattern::Charuco(10, 7, 0.04, 0.03, "DICT_5X5_100")).empty());
}

TEST(Detect, AWrongBoardSizeIsNotFound) {
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  const Rig rig = PaperRig(0.5);
  Eigen::Matrix3d r;
  r << Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, 0);
  const cv::Mat image = RenderTarget(
      rig.cameras[0], CameraRays(rig.cameras[0].intrinsics), MakeTargetPrints(board),
      Rigid3d(Eigen::Quaterniond(r), Eigen::Vector3d(0.8, 0.45, 0.7)), RenderOptions{});
  EXPECT_FALSE(DetectPattern(image, BoardPattern::Chessboard(9, 6, 0.06)).empty());
  EXPECT_TRUE(DetectPattern(image, BoardPattern::Chessboard(7, 6, 0.06)).empty());
}

TEST(Detect, SixteenBitImagesAreScaled) {
  cv::Mat wide(4, 4, CV_16U, cv::Scalar(4000));
  wide.at<uint16_t>(0, 0) = 8000;
  const cv::Mat gray = ToGray8(wide);
  EXPECT_EQ(gray.type(), CV_8U);
  EXPECT_EQ(gray.at<uint8_t>(0, 0), 255);
  EXPECT_NEAR(gray.at<uint8_t>(1, 1), 128, 1);
}

}  // namespace
}  // namespace netlab::calib
