// `netlab calibrate` end to end on rendered image files.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "calibration/rig.h"
#include "tests/app/run_netlab.h"
#include "tests/calibration/synthetic_dataset.h"

namespace {

using netlab::testing::Json;
using netlab::testing::JsonParser;
namespace calib = netlab::calib;

using Result = netlab::testing::NetlabResult;
Result Netlab(const std::string& args) { return netlab::testing::RunNetlab(args); }
using netlab::testing::LastJson;

// Two cameras of the paper's rig at quarter resolution, 10 views of a chessboard, as PNG files.
class CalibrateCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::filesystem::temp_directory_path() / ("netlab_calibrate_cli_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_ / "cam0");
    std::filesystem::create_directories(dir_ / "cam1");
    truth_ = calib::PaperRig(0.5);
    truth_.cameras.resize(2);
    const auto board = calib::CalibrationTarget::Parse("chessboard:9x6:0.06");
    std::mt19937 rng(12);
    const auto poses = calib::RandomTargetPoses(
        truth_, board, {0, 1}, 10, Eigen::Vector3d(0.9, 0.0, 0.1), Eigen::Vector3d(0.5, 0.5, 0.4),
        calib::testing::FacingPlusX(board.faces[0].pattern), 0.7, rng);
    const auto prints = calib::MakeTargetPrints(board);
    for (int c = 0; c < 2; ++c) {
      const calib::CameraRays rays(truth_.cameras[c].intrinsics);
      for (size_t f = 0; f < poses.size(); ++f) {
        calib::RenderOptions options;
        options.noise_sigma = 2.0;
        options.seed = 100 * c + f;
        char name[64];
        std::snprintf(name, sizeof(name), "cam%d/frame_%03zu.png", c, f);
        cv::imwrite((dir_ / name).string(),
                    calib::RenderTarget(truth_.cameras[c], rays, prints, poses[f], options));
      }
    }
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static std::string Images() {
    return "--images cam0='" + (dir_ / "cam0/*.png").string() + "' --images cam1='" +
           (dir_ / "cam1/*.png").string() + "'";
  }
  static std::filesystem::path dir_;
  static calib::Rig truth_;
};
std::filesystem::path CalibrateCommand::dir_;
calib::Rig CalibrateCommand::truth_;

TEST_F(CalibrateCommand, WritesTheRigAndTheJsonSummary) {
  const std::string out = (dir_ / "rig.yaml").string();
  const Result r = Netlab("calibrate --board chessboard:9x6:0.06 " + Images() + " --out " + out +
                          " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const Json json = LastJson(r.out);
  EXPECT_LT(json["rms_px"].number(), 0.15);
  ASSERT_EQ(json["cameras"].array().size(), 2u);
  const Json& cam0 = json["cameras"].array()[0];
  EXPECT_EQ(cam0["name"].string(), "cam0");
  EXPECT_EQ(cam0["views"].number(), 10);
  EXPECT_NEAR(cam0["fx"].number(), truth_.cameras[0].intrinsics.fx, 0.003 * truth_.cameras[0].intrinsics.fx);
  for (const char* key : {"fy", "cx", "cy", "rms_px"}) EXPECT_TRUE(cam0.has(key)) << key;
  EXPECT_NEAR(json["baselines"]["cam0-cam1"].number(), 1.0, 0.005);
  EXPECT_TRUE(json.has("warnings"));
  EXPECT_GT(json["wall_s"].number(), 0.0);
  const calib::Rig rig = calib::ReadRig(out);
  ASSERT_EQ(rig.cameras.size(), 2u);
  EXPECT_NEAR((rig.cameras[0].Center() - rig.cameras[1].Center()).norm(), 1.0, 0.005);
}

TEST_F(CalibrateCommand, FixedIntrinsicsComeFromARigFile) {
  const std::string known = (dir_ / "known.yaml").string();
  calib::WriteRig(known, truth_);
  const std::string out = (dir_ / "rig2.yaml").string();
  const Result r = Netlab("calibrate --board chessboard:9x6:0.06 " + Images() + " --out " + out +
                          " --fix-intrinsics " + known + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const calib::Rig rig = calib::ReadRig(out);
  EXPECT_DOUBLE_EQ(rig.cameras[1].intrinsics.fx, truth_.cameras[1].intrinsics.fx);
}

TEST_F(CalibrateCommand, BadInputIsNamed) {
  const std::string out = (dir_ / "never.yaml").string();
  Result r = Netlab("calibrate --board chessboard:9x6 " + Images() + " --out " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("expected chessboard:COLSxROWS:SQUARE"), std::string::npos) << r.err;
  r = Netlab("calibrate --board chessboard:9x6:0.06 --images cam0='/nowhere/*.png' --out " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("matches no file"), std::string::npos) << r.err;
  r = Netlab("calibrate --board chessboard:7x6:0.06 " + Images() + " --out " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no chessboard of 7x6 inner corners found"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(Netlab("calibrate --board chessboard:9x6:0.06 " + Images()).status, 2);  // no --out
  EXPECT_EQ(Netlab("calibrate --board chessboard:9x6:0.06 --out " + out).status, 2);  // no images
}

}  // namespace
