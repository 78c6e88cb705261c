#include "calibration/rig.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>

namespace netlab::calib {
namespace {

class RigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("netlab_rig_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(Path(name)) << text;
    return Path(name);
  }
  std::filesystem::path dir_;
};

TEST_F(RigFile, RoundTripKeepsEveryCamera) {
  Rig rig = PaperRig();
  rig.cameras[2].intrinsics.rational = true;
  rig.cameras[2].intrinsics.distortion[6] = 0.03;
  WriteRig(Path("rig.yaml"), rig);
  EXPECT_FALSE(std::filesystem::exists(Path("rig.yaml.partial")));
  const Rig back = ReadRig(Path("rig.yaml"));
  ASSERT_EQ(back.cameras.size(), 4u);
  for (size_t c = 0; c < 4; ++c) {
    const Camera& a = rig.cameras[c];
    const Camera& b = back.cameras[c];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.intrinsics.width, b.intrinsics.width);
    EXPECT_NEAR(a.intrinsics.fx, b.intrinsics.fx, 1e-9);
    EXPECT_EQ(a.intrinsics.rational, b.intrinsics.rational);
    for (int i = 0; i < 8; ++i)
      EXPECT_NEAR(a.intrinsics.distortion[i], b.intrinsics.distortion[i], 1e-12);
    EXPECT_LT(a.cam_from_world.rotation.angularDistance(b.cam_from_world.rotation), 1e-9);
    EXPECT_LT((a.cam_from_world.translation - b.cam_from_world.translation).norm(), 1e-12);
  }
}

// The file is plain OpenCV FileStorage: the contract's keys read with cv::FileStorage alone.
TEST_F(RigFile, IsReadableByOpenCVFileStorage) {
  WriteRig(Path("rig.yaml"), PaperRig());
  cv::FileStorage fs(Path("rig.yaml"), cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  const cv::FileNode cameras = fs["cameras"];
  ASSERT_TRUE(cameras.isSeq());
  ASSERT_EQ(cameras.size(), 4u);
  cv::Mat k, d, r, t;
  cameras[0]["camera_matrix"] >> k;
  cameras[0]["distortion_coefficients"] >> d;
  cameras[0]["rotation"] >> r;
  cameras[0]["translation"] >> t;
  EXPECT_EQ(static_cast<std::string>(cameras[0]["name"]), "cam0");
  EXPECT_EQ(static_cast<int>(cameras[0]["image_width"]), 2048);
  EXPECT_EQ(k.size(), cv::Size(3, 3));
  EXPECT_EQ(d.size(), cv::Size(5, 1));
  EXPECT_EQ(r.size(), cv::Size(3, 3));
  EXPECT_EQ(t.size(), cv::Size(1, 3));
}

TEST_F(RigFile, BrokenFilesAreNamed) {
  auto error_of = [&](const std::string& text) {
    try {
      ReadRig(Write("bad.yaml", text));
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("%YAML:1.0\n---\nfoo: 1\n").find("expected a sequence 'cameras'"),
            std::string::npos);
  const std::string camera =
      "%YAML:1.0\n---\ncameras:\n  - name: cam0\n    image_width: 100\n    image_height: 100\n"
      "    camera_matrix: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: d\n"
      "      data: [ 100., 0., 50., 0., 100., 50., 0., 0., 1. ]\n";
  const std::string distortion =
      "    distortion_coefficients: !!opencv-matrix\n      rows: 1\n      cols: 5\n      dt: d\n"
      "      data: [ 0., 0., 0., 0., 0. ]\n";
  const std::string rotation =
      "    rotation: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: d\n"
      "      data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]\n";
  const std::string translation =
      "    translation: !!opencv-matrix\n      rows: 3\n      cols: 1\n      dt: d\n"
      "      data: [ 0., 0., 0. ]\n";
  EXPECT_EQ(error_of(camera + distortion + rotation + translation), "");
  const std::string missing = error_of(camera + rotation + translation);
  EXPECT_NE(missing.find("missing distortion_coefficients"), std::string::npos) << missing;
  std::string bad_rotation = rotation;
  bad_rotation.replace(bad_rotation.find("1., 0., 0., 0., 1."), 18, "2., 0., 0., 0., 1.");
  const std::string not_rotation = error_of(camera + distortion + bad_rotation + translation);
  EXPECT_NE(not_rotation.find("not a rotation matrix"), std::string::npos) << not_rotation;
  std::string wide = distortion;
  wide.replace(wide.find("cols: 5"), 7, "cols: 4");
  wide.replace(wide.find("0., 0., 0., 0., 0."), 18, "0., 0., 0., 0.");
  const std::string size = error_of(camera + wide + rotation + translation);
  EXPECT_NE(size.find("expected 1x5 or 1x8, got 1x4"), std::string::npos) << size;
  EXPECT_NE(error_of("not: [yaml").find("bad.yaml"), std::string::npos);
  try {
    ReadRig(Path("absent.yaml"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos);
  }
}

// The preset is the paper's rig: two facing pairs 1 m apart, 0.5 m above the flight axis.
TEST(PaperRig, HasTwoFacingStereoPairs) {
  const Rig rig = PaperRig();
  ASSERT_EQ(rig.cameras.size(), 4u);
  EXPECT_NEAR((rig.cameras[0].Center() - rig.cameras[1].Center()).norm(), 1.0, 1e-12);
  EXPECT_NEAR((rig.cameras[2].Center() - rig.cameras[3].Center()).norm(), 1.0, 1e-12);
  EXPECT_LE((rig.cameras[0].Center() - rig.cameras[2].Center()).norm(), 7.0);
  for (const Camera& c : rig.cameras) EXPECT_NEAR(c.Center().z(), 0.5, 1e-12);
  EXPECT_GT(rig.cameras[0].ViewDirection().x(), 0.9);   // looking along the flight
  EXPECT_LT(rig.cameras[2].ViewDirection().x(), -0.9);  // looking back
  // 16 mm and 25 mm lenses on 5.5 um pixels.
  EXPECT_NEAR(rig.cameras[0].intrinsics.fx, 16e3 / 5.5, 1e-9);
  EXPECT_NEAR(rig.cameras[2].intrinsics.fx, 25e3 / 5.5, 1e-9);
  // The middle of the flight path projects near every image centre.
  for (const Camera& c : rig.cameras) {
    const Eigen::Vector2d p = c.ProjectWorld(Eigen::Vector3d(1.0, 0.0, 0.0));
    EXPECT_NEAR(p.x(), 1023.5, 1.0);
    EXPECT_NEAR(p.y(), 1023.5, 1.0);
  }
}

}  // namespace
}  // namespace netlab::calib
