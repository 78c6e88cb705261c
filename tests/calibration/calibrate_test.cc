// Rig calibration against synthetic ground truth (the library's own renderer and detector).

#include "calibration/calibrate.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/calibration/synthetic_dataset.h"

namespace netlab::calib {
namespace {

using testing::CompareRelativePoses;
using testing::FacingPlusX;
using testing::Render;

// The two 16 mm cameras of the paper's rig at half resolution, a chessboard waved in front.
TEST(CalibrateRig, StereoPairFromAChessboardRecoversIntrinsicsAndPose) {
  Rig truth = PaperRig(0.5);
  truth.cameras.resize(2);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(21);
  const auto poses = RandomTargetPoses(truth, board, {0, 1}, 16, Eigen::Vector3d(0.9, 0.0, 0.1),
                                       Eigen::Vector3d(0.5, 0.5, 0.4),
                                       FacingPlusX(board.faces[0].pattern), 0.7, rng);
  const auto data = Render(truth, board, poses, 2.0, 1);
  const CalibrationResult result = CalibrateRig(board, data.input, CalibrationOptions{});
  // Corner noise ~0.07 px: the reprojection RMS stays near it.
  EXPECT_LT(result.summary.rms_px, 0.12);
  for (int c = 0; c < 2; ++c) {
    const CameraIntrinsics& e = result.rig.cameras[c].intrinsics;
    const CameraIntrinsics& t = truth.cameras[c].intrinsics;
    EXPECT_NEAR(e.fx / t.fx, 1.0, 2e-3) << c;
    EXPECT_NEAR(e.fy / t.fy, 1.0, 2e-3) << c;
    EXPECT_NEAR(e.cx, t.cx, 2.0) << c;
    EXPECT_NEAR(e.cy, t.cy, 2.0) << c;
    EXPECT_NEAR(e.distortion[0], t.distortion[0], 0.01) << c;
  }
  const auto error = CompareRelativePoses(result.rig, truth);
  EXPECT_LT(error.rotation_rad, 0.1 * M_PI / 180);
  EXPECT_LT(error.translation_m, 3e-3);
  // The world is the board in the first frame: the true board poses map onto it.
  const Rigid3d world_from_true = poses[0];
  for (int f = 0; f < 16; ++f) {
    ASSERT_TRUE(result.frame_seen[f]);
    const Rigid3d expected = world_from_true.Inverse() * poses[f];
    EXPECT_LT((result.world_from_target[f].translation - expected.translation).norm(), 5e-3);
  }
  // Metric check: triangulated squares measure 60 mm.
  ASSERT_FALSE(result.summary.pairs.empty());
  EXPECT_NEAR(result.summary.pairs[0].mean_length_mm, 60.0, 0.1);
  EXPECT_LT(result.summary.pairs[0].rms_error_mm, 0.5);
  EXPECT_NEAR(result.summary.pairs[0].baseline_m, 1.0, 3e-3);
}

// The paper's four cameras, two facing pairs, and the double-sided foil between them: the back
// pair sees the mirrored back face, and both pairs land in one frame.
void ExpectFoilLandsInOneFrame(const BoardPattern& pattern, bool name_back_cameras) {
  const Rig truth = PaperRig(0.5);
  CalibrationTarget foil = CalibrationTarget::Foil(pattern, 0.0005);
  if (name_back_cameras) foil.back_cameras = {"cam2", "cam3"};
  std::mt19937 rng(5);
  const auto poses =
      RandomTargetPoses(truth, foil, {0, 1, 2, 3}, 20, Eigen::Vector3d(1.25, 0.0, 0.1),
                        Eigen::Vector3d(0.3, 0.3, 0.25), FacingPlusX(pattern), 0.6, rng);
  const auto data = Render(truth, foil, poses, 2.0, 7);
  const CalibrationResult result = CalibrateRig(foil, data.input, CalibrationOptions{});
  EXPECT_EQ(result.summary.face_of_camera, (std::vector<int>{0, 0, 1, 1}));
  EXPECT_LT(result.summary.rms_px, 0.2);
  const auto error = CompareRelativePoses(result.rig, truth);
  // 5.5 m between the pairs: ~1 mm camera-centre sigma (the solver's own covariance).
  EXPECT_LT(error.rotation_rad, 0.1 * M_PI / 180);
  EXPECT_LT(error.translation_m, 6e-3);
  for (const CameraReport& c : result.summary.cameras) {
    EXPECT_GT(c.position_sigma_m, 0.0);
    EXPECT_LT(c.position_sigma_m, 3e-3);
  }
}

TEST(CalibrateRig, FacingPairsWithAChessboardFoilLandInOneFrame) {
  ExpectFoilLandsInOneFrame(BoardPattern::Chessboard(9, 6, 0.06), false);
}

TEST(CalibrateRig, FacingPairsWithACharucoFoilLandInOneFrame) {
  ExpectFoilLandsInOneFrame(BoardPattern::Charuco(10, 7, 0.06, 0.045, "DICT_5X5_100"), true);
}

// Known intrinsics held fixed: only the poses are estimated.
TEST(CalibrateRig, FixedIntrinsicsStayFixed) {
  Rig truth = PaperRig(0.5);
  truth.cameras.resize(2);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(3);
  const auto poses = RandomTargetPoses(truth, board, {0, 1}, 4, Eigen::Vector3d(0.9, 0.0, 0.1),
                                       Eigen::Vector3d(0.4, 0.4, 0.3),
                                       FacingPlusX(board.faces[0].pattern), 0.5, rng);
  const auto data = Render(truth, board, poses, 2.0, 3);
  CalibrationOptions options;
  for (const Camera& c : truth.cameras) options.fixed_intrinsics[c.name] = c.intrinsics;
  const CalibrationResult result = CalibrateRig(board, data.input, options);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(result.rig.cameras[c].intrinsics.fx, truth.cameras[c].intrinsics.fx);
    EXPECT_EQ(result.rig.cameras[c].intrinsics.distortion[0],
              truth.cameras[c].intrinsics.distortion[0]);
  }
  EXPECT_LT(CompareRelativePoses(result.rig, truth).translation_m, 3e-3);
  // Four views are few: said so.
  bool warned = false;
  for (const std::string& w : result.summary.warnings)
    warned |= w.find("only 4 views") != std::string::npos;
  EXPECT_TRUE(warned);
}

// ArUco markers at known positions around the working area (the rig's, target's and ejector's
// 3D markers): the rig lands in the map's frame.
TEST(CalibrateRig, MarkerMapPutsTheRigInTheMapFrame) {
  const Rig truth = PaperRig(0.5);
  std::vector<std::pair<int, std::array<Eigen::Vector3d, 4>>> markers;
  int id = 0;
  // A wall of markers facing -x at x = 2.0 and one facing +x at x = 0.3: each pair sees one.
  for (double x : {2.0, 0.3}) {
    const Eigen::Vector3d normal(x > 1.0 ? -1.0 : 1.0, 0.0, 0.0);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        markers.emplace_back(
            id++,
            MarkerCorners(Eigen::Vector3d(x + 0.05 * ((i + j) % 2), 0.2 * (i - 1), 0.2 * (j - 1)),
                          Eigen::Vector3d(0, x > 1.0 ? -1.0 : 1.0, 0), normal, 0.12));
  }
  const CalibrationTarget map = CalibrationTarget::MarkerMap("DICT_4X4_50", markers);
  const auto data = Render(truth, map, {Rigid3d(), Rigid3d()}, 1.0, 9);
  CalibrationOptions options;
  for (const Camera& c : truth.cameras) options.fixed_intrinsics[c.name] = c.intrinsics;
  const CalibrationResult result = CalibrateRig(map, data.input, options);
  for (size_t c = 0; c < 4; ++c) {
    EXPECT_LT((result.rig.cameras[c].Center() - truth.cameras[c].Center()).norm(), 0.01) << c;
    EXPECT_LT(result.rig.cameras[c].cam_from_world.rotation.angularDistance(
                  truth.cameras[c].cam_from_world.rotation),
              0.2 * M_PI / 180)
        << c;
  }
}

// A mislabelled view (a corner moved by 20 px) is dropped, not fitted.
TEST(CalibrateRig, GrossOutliersAreDropped) {
  Rig truth = PaperRig(0.5);
  truth.cameras.resize(2);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(8);
  const auto poses = RandomTargetPoses(truth, board, {0, 1}, 10, Eigen::Vector3d(0.9, 0.0, 0.1),
                                       Eigen::Vector3d(0.4, 0.4, 0.3),
                                       FacingPlusX(board.faces[0].pattern), 0.6, rng);
  auto data = Render(truth, board, poses, 2.0, 5);
  data.input.observations[3].pixels[7] += Eigen::Vector2d(20.0, -12.0);
  data.input.observations[12].pixels[40] += Eigen::Vector2d(-9.0, 15.0);
  const CalibrationResult result = CalibrateRig(board, data.input, CalibrationOptions{});
  EXPECT_EQ(result.summary.outliers, 2);
  EXPECT_LT(result.summary.rms_px, 0.15);
  EXPECT_LT(CompareRelativePoses(result.rig, truth).translation_m, 3e-3);
}

TEST(CalibrateRig, ACameraThatSharesNoFrameIsNamed) {
  Rig truth = PaperRig(0.5);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(2);
  // Boards only the 16 mm pair sees, and boards only cam2 sees.
  auto front = RandomTargetPoses(truth, board, {0, 1}, 5, Eigen::Vector3d(0.5, 0.0, 0.1),
                                 Eigen::Vector3d(0.2, 0.2, 0.2),
                                 FacingPlusX(board.faces[0].pattern), 0.4, rng);
  Eigen::Matrix3d flip = Eigen::Vector3d(-1, 1, -1).asDiagonal();
  auto back = RandomTargetPoses(
      truth, board, {2}, 5, Eigen::Vector3d(2.0, 0.0, 0.2), Eigen::Vector3d(0.2, 0.2, 0.2),
      FacingPlusX(board.faces[0].pattern) * Eigen::Quaterniond(flip), 0.4, rng);
  truth.cameras.resize(3);
  std::vector<Rigid3d> poses = front;
  poses.insert(poses.end(), back.begin(), back.end());
  const auto data = Render(truth, board, poses, 1.0, 2);
  try {
    CalibrateRig(board, data.input, CalibrationOptions{});
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cam2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("share no frame"), std::string::npos) << e.what();
  }
}

TEST(CalibrateRig, TooFewViewsForIntrinsicsIsAnError) {
  Rig truth = PaperRig(0.5);
  truth.cameras.resize(1);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(6);
  const auto poses = RandomTargetPoses(truth, board, {0}, 2, Eigen::Vector3d(0.9, 0.0, 0.1),
                                       Eigen::Vector3d(0.3, 0.3, 0.3),
                                       FacingPlusX(board.faces[0].pattern), 0.5, rng);
  const auto data = Render(truth, board, poses, 1.0, 4);
  try {
    CalibrateRig(board, data.input, CalibrationOptions{});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("only 2 views"), std::string::npos) << e.what();
  }
}

TEST(CalibrateRig, AllViewsAlikeIsWarned) {
  Rig truth = PaperRig(0.5);
  truth.cameras.resize(1);
  const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.06));
  std::mt19937 rng(7);
  const auto poses = RandomTargetPoses(truth, board, {0}, 6, Eigen::Vector3d(0.9, 0.0, 0.1),
                                       Eigen::Vector3d(0.3, 0.3, 0.3),
                                       FacingPlusX(board.faces[0].pattern), 0.05, rng);
  const auto data = Render(truth, board, poses, 1.0, 4);
  const CalibrationResult result = CalibrateRig(board, data.input, CalibrationOptions{});
  bool warned = false;
  for (const std::string& w : result.summary.warnings)
    warned |= w.find("views are alike") != std::string::npos;
  EXPECT_TRUE(warned) << result.summary.BriefReport();
}

class DetectInImagesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("netlab_calib_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    Rig rig = PaperRig(0.25);
    const CalibrationTarget board = CalibrationTarget::Board(BoardPattern::Chessboard(9, 6, 0.08));
    Eigen::Matrix3d r;
    r << Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, 0);
    image_ = RenderTarget(
        rig.cameras[0], CameraRays(rig.cameras[0].intrinsics), MakeTargetPrints(board),
        Rigid3d(Eigen::Quaterniond(r), Eigen::Vector3d(0.6, 0.32, 0.73)), RenderOptions{});
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Save(const std::string& name, const cv::Mat& image) {
    const std::string path = (dir_ / name).string();
    cv::imwrite(path, image);
    return path;
  }
  std::string ErrorOf(const std::vector<std::vector<std::string>>& files,
                      const std::string& spec = "chessboard:9x6:0.08") {
    std::vector<std::string> names;
    for (size_t i = 0; i < files.size(); ++i) names.push_back("cam" + std::to_string(i));
    try {
      DetectInImages(names, files, CalibrationTarget::Parse(spec), {});
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  std::filesystem::path dir_;
  cv::Mat image_;
};

TEST_F(DetectInImagesTest, FindsTheBoardAndRecordsSizes) {
  const std::string a = Save("a.png", image_);
  std::vector<std::string> names = {"cam0"};
  const CalibrationInput input =
      DetectInImages(names, {{a, a}}, CalibrationTarget::Parse("chessboard:9x6:0.08"), {});
  EXPECT_EQ(input.observations.size(), 2u);
  EXPECT_EQ(input.image_sizes[0], cv::Size(512, 512));
}

TEST_F(DetectInImagesTest, UnreadableImageIsNamed) {
  const std::string bad = (dir_ / "bad.png").string();
  { std::ofstream(bad) << "not a png"; }
  EXPECT_NE(ErrorOf({{Save("a.png", image_), bad}}).find("bad.png: unreadable"), std::string::npos);
}

TEST_F(DetectInImagesTest, DifferentSizesWithinACameraAreNamed) {
  cv::Mat small;
  cv::resize(image_, small, cv::Size(256, 256));
  const std::string error = ErrorOf({{Save("a.png", image_), Save("b.png", small)}});
  EXPECT_NE(error.find("b.png is 256x256"), std::string::npos) << error;
}

TEST_F(DetectInImagesTest, UnequalCountsAreNamed) {
  const std::string a = Save("a.png", image_);
  const std::string error = ErrorOf({{a, a}, {a}});
  EXPECT_NE(error.find("unequal numbers of images per camera: cam0 has 2, cam1 has 1"),
            std::string::npos)
      << error;
}

TEST_F(DetectInImagesTest, NoBoardFoundNamesTheImagesAndTheBoard) {
  const std::string a = Save("a.png", image_);
  const std::string error = ErrorOf({{a}}, "chessboard:7x6:0.08");
  EXPECT_NE(error.find("no chessboard of 7x6 inner corners found"), std::string::npos) << error;
  EXPECT_NE(error.find("a.png"), std::string::npos) << error;
}

}  // namespace
}  // namespace netlab::calib
