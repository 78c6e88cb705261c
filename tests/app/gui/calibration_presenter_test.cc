// The calibration room without a window (app/gui/document/calibration_presenter.h): on the
// paper's rig (two stereo pairs 5.5 m apart, 1 m bases), the table's rows, the baselines nearest
// first, and the frusta of the 3D sketch; and the whole work on rendered images of the
// double-sided foil (the paper's rig at a quarter of its resolution, 512 px, 8 frames, one of
// cam1's images taken with the camera knocked by 0.15 deg): detection with per-image reasons,
// the calibration, excluding the worst image and re-running as one undoable step, and Save,
// whose rig equals what `netlab calibrate`'s code path (DetectInImages, CalibrateRig, WriteRig)
// gives for the same images and lies within the calibration's stated sigma of the true rig.

#include "app/gui/document/calibration_presenter.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <QCoreApplication>
#include <QUndoStack>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "app/gui/document/project.h"
#include "calibration/rig_compare.h"
#include "calibration/synthetic.h"
#include "tests/app/gui/foil_shot.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;
using namespace testing;  // the foil shot

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

// ---- From images to a saved rig.

CalibrationRun CalibrateNow(const CalibrationPresenter& calibration) {
  return CalibrationPresenter::Calibrate(calibration.MakeCalibrationJob());
}

TEST(CalibrationPresenter, DetectCalibrateExcludeTheWorstImageRerunAndSave) {
  const FoilShot shot = RenderFoilShot("netlab_calibration_presenter");
  std::string target;
  const auto globs = CalibrationPresenter::GlobsInFolder(shot.dir.string(), &target);
  EXPECT_EQ(globs, shot.globs);
  EXPECT_EQ(target, (shot.dir / "foil.yaml").string());

  // A project whose rig Save repoints.
  const fs::path project_path = shot.dir / "project.yaml";
  {
    std::ofstream p(project_path);
    p << "netlab_project: 1\nexperiment: shot/experiment.yaml\nrig: old_rig.yaml\n"
         "labels: labels.h5\nnet: {rows: 5, cols: 5}\n";
  }
  const calib::Rig old_rig = calib::PaperRig(0.25);
  CalibrationPresenter calibration(&old_rig, (shot.dir / "old_rig.yaml").string(),
                                   project_path.string());
  EXPECT_THROW(calibration.SetTarget((shot.dir / "nothing.yaml").string()), std::exception);
  calibration.SetTarget(target);
  EXPECT_THROW(calibration.SetImages({{"cam0", (shot.dir / "cam0/*.jpg").string()}}),
               std::runtime_error);
  calibration.SetImages(globs);
  ASSERT_EQ(calibration.cameras(), 4);
  ASSERT_EQ(calibration.frames(), kFrames);
  EXPECT_FALSE(calibration.detected());

  // Detection: a token cancelled before the start stops it at once; then the whole run.
  CancelToken cancel;
  cancel.Cancel();
  const DetectionAnswer cancelled =
      CalibrationPresenter::Detect(calibration.MakeDetectionJob(), ProgressReporter({}, cancel));
  EXPECT_TRUE(cancelled.cancelled);
  int last_done = 0, last_total = 0;
  calibration.SetDetections(CalibrationPresenter::Detect(calibration.MakeDetectionJob(),
                                                         ProgressReporter([&](const Progress& p) {
                                                           last_done = static_cast<int>(p.done);
                                                           last_total = static_cast<int>(p.total);
                                                         })));
  EXPECT_EQ(last_done, 4 * kFrames);
  EXPECT_EQ(last_total, 4 * kFrames);
  ASSERT_TRUE(calibration.detected());
  const CalibrationImage& blank = calibration.image({3, kFrames - 1});
  EXPECT_EQ(blank.status, CalibrationImage::Status::kFailed);
  EXPECT_EQ(blank.why, "no chessboard of 9x6 inner corners found");
  EXPECT_EQ(calibration.image({0, 0}).status, CalibrationImage::Status::kFound);
  EXPECT_EQ(calibration.image({0, 0}).found.ids.size(), 54u);
  EXPECT_TRUE(calibration.DetectionSummary().startsWith(
      "32 of 32 images searched: the target found in 31, 1 failed"))
      << calibration.DetectionSummary().toStdString();

  // Calibrate: the worst image is the knocked one.
  EXPECT_FALSE(calibration.NeedsCalibration());
  calibration.SetCalibration(CalibrateNow(calibration));
  ASSERT_NE(calibration.result(), nullptr) << calibration.CalibrationText().toStdString();
  const double rms_all = calibration.result()->summary.rms_px;
  ASSERT_EQ(calibration.WorstImage(), ImageKey(kKnockedCamera, kKnockedFrame));
  const double worst_rms = *calibration.ImageRms({kKnockedCamera, kKnockedFrame});
  EXPECT_GT(worst_rms, 3 * *calibration.ImageRms({0, 0}));
  EXPECT_FALSE(calibration.ImageRms({3, kFrames - 1}).has_value());
  // Its residuals are its largest; the coverage counts every point of the images used.
  const auto residuals = calibration.Residuals({kKnockedCamera, kKnockedFrame});
  EXPECT_EQ(residuals.size(), 54u);
  double sum = 0.0;
  for (const PointResidual& r : residuals) sum += r.residual.squaredNorm();
  EXPECT_NEAR(std::sqrt(sum / residuals.size()), worst_rms, 0.3 * worst_rms);
  const CoverageGrid coverage = calibration.Coverage(3);
  int points = 0;
  for (int n : coverage.counts) points += n;
  EXPECT_EQ(points, 54 * (kFrames - 1));
  EXPECT_TRUE(calibration.CalibrationText().contains("Metric check"))
      << calibration.CalibrationText().toStdString();
  // What the CLI writes for the same images.
  ExpectSameRig(calibration.result()->rig, CliRig(shot, {}));

  // Exclude the worst image: one step; the re-run is wanted, then answers.
  calibration.ToggleExcluded(*calibration.WorstImage());
  EXPECT_EQ(calibration.undo_stack()->count(), 1);
  EXPECT_TRUE(calibration.is_excluded({kKnockedCamera, kKnockedFrame}));
  EXPECT_TRUE(calibration.NeedsCalibration());
  EXPECT_EQ(calibration.result(), nullptr);
  calibration.SetCalibration(CalibrateNow(calibration));
  ASSERT_NE(calibration.result(), nullptr);
  const double rms_without = calibration.result()->summary.rms_px;
  EXPECT_LT(rms_without, 0.7 * rms_all);
  EXPECT_FALSE(calibration.ImageRms({kKnockedCamera, kKnockedFrame}).has_value());
  // Undo brings the first result back at once (no re-run), redo the second.
  calibration.undo_stack()->undo();
  EXPECT_FALSE(calibration.NeedsCalibration());
  EXPECT_EQ(calibration.result()->summary.rms_px, rms_all);
  calibration.undo_stack()->redo();
  EXPECT_EQ(calibration.result()->summary.rms_px, rms_without);

  // Save: the CLI's rig for the same images, within the stated sigma of the truth; the project
  // names it.
  const fs::path saved = shot.dir / "rig.yaml";
  calibration.Save(saved.string());
  EXPECT_TRUE(calibration.saved());
  EXPECT_FALSE(fs::exists(saved.string() + ".partial"));
  const calib::Rig rig = calib::ReadRig(saved.string());
  ExpectSameRig(rig, CliRig(shot, {{kKnockedCamera, kKnockedFrame}}));
  const calib::RigComparison comparison = calib::CompareRigs(rig, shot.truth, false);
  for (size_t c = 0; c < 4; ++c) {
    const double sigma = calibration.result()->summary.cameras[c].position_sigma_m;
    EXPECT_GT(sigma, 0.0);
    EXPECT_LT(comparison.cameras[c].centre_error_m, 3 * sigma)
        << comparison.cameras[c].name << " sigma " << sigma;
  }
  EXPECT_EQ(LoadProject(project_path.string()).rig, saved.string());
  fs::remove_all(shot.dir);
}

}  // namespace
}  // namespace netlab::gui
