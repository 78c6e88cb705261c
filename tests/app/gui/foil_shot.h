#pragma once
// Rendered calibration images for the calibration room's tests: the double-sided foil seen by the
// paper's rig at a quarter of its resolution (512 px), 8 frames, written as the twin writes them;
// and what `netlab calibrate`'s code path makes of them.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "app/gui/document/calibration_presenter.h"
#include "calibration/calibrate.h"
#include "calibration/synthetic.h"

namespace netlab::gui::testing {

namespace fs = std::filesystem;

constexpr int kFrames = 8;
constexpr int kKnockedCamera = 1, kKnockedFrame = 5;

// The foil's images for every camera of the paper's rig at 512 px, written as the twin writes
// them (DIR/camN/view_NNN.png, DIR/foil.yaml); cam1's frame 5 seen by the camera turned by
// 0.15 deg (a knock): its corners disagree with the others' by about 2 px. A blank image for
// cam3 frame 7: the foil not found there.
struct FoilShot {
  fs::path dir;
  calib::Rig truth;
  std::vector<std::pair<std::string, std::string>> globs;
};

// In a fresh temporary folder named after `name`.
inline FoilShot RenderFoilShot(const std::string& name) {
  FoilShot shot;
  shot.dir = fs::temp_directory_path() / (name + "_" + std::to_string(getpid()));
  fs::remove_all(shot.dir);
  fs::create_directories(shot.dir);
  shot.truth = calib::PaperRig(0.25);
  {
    std::ofstream foil(shot.dir / "foil.yaml");
    foil << "type: double_sided_foil\nboard: {type: chessboard, cols: 9, rows: 6, square: 0.06}\n"
            "thickness: 0.0005\nflip_axis: y\n";
  }
  const calib::CalibrationTarget target =
      calib::CalibrationTarget::Parse((shot.dir / "foil.yaml").string());
  std::mt19937 rng(11);
  const auto poses = calib::RandomTargetPoses(
      shot.truth, target, {0, 1, 2, 3}, kFrames, Eigen::Vector3d(1.25, 0.0, 0.1),
      Eigen::Vector3d(0.3, 0.3, 0.25), calib::FacingPlusX(target.faces[0].pattern), 0.6, rng);
  const auto prints = calib::MakeTargetPrints(target);
  for (int c = 0; c < 4; ++c) {
    const calib::Camera& camera = shot.truth.cameras[c];
    const fs::path folder = shot.dir / camera.name;
    fs::create_directories(folder);
    const calib::CameraRays rays(camera.intrinsics);
    for (int f = 0; f < kFrames; ++f) {
      calib::RenderOptions options;
      options.noise_sigma = 2.0;
      options.seed = 100 * c + f;
      calib::Camera seen = camera;
      if (c == kKnockedCamera && f == kKnockedFrame)
        seen.cam_from_world.rotation =
            Eigen::AngleAxisd(0.15 * M_PI / 180, Eigen::Vector3d::UnitY()) *
            seen.cam_from_world.rotation;
      cv::Mat image = calib::RenderTarget(seen, rays, prints, poses[f], options);
      if (c == 3 && f == kFrames - 1) image.setTo(90);
      char file[32];
      std::snprintf(file, sizeof file, "view_%03d.png", f);
      cv::imwrite((folder / file).string(), image);
    }
    shot.globs.emplace_back(camera.name, (folder / "*.png").string());
  }
  return shot;
}

// What `netlab calibrate` computes for these images, minus `excluded`
// (app/cli/calibrate_command.cc).
inline calib::Rig CliRig(const FoilShot& shot, const std::set<ImageKey>& excluded) {
  const calib::CalibrationTarget target =
      calib::CalibrationTarget::Parse((shot.dir / "foil.yaml").string());
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> files;
  for (const auto& [name, pattern] : shot.globs) {
    names.push_back(name);
    files.emplace_back();
    for (int f = 0; f < kFrames; ++f) {
      char file[32];
      std::snprintf(file, sizeof file, "view_%03d.png", f);
      files.back().push_back((shot.dir / name / file).string());
    }
  }
  calib::CalibrationInput input = calib::DetectInImages(names, files, target, {}, 2);
  std::erase_if(input.observations, [&](const calib::Observation& o) {
    return excluded.count({o.camera, o.frame}) != 0;
  });
  const fs::path out = shot.dir / "cli_rig.yaml";
  calib::WriteRig(out.string(),
                  calib::CalibrateRig(target, input, calib::CalibrationOptions{}).rig);
  return calib::ReadRig(out.string());
}

inline void ExpectSameRig(const calib::Rig& a, const calib::Rig& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t c = 0; c < a.cameras.size(); ++c) {
    const calib::Camera &x = a.cameras[c], &y = b.cameras[c];
    EXPECT_EQ(x.name, y.name);
    // Two runs of CalibrateRig on the same input agree to about the 15th digit.
    EXPECT_NEAR(x.intrinsics.fx, y.intrinsics.fx, 1e-6) << x.name;
    EXPECT_NEAR(x.intrinsics.cx, y.intrinsics.cx, 1e-6) << x.name;
    EXPECT_NEAR(x.intrinsics.distortion[0], y.intrinsics.distortion[0], 1e-9) << x.name;
    EXPECT_NEAR((x.Center() - y.Center()).norm(), 0.0, 1e-9) << x.name;
    EXPECT_NEAR(x.cam_from_world.rotation.angularDistance(y.cam_from_world.rotation), 0.0, 1e-9)
        << x.name;
  }
}

}  // namespace netlab::gui::testing
