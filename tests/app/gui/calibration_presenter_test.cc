// The calibration room without a window (app/gui/document/calibration_presenter.h): on the
// paper's rig (two stereo pairs 5.5 m apart, 1 m bases), the table's rows, the baselines nearest
// first, and the frusta of the 3D sketch (the centre first, the image corners at the depth asked,
// on the camera's side of its viewing direction).

#include "app/gui/document/calibration_presenter.h"

#include <gtest/gtest.h>

#include <QCoreApplication>

namespace netlab::gui {
namespace {

calib::Rig TwoPairs() {
  calib::Rig rig;
  rig.cameras = {calib::LookAtCamera("cam0", {-1.5, 0.5, 0.5}, {1, 0, 0}, 16.0, 5.5, 2048),
                 calib::LookAtCamera("cam1", {-1.5, -0.5, 0.5}, {1, 0, 0}, 16.0, 5.5, 2048),
                 calib::LookAtCamera("cam2", {4.0, -0.5, 0.5}, {1, 0, 0}, 25.0, 5.5, 2048),
                 calib::LookAtCamera("cam3", {4.0, 0.5, 0.5}, {1, 0, 0}, 25.0, 5.5, 2048)};
  return rig;
}

TEST(CalibrationPresenter, RowsAndBaselinesAreTheRigs) {
  const calib::Rig rig = TwoPairs();
  const CalibrationPresenter calibration(&rig, "rig.yaml");
  const std::vector<RigCameraRow> rows = calibration.Cameras();
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[2].name, "cam2");
  EXPECT_NEAR((rows[2].centre - Eigen::Vector3d(4.0, -0.5, 0.5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(rows[0].fx, 16.0 / 5.5e-3, 1e-6);
  const std::vector<Baseline> baselines = calibration.Baselines();
  ASSERT_EQ(baselines.size(), 6u);
  EXPECT_NEAR(baselines[0].length_m, 1.0, 1e-9);
  EXPECT_NEAR(baselines[1].length_m, 1.0, 1e-9);
  EXPECT_NEAR(baselines[2].length_m, 5.5, 1e-9);
  EXPECT_NEAR(baselines.back().length_m, std::hypot(5.5, 1.0), 1e-9);
  EXPECT_TRUE(calibration.Summary().startsWith("rig.yaml: 4 cameras · baselines cam0–cam1 1.000 m"))
      << calibration.Summary().toStdString();
}

TEST(CalibrationPresenter, AFrustumsCornersLieAtTheDepthAskedAndProjectToTheImageCorners) {
  const calib::Rig rig = TwoPairs();
  const CalibrationPresenter calibration(&rig, "rig.yaml");
  for (int c = 0; c < 4; ++c) {
    const auto f = calibration.Frustum(c, 0.4);
    const calib::Camera& camera = rig.cameras[c];
    EXPECT_NEAR((f[0] - camera.Center()).norm(), 0.0, 1e-9);
    for (int i = 1; i <= 4; ++i) {
      EXPECT_NEAR((f[i] - f[0]).dot(camera.ViewDirection()), 0.4, 1e-9);
      const Eigen::Vector2d q = camera.ProjectWorld(f[i]);
      // A pinhole frustum: the lens distortion of LookAtCamera is zero, so exactly the corners.
      EXPECT_NEAR(std::min(std::abs(q.x()), std::abs(q.x() - 2048)), 0.0, 1e-6);
      EXPECT_NEAR(std::min(std::abs(q.y()), std::abs(q.y() - 2048)), 0.0, 1e-6);
    }
  }
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
