// The calibration room driven by a person's mouse and keys (Qt's offscreen platform), on the
// rendered foil images of tests/app/gui/foil_shot.h: type the target, add the cameras and type
// their globs, Detect and Cancel (the answer says cancelled, Calibrate waits), Detect, Calibrate,
// click the worst image's Used cell (it is excluded and the rig calibrated again), Ctrl+Z and
// Ctrl+Shift+Z, Save. The saved rig equals what `netlab calibrate`'s code path gives for the same
// images. The image view draws the corners and the residual arrows where the image's points are.
//
// With NETLAB_CALIBRATION_TWIN=SHOT (a rendered twin's shot folder: experiment.yaml,
// calibration/camN/*.png, calibration/foil.yaml, rig_true.yaml) the same session runs in the
// window on a project over it: the detection and calibration times, and the saved rig against the
// true one, are printed; with NETLAB_CALIBRATION_SCREENSHOT=OUT.png the window is saved as the
// person sees it.

#include "app/gui/calibration_room.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <QCheckBox>
#include <QElapsedTimer>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QProgressBar>
#include <QPushButton>
#include <QTableWidget>
#include <QTest>
#include <QUndoStack>
#include <cstdlib>

#include "app/gui/document/project.h"
#include "app/gui/document/session.h"
#include "app/gui/main_window.h"
#include "calibration/rig_compare.h"
#include "tests/app/gui/foil_shot.h"

namespace netlab::gui {
namespace {

using namespace testing;  // the foil shot

void Click(QWidget* widget) { QTest::mouseClick(widget, Qt::LeftButton); }

// A click on a table cell, where a person clicks.
void ClickCell(QTableWidget* table, int row, int column) {
  table->scrollToItem(table->item(row, column));
  const QRect cell = table->visualItemRect(table->item(row, column));
  QTest::mouseClick(table->viewport(), Qt::LeftButton, {}, cell.center());
}

bool WaitIdle(const CalibrationRoom& room, int timeout_ms) {
  QElapsedTimer clock;
  clock.start();
  while (room.busy() && clock.elapsed() < timeout_ms) QTest::qWait(20);
  QTest::qWait(20);
  return !room.busy();
}

std::pair<double, double> RunDetectAndCalibrate(CalibrationRoom& room, int timeout_ms);

// The person's session up to the exclusion: the target typed, one row per camera added and its
// glob typed, Detect, Calibrate. Returns the seconds detection and calibration took.
std::pair<double, double> DetectAndCalibrate(
    CalibrationRoom& room, const std::string& target,
    const std::vector<std::pair<std::string, std::string>>& globs, int timeout_ms) {
  QTest::mouseClick(room.target_edit(), Qt::LeftButton);
  QTest::keyClicks(room.target_edit(), QString::fromStdString(target));
  QPushButton* add = nullptr;
  for (QPushButton* b : room.findChildren<QPushButton*>())
    if (b->text() == "Add camera") add = b;
  EXPECT_NE(add, nullptr);
  for (const auto& [name, pattern] : globs) {
    Click(add);  // a row named camN, its glob's editor open
    const int row = room.globs_table()->rowCount() - 1;
    room.globs_table()->item(row, 0)->setText(QString::fromStdString(name));
    QWidget* editor = QApplication::focusWidget();
    EXPECT_NE(editor, nullptr);
    if (editor == nullptr) break;
    QTest::keyClicks(editor, QString::fromStdString(pattern));
    QTest::keyClick(editor, Qt::Key_Return);
  }
  EXPECT_EQ(room.globs_table()->rowCount(), static_cast<int>(globs.size()));
  // Detect, then Cancel at once: the images reached are kept, Calibrate waits for all.
  Click(room.detect_button());
  EXPECT_TRUE(room.cancel_button()->isEnabled());
  Click(room.cancel_button());
  EXPECT_TRUE(WaitIdle(room, timeout_ms));
  EXPECT_TRUE(room.status_label()->text().contains("(cancelled)"))
      << room.status_label()->text().toStdString();
  EXPECT_FALSE(room.calibrate_button()->isEnabled());
  return RunDetectAndCalibrate(room, timeout_ms);
}

// Detect, then Calibrate, each waited for: the seconds they took.
std::pair<double, double> RunDetectAndCalibrate(CalibrationRoom& room, int timeout_ms) {
  QElapsedTimer clock;
  clock.start();
  Click(room.detect_button());
  EXPECT_TRUE(room.cancel_button()->isEnabled());
  EXPECT_TRUE(WaitIdle(room, timeout_ms));
  const double detect_s = clock.elapsed() / 1000.0;
  EXPECT_TRUE(room.calibrate_button()->isEnabled()) << room.status_label()->text().toStdString();
  clock.restart();
  Click(room.calibrate_button());
  EXPECT_TRUE(WaitIdle(room, timeout_ms));
  return {detect_s, clock.elapsed() / 1000.0};
}

TEST(CalibrationRoom, APersonCalibratesExcludesTheWorstImageUndoesAndSaves) {
  const FoilShot shot = RenderFoilShot("netlab_calibration_room");
  const calib::Rig old_rig = calib::PaperRig(0.25);
  CalibrationPresenter presenter(&old_rig, "old_rig.yaml");
  CalibrationRoom room;
  room.resize(1600, 1000);
  room.show();
  room.Show(&presenter);
  ASSERT_TRUE(QTest::qWaitForWindowExposed(&room));
  // Detect without a target: said, nothing run.
  Click(room.detect_button());
  EXPECT_TRUE(room.status_label()->text().startsWith("Choose the target first"));

  DetectAndCalibrate(room, (shot.dir / "foil.yaml").string(), shot.globs, 60000);
  ASSERT_NE(presenter.result(), nullptr) << room.results_label()->text().toStdString();
  EXPECT_EQ(room.images_table()->rowCount(), 4 * kFrames);
  EXPECT_EQ(room.progress()->maximum(), 4 * kFrames);
  EXPECT_EQ(room.progress()->value(), 4 * kFrames);
  // The blank image is listed failed, with why.
  EXPECT_EQ(
      room.images_table()->item(3 * kFrames + kFrames - 1, CalibrationRoom::kUsedColumn)->text(),
      "failed: no chessboard of 9x6 inner corners found");
  EXPECT_EQ(room.cameras_table()->rowCount(), 4);
  EXPECT_TRUE(room.results_label()->text().contains("Metric check"));
  EXPECT_TRUE(room.summary_label()->text().startsWith("calibrated here (not saved)"));
  const double rms_all = presenter.result()->summary.rms_px;

  // The worst image: the knocked one, its RMS in bold.
  const int worst_row = kKnockedCamera * kFrames + kKnockedFrame;
  ASSERT_EQ(presenter.WorstImage(), ImageKey(kKnockedCamera, kKnockedFrame));
  EXPECT_TRUE(room.images_table()->item(worst_row, 3)->font().bold());

  // Its view: the corners green where they were found, the residuals red and scaled.
  ClickCell(room.images_table(), worst_row, 1);
  ASSERT_TRUE(WaitIdle(room, 10000));
  CalibrationImageView* view = room.image_view();
  EXPECT_GT(view->residual_scale(), 0.0);
  const CalibrationImage& knocked = presenter.image({kKnockedCamera, kKnockedFrame});
  QCheckBox* residuals = nullptr;
  for (QCheckBox* box : room.findChildren<QCheckBox*>())
    if (box->text() == "Residuals") residuals = box;
  ASSERT_NE(residuals, nullptr);
  Click(residuals);  // off: the crosses alone
  QImage drawn = view->grab().toImage();
  const QPointF corner = view->ToScreen(knocked.found.pixels[0]) + QPointF(3, 0);
  const QColor at_corner = drawn.pixelColor(corner.toPoint());
  EXPECT_GT(at_corner.green(), at_corner.red() + 50) << at_corner.name().toStdString();
  EXPECT_GT(at_corner.green(), at_corner.blue() + 50) << at_corner.name().toStdString();
  Click(residuals);  // on: an arrow from every point
  drawn = view->grab().toImage();
  const std::vector<PointResidual> arrows = presenter.Residuals({kKnockedCamera, kKnockedFrame});
  ASSERT_FALSE(arrows.empty());
  const PointResidual& longest = *std::max_element(
      arrows.begin(), arrows.end(), [](const PointResidual& a, const PointResidual& b) {
        return a.residual.norm() < b.residual.norm();
      });
  const QPointF tip =
      view->ToScreen(longest.pixel + 0.75 * view->residual_scale() * longest.residual);
  const QColor at_tip = drawn.pixelColor(tip.toPoint());
  EXPECT_GT(at_tip.red(), 180) << at_tip.name().toStdString();
  EXPECT_LT(at_tip.green(), 120) << at_tip.name().toStdString();

  // A click on its Used cell: excluded, calibrated again (one step).
  ClickCell(room.images_table(), worst_row, CalibrationRoom::kUsedColumn);
  ASSERT_TRUE(WaitIdle(room, 60000));
  EXPECT_TRUE(presenter.is_excluded({kKnockedCamera, kKnockedFrame}));
  ASSERT_NE(presenter.result(), nullptr);
  const double rms_without = presenter.result()->summary.rms_px;
  EXPECT_LT(rms_without, 0.7 * rms_all);
  EXPECT_EQ(room.images_table()->item(worst_row, CalibrationRoom::kUsedColumn)->text(),
            "✗ excluded");
  EXPECT_EQ(room.images_table()->item(worst_row, 3)->text(), "");

  // Ctrl+Z brings the first result back, Ctrl+Shift+Z the second.
  QTest::keyClick(room.images_table(), Qt::Key_Z, Qt::ControlModifier);
  ASSERT_TRUE(WaitIdle(room, 60000));
  EXPECT_TRUE(presenter.excluded().empty());
  EXPECT_EQ(presenter.result()->summary.rms_px, rms_all);
  EXPECT_EQ(room.images_table()->item(worst_row, CalibrationRoom::kUsedColumn)->text(), "✓");
  QTest::keyClick(room.images_table(), Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
  ASSERT_TRUE(WaitIdle(room, 60000));
  EXPECT_EQ(presenter.result()->summary.rms_px, rms_without);

  // Save (the dialog's answer given): the CLI's rig for the same images.
  EXPECT_TRUE(room.save_button()->isEnabled());
  const fs::path saved = shot.dir / "rig.yaml";
  ASSERT_TRUE(room.SaveTo(QString::fromStdString(saved.string())));
  ExpectSameRig(calib::ReadRig(saved.string()), CliRig(shot, {{kKnockedCamera, kKnockedFrame}}));
  EXPECT_TRUE(room.summary_label()->text().startsWith(QString::fromStdString(saved.string())));
  room.Show(nullptr);
  fs::remove_all(shot.dir);
}

// Inputs that cannot be used are said, naming what is wrong, and nothing runs.
TEST(CalibrationRoom, BadInputsAreSaidAndNothingRuns) {
  const fs::path dir =
      fs::temp_directory_path() / ("netlab_calibration_bad_" + std::to_string(getpid()));
  fs::create_directories(dir / "cam0");
  CalibrationPresenter presenter(nullptr, "");
  CalibrationRoom room;
  room.resize(1200, 800);
  room.show();
  room.Show(&presenter);
  ASSERT_TRUE(QTest::qWaitForWindowExposed(&room));
  room.FillFromFolder(QString::fromStdString(dir.string()));  // no images in cam0/
  EXPECT_TRUE(room.status_label()->text().contains("no sub-folder with images"))
      << room.status_label()->text().toStdString();
  QTest::keyClicks(room.target_edit(), "chessboard:9x6");
  Click(room.detect_button());
  EXPECT_TRUE(room.status_label()->text().startsWith("Choose the images first"))
      << room.status_label()->text().toStdString();
  room.globs_table()->insertRow(0);
  room.globs_table()->setItem(0, 0, new QTableWidgetItem("cam0"));
  room.globs_table()->setItem(
      0, 1, new QTableWidgetItem(QString::fromStdString((dir / "cam0/*.png").string())));
  Click(room.detect_button());
  EXPECT_TRUE(room.status_label()->text().startsWith("Target: "))
      << room.status_label()->text().toStdString();
  room.target_edit()->setText("chessboard:9x6:0.06");
  Click(room.detect_button());
  EXPECT_TRUE(room.status_label()->text().contains("matches no file"))
      << room.status_label()->text().toStdString();
  EXPECT_FALSE(room.busy());
  EXPECT_FALSE(room.calibrate_button()->isEnabled());
  room.Show(nullptr);
  fs::remove_all(dir);
}

// The twin's foil images (see the top of this file), in the window: a project over the twin's
// recording opens in the calibration room with the images and the foil filled in; Detect,
// Calibrate, the worst image left out, Save; the project is opened again with the saved rig and
// the room keeps its work.
TEST(CalibrationRoom, TheTwinsFoilImagesInTheWindow) {
  const char* twin = std::getenv("NETLAB_CALIBRATION_TWIN");
  if (twin == nullptr) GTEST_SKIP() << "NETLAB_CALIBRATION_TWIN not set";
  const fs::path shot = twin;
  const calib::Rig truth = calib::ReadRig((shot / "rig_true.yaml").string());
  const fs::path dir =
      fs::temp_directory_path() / ("netlab_twin_project_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(shot / "rig_true.yaml", dir / "rig_before.yaml");
  const std::string project = (dir / "project.yaml").string();
  SaveProject(MakeProject((shot / "experiment.yaml").string(), (dir / "rig_before.yaml").string(),
                          "", (dir / "labels.h5").string(), 11, 11),
              project);
  MainWindow w;
  w.resize(1600, 1000);
  w.show();
  QString error;
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false, &error)) << error.toStdString();
  ASSERT_TRUE(QTest::qWaitForWindowExposed(&w));
  w.ShowRoom(MainWindow::Room::kCalibration);
  CalibrationRoom& room = *w.calibration_room();
  ASSERT_EQ(room.globs_table()->rowCount(), 4);  // shot/calibration/camN/*.png
  ASSERT_TRUE(room.target_edit()->text().endsWith("foil.yaml"));
  const auto [detect_s, calibrate_s] = RunDetectAndCalibrate(room, 600000);
  const CalibrationPresenter& presenter = *w.calibration();
  ASSERT_NE(presenter.result(), nullptr) << room.results_label()->text().toStdString();
  std::printf("twin: %s\n", presenter.DetectionSummary().toStdString().c_str());
  for (const CalibrationImage& image : presenter.images())
    if (image.status == CalibrationImage::Status::kFailed)
      std::printf("twin: %s %s failed: %s\n", presenter.camera_name(image.camera).c_str(),
                  fs::path(image.path).filename().c_str(), image.why.c_str());
  const ImageKey worst = *presenter.WorstImage();
  std::printf(
      "twin: %d images, detection %.1f s, calibration %.1f s, RMS %.3f px; worst image "
      "%s %s (%.3f px)\n",
      static_cast<int>(presenter.images().size()), detect_s, calibrate_s,
      presenter.result()->summary.rms_px, presenter.camera_name(worst.first).c_str(),
      presenter.image(worst).path.c_str(), *presenter.ImageRms(worst));
  ClickCell(room.images_table(), worst.first * presenter.frames() + worst.second,
            CalibrationRoom::kUsedColumn);
  QElapsedTimer clock;
  clock.start();
  ASSERT_TRUE(WaitIdle(room, 600000));
  ASSERT_NE(presenter.result(), nullptr);
  std::printf("twin: without it, calibration %.1f s, RMS %.3f px\n", clock.elapsed() / 1000.0,
              presenter.result()->summary.rms_px);

  const std::string saved = (dir / "rig.yaml").string();
  ASSERT_TRUE(room.SaveTo(QString::fromStdString(saved)));
  // The project names the rig, the window works with it, the room kept its work.
  EXPECT_EQ(LoadProject(project).rig, saved);
  ASSERT_NE(w.session(), nullptr);
  EXPECT_EQ(w.session()->project().rig, saved);
  const calib::Rig rig = calib::ReadRig(saved);
  ExpectSameRig(w.session()->rig(), rig);
  EXPECT_EQ(w.room(), MainWindow::Room::kCalibration);
  ASSERT_EQ(w.calibration(), &presenter);
  ASSERT_NE(presenter.result(), nullptr);
  EXPECT_TRUE(presenter.saved());

  calib::Rig true_cameras;
  for (const calib::Camera& c : rig.cameras)
    true_cameras.cameras.push_back(truth.cameras[truth.Find(c.name)]);
  const calib::RigComparison comparison = calib::CompareRigs(rig, true_cameras, false);
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const double sigma = presenter.result()->summary.cameras[c].position_sigma_m;
    std::printf("twin: %s centre error %.2f mm, stated sigma %.2f mm\n",
                rig.cameras[c].name.c_str(), 1000 * comparison.cameras[c].centre_error_m,
                1000 * sigma);
    EXPECT_LT(comparison.cameras[c].centre_error_m, 3 * sigma) << rig.cameras[c].name;
  }
  if (const char* screenshot = std::getenv("NETLAB_CALIBRATION_SCREENSHOT")) {
    // The knocked camera's next image shown with its coverage.
    ClickCell(room.images_table(),
              worst.first * presenter.frames() + (worst.second + 1) % presenter.frames(), 1);
    for (QCheckBox* box : room.findChildren<QCheckBox*>())
      if (box->text() == "Coverage") Click(box);
    ASSERT_TRUE(WaitIdle(room, 10000));
    ASSERT_TRUE(w.grab().save(screenshot));
    std::printf("twin: wrote %s\n", screenshot);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace netlab::gui
