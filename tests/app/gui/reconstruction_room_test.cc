// The reconstruction room in the window (Qt's offscreen platform), driven by mouse and keys, on
// the command tests' small net rendered by `netlab render` (0.1 s) with its true labels and rig,
// one label moved 12 px off its knot: Triangulate (netlab triangulate's engine on a worker;
// cancelled once, then run to the end), the moved label listed as an outlier with why; a click on
// it lands on that label in the labeling room (its frame, its camera maximised, its knot) and
// Ctrl+4 comes back. The 3D view follows the frame slider and the window's frame; a drag turns it,
// a right drag pans it, the wheel zooms. Export writes tracks.h5 equal to `netlab triangulate`'s
// from the same labels, and xyzpts.csv / xyzres.csv beside it equal to its --csv files byte for
// byte.

#include "app/gui/reconstruction_room.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <QAbstractItemModelTester>
#include <QApplication>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QSlider>
#include <QTableView>
#include <QTableWidget>
#include <QTest>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "app/gui/camera_view.h"
#include "app/gui/document/project.h"
#include "app/gui/document/session.h"
#include "app/gui/main_window.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/gui/small_shot_film.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

// A drag with `button` held from `from` to `to` (one move between press and release).
void Drag(QWidget* widget, Qt::MouseButton button, QPoint from, QPoint to) {
  QTest::mousePress(widget, button, {}, from);
  QMouseEvent move(QEvent::MouseMove, QPointF(to), widget->mapToGlobal(QPointF(to)), button, button,
                   Qt::NoModifier);
  QApplication::sendEvent(widget, &move);
  QTest::mouseRelease(widget, button, {}, to);
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
using testing::RunNetlab;

constexpr int kLastFrame = 17;                     // frames 0..17 (0.1 s at 179 fps)
constexpr int kMovedCamera = 1, kMovedFrame = 10;  // the label moved off its knot

const fs::path& Dir() {
  static const fs::path dir =
      fs::temp_directory_path() / ("netlab_reconstruction_room_" + std::to_string(getpid()));
  return dir;
}

bool WaitIdle(const ReconstructionRoom& room, int timeout_ms) {
  QElapsedTimer clock;
  clock.start();
  while (room.busy() && clock.elapsed() < timeout_ms) QTest::qWait(20);
  QTest::qWait(20);
  return !room.busy();
}

// The knot of the moved label: the first that every camera sees in that frame (with three views
// left, the point is placed and the moved one measured against it).
int moved_knot = -1;
int MovedKnot() { return moved_knot; }

class ReconstructionRoomTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Dir());
    fs::create_directories(Dir());
    const std::string d = Dir().string();
    const auto film =
        testing::FilmSmallShot(d, testing::SmallShotLasting(0.1), kLastFrame, "--scale 0.25");
    ASSERT_EQ(film.status, 0) << film.err;
    recon::LabelSet labels = recon::ReadLabels(d + "/shot/labels_true.h5");
    for (int k = 0; k < labels.knots() && moved_knot < 0; ++k) {
      bool all = true;
      for (int c = 0; c < static_cast<int>(labels.cameras.size()); ++c)
        all = all && labels.at(c, kMovedFrame, k).present();
      if (all) moved_knot = k;
    }
    ASSERT_GE(moved_knot, 0);
    recon::Label& moved = labels.at(kMovedCamera, kMovedFrame, MovedKnot());
    ASSERT_TRUE(moved.present());
    moved.px += Eigen::Vector2d(12.0, 0.0);
    recon::WriteLabels(d + "/labels.h5", labels);
    Project project = MakeProject(d + "/shot/experiment.yaml", d + "/shot/rig_true.yaml",
                                  d + "/coloring.yaml", d + "/labels.h5", 0, 0);
    project.target = d + "/sim.h5";  // the box, drawn in the 3D view
    SaveProject(project, d + "/project.yaml");
  }
  static void TearDownTestSuite() {
    if (!getenv("NETLAB_KEEP_TEST_FILES")) fs::remove_all(Dir());
  }
};

// The labeling room shown at the moved label: its frame, camera and knot.
void ExpectOnTheMovedLabel(MainWindow& w) {
  EXPECT_EQ(w.room(), MainWindow::Room::kLabeling);
  EXPECT_EQ(w.frame(), kMovedFrame);
  EXPECT_EQ(w.camera(), kMovedCamera);
  EXPECT_EQ(w.knot(), MovedKnot());
}

TEST_F(ReconstructionRoomTest, TriangulateClickAnOutlierLandOnItsLabelAndExportAsTheCli) {
  const std::string d = Dir().string();
  MainWindow w;
  w.resize(1500, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(d + "/project.yaml"), false));
  ASSERT_TRUE(w.WaitForFrame());
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);  // Room > Reconstruction room
  ASSERT_EQ(w.room(), MainWindow::Room::kReconstruction);
  ReconstructionRoom* room = w.reconstruction_room();
  EXPECT_FALSE(room->export_button()->isEnabled());

  // Bundle adjustment of the points (the default), the labels' sigma typed; Triangulate.
  EXPECT_EQ(room->adjustment_box()->currentText(), "points");
  room->sigma_box()->selectAll();
  QTest::keyClicks(room->sigma_box(), "0.100");
  // The options reach the engine's job: a link-length prior without bundle adjustment is
  // refused with why, as netlab triangulate refuses it.
  room->adjustment_box()->setCurrentText("none");
  room->link_box()->setValue(0.1);
  QTest::mouseClick(room->triangulate_button(), Qt::LeftButton);
  EXPECT_EQ(room->status_label()->text(),
            "Cannot triangulate: the priors (link length, smoothing) need bundle adjustment of the "
            "points or the rig");
  EXPECT_FALSE(room->busy());
  room->adjustment_box()->setCurrentText("points");
  room->link_box()->setValue(0.0);
  // Cancelled at once: said, nothing kept, the room free again.
  QTest::mouseClick(room->triangulate_button(), Qt::LeftButton);
  ASSERT_TRUE(room->cancel_button()->isEnabled());
  QTest::mouseClick(room->cancel_button(), Qt::LeftButton);
  EXPECT_EQ(room->status_label()->text(), "Triangulation cancelled.");
  EXPECT_FALSE(room->busy());
  EXPECT_EQ(w.reconstruction()->tracks(), nullptr);
  EXPECT_FALSE(room->export_button()->isEnabled());
  // Then to the end.
  QTest::mouseClick(room->triangulate_button(), Qt::LeftButton);
  ASSERT_TRUE(WaitIdle(*room, 60000));
  ASSERT_TRUE(room->export_button()->isEnabled()) << room->status_label()->text().toStdString();
  std::printf("%s\n", room->summary_label()->text().toStdString().c_str());

  // The moved label is an outlier, with why.
  int row = -1;
  const auto& problems = room->problems();
  for (size_t i = 0; i < problems.size(); ++i)
    if (!problems[i].degenerate && problems[i].camera == kMovedCamera &&
        problems[i].t == kMovedFrame && problems[i].knot == MovedKnot())
      row = static_cast<int>(i);
  ASSERT_GE(row, 0) << problems.size() << " problems listed";
  EXPECT_TRUE(problems[row].why.contains("px from the point's projection"))
      << problems[row].why.toStdString();
  EXPECT_LE(problems.size(), 3u) << "only the moved label should be in doubt";

  // A click on it: the labeling room at that label.
  QTableWidget* table = room->problems_table();
  table->scrollToItem(table->item(row, 0));
  QTest::mouseClick(table->viewport(), Qt::LeftButton, {},
                    table->visualItemRect(table->item(row, 0)).center());
  ExpectOnTheMovedLabel(w);
  EXPECT_EQ(w.maximised(), kMovedCamera);
  // And back.
  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
  EXPECT_EQ(w.room(), MainWindow::Room::kReconstruction);
  EXPECT_EQ(room->frame(), kMovedFrame);

  // The frame's knots with their residual and sigma: a model Qt's tester finds sound, sorted by a
  // header click, filtered to the outliers; a click on the moved knot's row lands on its label.
  KnotErrorModel* model = room->knot_model();
  QAbstractItemModelTester tester(model, QAbstractItemModelTester::FailureReportingMode::Fatal);
  ASSERT_EQ(model->rowCount(), 36);
  const KnotTracks* moved_tracks = w.reconstruction()->tracks();
  ASSERT_NE(moved_tracks, nullptr);
  const int moved_row = w.reconstruction()->TrackRow(kMovedFrame);
  for (int i = 0; i < model->rowCount(); ++i) {
    const KnotErrorModel::Row& r = model->row(i);
    const size_t at = static_cast<size_t>(moved_row) * 36 + r.knot;
    if (!moved_tracks->valid[at]) continue;
    EXPECT_DOUBLE_EQ(r.residual_px, moved_tracks->reprojection_error_px[at]);
    EXPECT_NEAR(r.sigma_mm * r.sigma_mm * 1e-6,
                Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(moved_tracks->covariance[at])
                    .eigenvalues()
                    .maxCoeff(),
                1e-15);
  }
  QHeaderView* header = room->knot_table()->horizontalHeader();
  const int residual_x = header->sectionViewportPosition(KnotErrorModel::kResidual) + 5;
  QTest::mouseClick(header->viewport(), Qt::LeftButton, {}, QPoint(residual_x, 5));
  if (header->sortIndicatorOrder() != Qt::DescendingOrder)
    QTest::mouseClick(header->viewport(), Qt::LeftButton, {}, QPoint(residual_x, 5));
  ASSERT_EQ(header->sortIndicatorSection(), KnotErrorModel::kResidual);
  for (int i = 1; i < model->rowCount(); ++i)
    EXPECT_GE(model->index(i - 1, KnotErrorModel::kResidual).data(Qt::UserRole).toDouble(),
              model->index(i, KnotErrorModel::kResidual).data(Qt::UserRole).toDouble())
        << "row " << i;
  room->knot_filter_box()->setCurrentText("outliers");
  ASSERT_GE(model->rowCount(), 1);
  ASSERT_LE(model->rowCount(), 3);
  int knot_row = -1;
  for (int i = 0; i < model->rowCount(); ++i)
    if (model->row(i).knot == MovedKnot()) knot_row = i;
  ASSERT_GE(knot_row, 0);
  EXPECT_EQ(model->index(knot_row, KnotErrorModel::kStatus).data().toString(), "outlier view");
  EXPECT_TRUE(model->index(knot_row, KnotErrorModel::kOutliers)
                  .data()
                  .toString()
                  .startsWith(QString::fromStdString(w.session()->camera_names()[kMovedCamera])))
      << model->index(knot_row, KnotErrorModel::kOutliers).data().toString().toStdString();
  QTableView* knots = room->knot_table();
  QTest::mouseClick(knots->viewport(), Qt::LeftButton, {},
                    knots->visualRect(model->index(knot_row, 0)).center());
  ExpectOnTheMovedLabel(w);
  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
  room->knot_filter_box()->setCurrentText("degenerate");
  for (int i = 0; i < model->rowCount(); ++i) EXPECT_TRUE(model->row(i).degenerate);
  room->knot_filter_box()->setCurrentText("all");

  // The 3D view follows the slider; the labeling room opens at the frame left.
  NetView3D* view = room->view();
  room->frame_slider()->setValue(4);
  EXPECT_EQ(room->frame(), 4);
  EXPECT_EQ(view->row(), 4);
  QTest::keyClick(&w, Qt::Key_3, Qt::ControlModifier);
  EXPECT_EQ(w.frame(), 4);
  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
  EXPECT_EQ(room->frame(), 4);
  const KnotTracks* tracks = w.reconstruction()->tracks();
  ASSERT_NE(tracks, nullptr);
  const auto centre = view->ToScreen(tracks->Position(4, MovedKnot()));
  ASSERT_TRUE(centre.has_value());
  EXPECT_TRUE(view->rect().contains(centre->toPoint()));
  // A click on the knot selects it: its residual and sigma.
  QTest::mouseClick(view, Qt::LeftButton, {}, centre->toPoint());
  EXPECT_EQ(view->selected(), std::set<int>{MovedKnot()});
  EXPECT_TRUE(room->knot_label()->text().contains("reprojection RMS"))
      << room->knot_label()->text().toStdString();
  // A drag turns the view, the wheel zooms it.
  const double yaw = view->yaw(), distance = view->distance();
  Drag(view, Qt::LeftButton, QPoint(100, 100), QPoint(160, 110));
  EXPECT_NE(view->yaw(), yaw);
  QWheelEvent wheel(QPointF(100, 100), view->mapToGlobal(QPointF(100, 100)), QPoint(),
                    QPoint(0, 120), Qt::NoButton, Qt::NoModifier, Qt::NoScrollPhase, false);
  QApplication::sendEvent(view, &wheel);
  EXPECT_LT(view->distance(), distance);
  // A right drag pans: the net follows the mouse, the view's angle and distance stay.
  const Eigen::Vector3d knot = tracks->Position(kMovedFrame, MovedKnot());
  const std::optional<QPointF> before_pan = view->ToScreen(knot);
  ASSERT_TRUE(before_pan.has_value());
  const double turned = view->yaw(), zoomed = view->distance();
  Drag(view, Qt::RightButton, QPoint(100, 100), QPoint(160, 100));
  const std::optional<QPointF> after_pan = view->ToScreen(knot);
  ASSERT_TRUE(after_pan.has_value());
  EXPECT_GT(after_pan->x() - before_pan->x(), 30.0);
  EXPECT_LT(std::abs(after_pan->y() - before_pan->y()), 15.0);
  EXPECT_EQ(view->yaw(), turned);
  EXPECT_EQ(view->distance(), zoomed);

  // Export: the CLI's files, its numbers.
  fs::create_directories(Dir() / "export");
  ASSERT_TRUE(room->ExportTo(QString::fromStdString((Dir() / "export/tracks.h5").string())));
  const auto cli =
      RunNetlab("triangulate --rig " + d + "/shot/rig_true.yaml --labels " + d +
                "/labels.h5 --knots 6x6 --fps 179 --sigma-px 0.1 --experiment " + d +
                "/shot/experiment.yaml --out " + d + "/cli_tracks.h5 --csv " + d + "/cli_ --quiet");
  ASSERT_EQ(cli.status, 0) << cli.err;
  // The DLTdv files are the CLI's --csv files, byte for byte.
  for (const char* name : {"xyzpts.csv", "xyzres.csv"}) {
    const std::string ours = ReadText((Dir() / "export" / name).string());
    EXPECT_FALSE(ours.empty()) << name;
    EXPECT_EQ(ours, ReadText(d + "/cli_" + name)) << name;
  }
  const KnotTracks ours = ReadKnotTracks(d + "/export/tracks.h5");
  const KnotTracks theirs = ReadKnotTracks(d + "/cli_tracks.h5");
  ASSERT_EQ(ours.position.size(), theirs.position.size());
  EXPECT_EQ(ours.valid, theirs.valid);
  EXPECT_EQ(ours.time, theirs.time);
  double worst = 0.0;
  for (size_t i = 0; i < ours.position.size(); ++i)
    if (ours.valid[i]) worst = std::max(worst, (ours.position[i] - theirs.position[i]).norm());
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ(ours.outliers.size(), theirs.outliers.size());
  // The project names the tracks the room wrote on triangulating.
  EXPECT_EQ(LoadProject(d + "/project.yaml").tracks, (Dir() / "tracks.h5").string());

  // A label moved in the labeling room: its frame's tracks follow at once, knot by knot.
  Session* s = w.session();
  int other = -1;
  for (int k = 0; k < tracks->knots() && other < 0; ++k)
    if (k != MovedKnot() && tracks->Valid(kMovedFrame, k) &&
        s->document().labels().at(0, kMovedFrame, k).accepted())
      other = k;
  ASSERT_GE(other, 0);
  const Eigen::Vector3d before = tracks->Position(kMovedFrame, other);
  const Eigen::Vector2d px = s->document().labels().at(0, kMovedFrame, other).px;
  s->PlaceLabel(0, kMovedFrame, other, px + Eigen::Vector2d(1.0, 0.0));
  EXPECT_EQ(w.reconstruction()->updated_rows(), std::set<int>{kMovedFrame});
  const recon::PointEstimate now = s->Triangulate(kMovedFrame, other);
  ASSERT_TRUE(now.valid);
  EXPECT_LT((tracks->Position(kMovedFrame, other) - now.position).norm(), 1e-12);
  EXPECT_GT((tracks->Position(kMovedFrame, other) - before).norm(), 1e-5);
  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
  EXPECT_TRUE(room->summary_label()->text().contains("1 frame triangulated again"))
      << room->summary_label()->text().toStdString();

  if (const char* out = getenv("NETLAB_RECONSTRUCTION_SCREENSHOT")) {
    room->SetFrame(kMovedFrame);
    QTest::mouseDClick(view, Qt::LeftButton, {}, QPoint(5, 5));  // fitted again
    if (getenv("NETLAB_RECONSTRUCTION_SIGMA")) {  // close to the net, the sigma shown
      view->SetView(view->yaw(), view->pitch(), 0.9);
      view->SetShowSigma(true);
    }
    QTest::qWait(50);
    ASSERT_TRUE(w.grab().save(out));
    std::printf("wrote %s\n", out);
  }
}

}  // namespace
}  // namespace netlab::gui
