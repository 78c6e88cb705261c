// The workstation's window on a shot rendered by `netlab render`, driven by real mouse and key
// events (Qt's offscreen platform): a scripted person seeds the corners, runs Find Path and a
// tracking run, fixes every review item with Find Node at the true place, saves. The labels file
// must equal what the same actions give on the engine without a window, with no wrong accepted
// label. And a screenshot: the overlays are drawn where the labels are.

#include "app/gui/main_window.h"

#include <gtest/gtest.h>

#include <QAction>
#include <QApplication>
#include <QDialog>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QFileDialog>
#include <QHeaderView>
#include <QInputDialog>
#include <QLabel>
#include <QLineEdit>
#include <QMenu>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QSettings>
#include <QSpinBox>
#include <QStatusBar>
#include <QTabBar>
#include <QTableView>
#include <QTableWidget>
#include <QTest>
#include <QTextBrowser>
#include <QTimer>
#include <QUndoStack>
#include <QWheelEvent>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "app/gui/calibration_room.h"
#include "app/gui/camera_view.h"
#include "app/gui/document/project.h"
#include "app/gui/knot_grid.h"
#include "app/gui/recording_room.h"
#include "app/gui/settings.h"
#include "app/gui/shortcut_editor.h"
#include "app/gui/timeline.h"
#include "common/hdf5_util.h"
#include "libreconstruct/geometry/triangulation.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/gui/scripted_person.h"
#include "tests/app/gui/small_shot_film.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;
using testing::RunNetlab;

constexpr int kLastFrame = 30;  // frames 0..30: a tracking run of 30 frames

const fs::path& Dir() {
  static const fs::path dir =
      fs::temp_directory_path() / ("netlab_gui_test_" + std::to_string(getpid()));
  return dir;
}

// Shows `w` (1400 x 1000), opens `project` in it, waits for its first frame to be drawn and for
// it to be the active window (so that its keys reach it).
void OpenShown(MainWindow& w, const std::string& project) {
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
}

class MainWindowTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Dir());
    fs::create_directories(Dir());
    // The command tests' small shot (a 6 x 6-knot net past a box), 0.2 s long (36 frames).
    const auto film =
        testing::FilmSmallShot(Dir().string(), testing::SmallShotLasting(0.2), kLastFrame);
    ASSERT_EQ(film.status, 0) << film.err;
  }
  static void TearDownTestSuite() {
    if (!getenv("NETLAB_KEEP_TEST_FILES")) fs::remove_all(Dir());
  }

  // A project over the rendered shot whose labels go to `labels` (copied from `start` if given).
  std::string MakeProjectFile(const std::string& name, const std::string& start = "") {
    const std::string d = Dir().string();
    const std::string labels = d + "/" + name + ".h5";
    fs::remove(labels);
    fs::remove(labels + ".journal");
    if (!start.empty()) fs::copy_file(start, labels);
    const std::string path = d + "/" + name + ".yaml";
    SaveProject(MakeProject(d + "/shot/experiment.yaml", d + "/shot/rig_true.yaml",
                            d + "/coloring.yaml", labels, 0, 0),
                path);
    return path;
  }
  static recon::LabelSet Truth() {
    return recon::ReadLabels((Dir() / "shot/labels_true.h5").string());
  }
};

TEST_F(MainWindowTest, AScriptedSessionLabelsAsTheEngineDoesWithNoWrongLabel) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("session");
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const ScriptedSession session = PlayScriptedSession(&w, truth);
  ASSERT_TRUE(session.finished) << "the tracking run did not end";
  const std::vector<Action>& actions = session.actions;
  EXPECT_TRUE(s->document().ReviewItems().empty())
      << s->document().ReviewItems().size() << " review items and " << s->missing().size()
      << " missing knots left after " << session.review_items << " items walked";
  std::printf("scripted session: %d queue items walked, %zu actions; %d missing knots left\n",
              session.review_items, actions.size(), s->missing().size());
  QTest::keyClick(&w, Qt::Key_S, Qt::ControlModifier);
  ASSERT_FALSE(s->document().modified()) << w.statusBar()->currentMessage().toStdString();
  const recon::LabelSet saved = recon::ReadLabels(s->project().labels);

  // No accepted label off its knot (> 2 px) or on a hidden knot; the run carried the labels to
  // the last frame (every frame has accepted labels in two cameras at least).
  int accepted = 0, wrong = 0;
  std::vector<std::set<int>> cameras_with_labels(saved.frames());
  for (int c = 0; c < s->cameras(); ++c)
    for (int t = 0; t < saved.frames(); ++t)
      for (int k = 0; k < saved.knots(); ++k) {
        const recon::Label& l = saved.at(c, t, k);
        if (!l.present() || l.state != recon::LabelState::kAccepted) continue;
        ++accepted;
        cameras_with_labels[t].insert(c);
        const recon::Label& want = truth.at(truth.FindCamera(saved.cameras[c]), t, k);
        wrong += !want.present() || (l.px - want.px).norm() > 2.0;
      }
  EXPECT_EQ(wrong, 0);
  for (int t = 0; t < saved.frames(); ++t) EXPECT_GE(cameras_with_labels[t].size(), 2u) << t;
  EXPECT_GT(accepted, 20 * (kLastFrame + 1));

  // The same actions on the engine, without a window.
  auto engine = Session::Open(LoadProject(MakeProjectFile("engine")));
  for (const Action& a : actions) switch (a.kind) {
      case Action::kFindNode: engine->FindNode(a.camera, a.t, a.knot, a.px, 6.0); break;
      case Action::kPlace: engine->PlaceLabel(a.camera, a.t, a.knot, a.px); break;
      case Action::kDelete: engine->DeleteLabel(a.camera, a.t, a.knot); break;
      case Action::kAccept: engine->AcceptLabel(a.camera, a.t, a.knot); break;
      case Action::kFindPath: engine->FindPathFromCorners(0); break;
      case Action::kTrack:
        engine->ApplyTrackRun(engine->Track(engine->document().labels(), a.t, kLastFrame, {},
                                            MainWindow::kMaxReviewPerFrame));
        break;
      case Action::kHide: engine->MarkHidden(a.camera, a.t, a.knot); break;
      case Action::kHideRun: engine->MarkHiddenRun(a.camera, a.t, a.knot); break;
    }
  const recon::LabelSet& direct = engine->document().labels();
  int differ = 0;
  for (int c = 0; c < s->cameras(); ++c)
    for (int t = 0; t < saved.frames(); ++t)
      for (int k = 0; k < saved.knots(); ++k) {
        const recon::Label &a = saved.at(c, t, k), &b = direct.at(c, t, k);
        const bool different = a.present() != b.present() || a.state != b.state ||
                               a.source != b.source || (a.present() && (a.px - b.px).norm() > 1e-9);
        if (different && ++differ <= 5)
          ADD_FAILURE() << "camera " << c << " frame " << t << " knot " << k << ": window "
                        << (a.present() ? "present" : "absent") << " state " << int(a.state)
                        << " source " << int(a.source) << ", engine "
                        << (b.present() ? "present" : "absent") << " state " << int(b.state)
                        << " source " << int(b.source);
      }
  EXPECT_EQ(differ, 0);
  // Every step is undoable: undoing all of them empties the labels.
  while (s->document().undo_stack()->canUndo()) QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_EQ(s->document().labels().CountPresent(), 0);
}

TEST_F(MainWindowTest, TheScreenshotDrawsTheOverlaysWhereTheLabelsAre) {
  const std::string project =
      MakeProjectFile("screenshot", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  const QImage shot = w.grab().toImage();
  shot.save((Dir() / "screenshot.png").string().c_str());
  // Not blank: the frame's pixels vary.
  std::set<QRgb> colours;
  for (int y = 0; y < shot.height(); y += 7)
    for (int x = 0; x < shot.width(); x += 7) colours.insert(shot.pixel(x, y));
  EXPECT_GT(colours.size(), 50u);
  // At every label of camera 0, the ring of an imported label is drawn (pale blue).
  const recon::LabelSet& labels = w.session()->document().labels();
  int checked = 0, drawn = 0;
  for (int k = 0; k < labels.knots(); ++k) {
    const recon::Label& l = labels.at(0, 0, k);
    if (!l.present()) continue;
    ++checked;
    const QPoint centre = w.view(0)->mapTo(&w, w.view(0)->ToWidget(l.px).toPoint());
    bool found = false;
    for (int dy = -5; dy <= 5 && !found; ++dy)
      for (int dx = -5; dx <= 5 && !found; ++dx) {
        const QColor c = shot.pixelColor(centre + QPoint(dx, dy));
        found = std::abs(c.red() - 200) < 40 && std::abs(c.green() - 200) < 40 && c.blue() > 215;
      }
    drawn += found;
  }
  EXPECT_GT(checked, 20);
  EXPECT_EQ(drawn, checked);
}

// Clicking a label selects its knot and camera; the colours panel then shows what the knot's code
// expects (a swatch per link) and what its yarns say, read on a worker. On true labels the yarns
// never say "mismatch"; where they say "consistent" they fit the knot itself (on this small shot
// the thin yarns mostly read "unreadable": the check says nothing it is not sure of).
TEST_F(MainWindowTest, TheColoursPanelSaysWhatTheSelectedKnotsYarnsSay) {
  const std::string project = MakeProjectFile("colours", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  auto* dock = w.findChild<QDockWidget*>("colours_dock");
  ASSERT_NE(dock, nullptr);
  auto* panel = qobject_cast<QLabel*>(dock->widget());
  ASSERT_NE(panel, nullptr);
  const recon::LabelSet& labels = w.session()->document().labels();
  int read = 0, consistent = 0;
  for (int c = 0; c < w.session()->cameras(); ++c)
    for (int k = 0; k < labels.knots(); ++k) {
      const int row = k / labels.cols, col = k % labels.cols;
      if (row == 0 || col == 0 || row + 1 == labels.rows || col + 1 == labels.cols ||
          !labels.at(c, 0, k).present())
        continue;  // inner knots (four links) the camera sees
      QTest::mouseClick(w.view(c), Qt::LeftButton, Qt::NoModifier,
                        w.view(c)->ToWidget(labels.at(c, 0, k).px).toPoint());
      const QString name = QString("(%1, %2)").arg(row).arg(col);
      QTRY_VERIFY_WITH_TIMEOUT(
          panel->text().contains("the yarns say") && panel->text().contains("knot " + name), 10000);
      const QString text = panel->text();
      ++read;
      EXPECT_EQ(text.count("background-color"), 4) << text.toStdString();
      EXPECT_FALSE(text.contains(">mismatch<")) << text.toStdString();
      if (text.contains(">consistent<")) {
        ++consistent;
        EXPECT_TRUE(text.contains("they fit " + name)) << text.toStdString();
      }
      if (read == 1) w.grab().save((Dir() / "colours.png").string().c_str());
    }
  EXPECT_GT(read, 30);
  std::printf("colours panel: %d of %d true inner labels read consistent\n", consistent, read);
}

TEST_F(MainWindowTest, ALabelsFileOfOtherFramesAndCameraOrderKeepsItsReviewReasons) {
  // A file over frames 5..6 with the cameras reversed: its labels and their reasons move onto the
  // recording's frames and cameras together.
  const recon::LabelSet truth = Truth();
  std::vector<std::string> reversed(truth.cameras.rbegin(), truth.cameras.rend());
  recon::LabelSet file = recon::LabelSet::Empty(truth.rows, truth.cols, reversed, {5, 6});
  recon::Label doubt;
  doubt.px = Eigen::Vector2d(100.0, 200.0);
  doubt.state = recon::LabelState::kNeedsReview;
  file.at(0, 1, 3) = doubt;
  file.reasons[{0, 1, 3}] = "epipolar check: 4.2 px off";
  const std::string path = (Dir() / "reasons_in.h5").string();
  recon::WriteLabels(path, file);
  auto s = Session::Open(LoadProject(MakeProjectFile("reasons", path)));
  const int c = s->document().labels().FindCamera(reversed[0]);
  ASSERT_GE(c, 0);
  EXPECT_TRUE(s->document().labels().at(c, 6, 3).present());
  EXPECT_EQ(s->document().Reason(c, 6, 3), "epipolar check: 4.2 px off");
}

TEST_F(MainWindowTest, F1ListsEveryActionWithItsKeys) {
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(MakeProjectFile("keys")), false));
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
  int rows = -1;
  QString first_keys;
  // The cheat sheet is modal: read it once it is up, then close it (whatever it holds, so that
  // a failure never leaves the test waiting on it).
  QTimer::singleShot(200, [&] {
    QWidget* dialog = QApplication::activeModalWidget();
    if (dialog == nullptr) return;
    dialog->grab().save((Dir() / "shortcuts.png").string().c_str());
    if (const auto* table = dialog->findChild<QTableWidget*>()) {
      rows = table->rowCount();
      for (int r = 0; r < rows; ++r)
        if (table->item(r, 0)->text() == "Save labels") first_keys = table->item(r, 1)->text();
    }
    dialog->close();
  });
  QTest::keyClick(&w, Qt::Key_F1);
  int actions = 0;
  for (QAction* a : w.actions()) actions += !a->shortcuts().isEmpty();
  EXPECT_GE(actions, 40);
  EXPECT_EQ(rows, actions + 4);  // and the four mouse gestures
  EXPECT_EQ(first_keys, QKeySequence("Ctrl+S").toString(QKeySequence::NativeText));
}

// A knot of frame `t` that every camera sees well inside its picture, with its four neighbours
// (an inner knot): deleting one camera's label of it leaves a knot the other three place.
int KnotSeenByAll(const recon::LabelSet& truth, int t, int from = 0) {
  for (int k = from; k < truth.knots(); ++k) {
    const int row = k / truth.cols, col = k % truth.cols;
    if (row == 0 || col == 0 || row + 1 == truth.rows || col + 1 == truth.cols) continue;
    bool seen = true;
    for (int c = 0; c < static_cast<int>(truth.cameras.size()); ++c)
      seen = seen && truth.at(c, t, k).present() && truth.at(c, t, k).px.minCoeff() > 60;
    if (seen) return k;
  }
  return -1;
}

// A person deletes camera c's label of knot k at frame t: goes to the frame, clicks the label,
// presses Delete.
void DeleteByHand(MainWindow* w, int c, int t, int k) {
  w->SetFrame(t);
  ASSERT_TRUE(w->WaitForFrame());
  QTest::mouseClick(w->view(c), Qt::LeftButton, Qt::NoModifier,
                    w->view(c)->ToWidget(w->session()->document().at(c, t, k).px).toPoint());
  ASSERT_EQ(w->knot(), k);
  QTest::keyClick(w, Qt::Key_Delete);
}

// Presses Space until the window is at (camera, t, knot); false when the queue has gone round.
bool SpaceTo(MainWindow* w, int camera, int t, int knot) {
  for (int i = 0; i <= w->review_table()->model()->rowCount(); ++i) {
    QTest::keyClick(w, Qt::Key_Space);
    if (w->camera() == camera && w->frame() == t && w->knot() == knot) return true;
  }
  return false;
}

// A person deletes one camera's label of a knot the other three cameras see (clicks it, Delete):
// the knot is listed as missing, Space reaches it (its frame, its camera alone, zoomed, the
// expected place drawn and said), and a Find Node click at the true place labels it there,
// accepted; it leaves the queue and the timeline's marks.
TEST_F(MainWindowTest, SpaceReachesAMissingKnotAndAFindNodeClickLabelsIt) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("missing", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const int t = 12, c = 1, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  const int tc = truth.FindCamera(s->camera_names()[c]);
  const Eigen::Vector2d where = truth.at(tc, t, k).px;
  // The label deleted with real events: the frame, a click on the label, Delete.
  w.SetFrame(t);
  ASSERT_TRUE(w.WaitForFrame());
  ASSERT_EQ(s->missing().Find(c, t, k), nullptr);
  QTest::mouseClick(w.view(c), Qt::LeftButton, Qt::NoModifier,
                    w.view(c)->ToWidget(s->document().at(c, t, k).px).toPoint());
  ASSERT_EQ(w.knot(), k);
  ASSERT_EQ(w.camera(), c);
  QTest::keyClick(&w, Qt::Key_Delete);
  ASSERT_FALSE(s->document().at(c, t, k).present());
  const MissingKnot* m = s->missing().Find(c, t, k);
  ASSERT_NE(m, nullptr) << "not listed as missing";
  EXPECT_LT((m->expected_px - where).norm(), 0.5);
  const auto* timeline = w.findChild<Timeline*>("labeling_timeline");
  ASSERT_NE(timeline, nullptr);
  EXPECT_TRUE(timeline->missing_frames().count(t));
  // Space reaches it: its camera alone, the ring at the expected place, the reason said.
  w.SetFrame(0);
  ASSERT_TRUE(SpaceTo(&w, c, t, k)) << "Space never reached the missing knot";
  EXPECT_TRUE(w.view(c)->isVisible());
  for (int other = 0; other < s->cameras(); ++other) {
    if (other != c) {
      EXPECT_FALSE(w.view(other)->isVisible()) << other;
    }
  }
  ASSERT_TRUE(w.view(c)->overlay().expected.has_value());
  EXPECT_LT((*w.view(c)->overlay().expected - where).norm(), 0.5);
  // Zoomed onto it (80 image pixels across), also once the view alone is laid out anew.
  QCoreApplication::processEvents();
  const QPointF centre(w.view(c)->width() / 2.0, w.view(c)->height() / 2.0);
  const QPointF at = w.view(c)->ToWidget(*w.view(c)->overlay().expected);
  EXPECT_LT(std::hypot(at.x() - centre.x(), at.y() - centre.y()), 2.0);
  EXPECT_NEAR(w.view(c)->scale(), std::min(w.view(c)->width(), w.view(c)->height()) / 80.0, 1e-9);
  EXPECT_TRUE(w.view(c)->overlay().reprojected.has_value());
  EXPECT_TRUE(w.statusBar()->currentMessage().contains("no label; seen in"))
      << w.statusBar()->currentMessage().toStdString();
  ASSERT_TRUE(w.WaitForFrame());
  w.grab().save((Dir() / "missing.png").string().c_str());
  // A Find Node click at the true place: labeled, accepted, off the queue.
  ClickAt(w.view(c), where);
  const recon::Label& l = s->document().at(c, t, k);
  ASSERT_TRUE(l.present()) << w.statusBar()->currentMessage().toStdString();
  EXPECT_EQ(l.state, recon::LabelState::kAccepted) << s->document().Reason(c, t, k);
  EXPECT_LT((l.px - where).norm(), 0.5);
  EXPECT_EQ(s->missing().Find(c, t, k), nullptr);
  const QAbstractItemModel* queue = w.review_table()->model();
  for (int row = 0; row < queue->rowCount(); ++row) {
    const QModelIndex i = queue->index(row, 0);
    EXPECT_FALSE(i.data(ReviewModel::kCameraRole).toInt() == c &&
                 i.data(ReviewModel::kFrameRowRole).toInt() == t &&
                 i.data(ReviewModel::kKnotRole).toInt() == k)
        << "still in the queue";
  }
}

// A review item's message in a narrow window is not cut off by the status bar's knot and frame
// readouts: they give way to it (the cursor's pixel stays), and the whole message is the bar's
// tooltip.
TEST_F(MainWindowTest, AStatusMessageHasTheBarsWidthAndIsWholeInItsTooltip) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("status", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  w.resize(700, 800);
  const int t = 7, c = 2, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  ASSERT_NO_FATAL_FAILURE(DeleteByHand(&w, c, t, k));
  // The readouts are shown while no message is.
  w.statusBar()->clearMessage();
  QCoreApplication::processEvents();
  int readouts = 0;
  for (QLabel* label : w.statusBar()->findChildren<QLabel*>()) readouts += label->isVisible();
  ASSERT_GE(readouts, 2);
  w.SetFrame(0);
  ASSERT_TRUE(SpaceTo(&w, c, t, k));
  QCoreApplication::processEvents();
  const QString message = w.statusBar()->currentMessage();
  ASSERT_TRUE(message.contains("expected near")) << message.toStdString();
  EXPECT_EQ(w.statusBar()->toolTip(), message);
  int visible = 0, beside = 0;  // the labels still shown, and the width they take
  for (QLabel* label : w.statusBar()->findChildren<QLabel*>())
    if (label->isVisible()) {
      ++visible;
      beside += label->width();
    }
  EXPECT_EQ(visible, 1) << "only the cursor's pixel stays beside a message";
  EXPECT_LE(beside, w.statusBar()->width() / 4);
}

// Places the other cameras' labels of knot k in frame row t at one point beside it: consistent
// views that put the knot `px` px from its label in camera c (as when one is off along its
// epipolar line).
void MoveTheOthersBeside(Session* s, int c, int t, int k, double px) {
  const auto rig_camera = [&](int camera) -> const calib::Camera& {
    for (const calib::Camera& cam : s->rig().cameras)
      if (cam.name == s->camera_names()[camera]) return cam;
    throw std::runtime_error("no rig camera " + s->camera_names()[camera]);
  };
  std::vector<recon::Observation> views;
  for (int o = 0; o < s->cameras(); ++o)
    for (size_t r = 0; r < s->rig().cameras.size(); ++r)
      if (o != c && s->rig().cameras[r].name == s->camera_names()[o])
        views.push_back({static_cast<int>(r), s->document().at(o, t, k).px});
  const recon::PointEstimate point = recon::TriangulatePoint(s->rig(), views, {});
  ASSERT_TRUE(point.valid);
  const Eigen::Vector2d where = s->document().at(c, t, k).px;
  const Eigen::Vector3d side =
      (rig_camera(c).Center() - point.position).cross(Eigen::Vector3d::UnitZ()).normalized();
  double d = 0.0;
  while ((rig_camera(c).ProjectWorld(point.position + d * side) - where).norm() < px) d += 1e-5;
  for (int o = 0; o < s->cameras(); ++o)
    if (o != c) s->PlaceLabel(o, t, k, rig_camera(o).ProjectWorld(point.position + d * side));
}

// The other three cameras' labels of a knot moved together (one point 2.5 px from the knot in
// camera b: consistent views, as when one is off along its epipolar line): a Find Node click on
// the knot's junction in b keeps it for review, and the status bar says why once, without
// repeating "Find Node:".
TEST_F(MainWindowTest, AFindNodeClickTheOtherCamerasPutElsewhereIsKeptForReviewAndSaysWhy) {
  const recon::LabelSet truth = Truth();
  const std::string project =
      MakeProjectFile("elsewhere", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const int t = 12, c = 1, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  const Eigen::Vector2d where = s->document().at(c, t, k).px;
  w.SetFrame(t);
  ASSERT_TRUE(w.WaitForFrame());
  ASSERT_NO_FATAL_FAILURE(MoveTheOthersBeside(s, c, t, k, 2.5));
  s->DeleteLabel(c, t, k);
  w.SetKnot(k);
  ClickAt(w.view(c), where);
  const recon::Label& l = s->document().at(c, t, k);
  const std::string said = w.statusBar()->currentMessage().toStdString();
  ASSERT_TRUE(l.present()) << said;
  EXPECT_EQ(l.state, recon::LabelState::kNeedsReview) << said;
  EXPECT_LT((l.px - where).norm(), 0.5);
  EXPECT_NE(said.find("found, kept for review: the junction is"), std::string::npos) << said;
  EXPECT_NE(said.find("from where the other cameras' labels put the knot"), std::string::npos)
      << said;
  EXPECT_EQ(said.find("review: Find Node"), std::string::npos) << said;
  ASSERT_TRUE(w.WaitForFrame());
  w.grab().save((Dir() / "elsewhere.png").string().c_str());
}

// The knot picker: I over a junction rings the knots its colours fit in the grid (the true one
// among them, the only one when they identify it); a click on a disc, or the arrows while the
// grid has the focus, picks the knot to label (not the frame); a Find Node click then labels it
// and its disc takes the label's colour. A frame change clears the ring.
TEST_F(MainWindowTest, IOffersTheKnotsTheColoursFitAndTheGridPicksTheKnotToLabel) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("picker");
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  KnotGrid* grid = w.knot_grid();
  ASSERT_NE(grid, nullptr);
  ASSERT_EQ(grid->rows(), truth.rows);
  ASSERT_EQ(grid->cols(), truth.cols);
  const int t = 0;
  int asked = 0, identified = 0, offered = 0;
  size_t candidates = 0;
  for (int c = 0; c < s->cameras(); ++c) {
    const int tc = truth.FindCamera(s->camera_names()[c]);
    for (int k = 0; k < truth.knots(); ++k) {
      const recon::Label& want = truth.at(tc, t, k);
      if (!want.present()) continue;
      QTest::mouseMove(w.view(c), w.view(c)->ToWidget(want.px).toPoint());
      QTest::keyClick(&w, Qt::Key_I);
      ++asked;
      const std::vector<int>& offer = grid->offered();
      const std::string said = w.statusBar()->currentMessage().toStdString();
      if (offer.empty()) continue;
      EXPECT_NE(std::find(offer.begin(), offer.end(), k), offer.end())
          << "camera " << c << ", knot " << k << ": " << said;
      if (grid->identified()) {
        ++identified;
        EXPECT_EQ(w.knot(), k) << said;
      } else {
        ++offered;
        candidates += offer.size();
      }
    }
  }
  std::printf(
      "knot picker, frame 0: %d junctions asked, %d identified, %d offered (%.1f knots "
      "each)\n",
      asked, identified, offered, offered ? double(candidates) / offered : 0.0);
  EXPECT_GT(identified + offered, 0);
  w.grab().save((Dir() / "picker.png").string().c_str());

  // A click on a disc picks the knot; the arrows move it while the grid has the focus, not the
  // frame.
  const int c = 0, tc = truth.FindCamera(s->camera_names()[c]);
  const int k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  QTest::mouseClick(grid, Qt::LeftButton, Qt::NoModifier, grid->KnotCentre(k - 1).toPoint());
  EXPECT_EQ(w.knot(), k - 1);
  EXPECT_EQ(grid->selected(), k - 1);
  grid->setFocus();
  QTest::keyClick(grid, Qt::Key_Right);
  EXPECT_EQ(w.knot(), k);
  EXPECT_EQ(w.frame(), t);
  // A Find Node click labels it; its disc takes the label's colour.
  EXPECT_FALSE(s->document().at(c, t, k).present());
  ClickAt(w.view(c), truth.at(tc, t, k).px);
  ASSERT_TRUE(s->document().at(c, t, k).present()) << w.statusBar()->currentMessage().toStdString();
  QTest::mouseMove(w.view(c), w.view(c)->ToWidget(truth.at(tc, t, k).px).toPoint());
  const QImage image = grid->grab().toImage();
  const QColor disc = image.pixelColor(grid->KnotCentre(k).toPoint());
  EXPECT_NE(disc, QColor(Qt::white)) << "the labeled knot's disc is still empty";
  // Its colours now exclude it elsewhere: I on another junction never offers it.
  const int other = KnotSeenByAll(truth, t, k + 1);
  if (other >= 0) {
    QTest::mouseMove(w.view(c), w.view(c)->ToWidget(truth.at(tc, t, other).px).toPoint());
    QTest::keyClick(&w, Qt::Key_I);
    const std::vector<int>& offer = grid->offered();
    EXPECT_EQ(std::find(offer.begin(), offer.end(), k), offer.end());
    // A frame change clears the ring.
    w.SetFrame(t + 1);
    EXPECT_TRUE(grid->offered().empty());
  }
}

// D on a missing knot (no label selected) marks it hidden, one undo step, and it leaves the
// queue; Ctrl+Z lists it again. Shift+D marks it hidden through the frames it is missing in,
// one step, and stops where the camera has a label again.
TEST_F(MainWindowTest, DMarksAMissingKnotHiddenAndShiftDTheFramesAfterIt) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("hidden", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const int t = 20, c = 2, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  ASSERT_GE(KnotSeenByAll(truth, t + 3), 0);
  for (int u = t; u < t + 3; ++u) s->DeleteLabel(c, u, k);  // lost in frames t .. t + 2
  ASSERT_EQ(s->missing().RunFrom(c, t, k), (std::vector<int>{t, t + 1, t + 2}));
  // D: hidden in frame t only.
  ASSERT_TRUE(SpaceTo(&w, c, t, k));
  const int steps = s->document().undo_stack()->count();
  QTest::keyClick(&w, Qt::Key_D);
  EXPECT_TRUE(s->document().at(c, t, k).hidden());
  EXPECT_EQ(s->document().undo_stack()->count(), steps + 1);
  EXPECT_EQ(s->missing().Find(c, t, k), nullptr);
  EXPECT_NE(s->missing().Find(c, t + 1, k), nullptr);
  // The window may have gone on to the frame's next item (Go > Advance…): back to the knot.
  EXPECT_EQ(w.frame(), t);
  w.SetCamera(c);
  w.SetKnot(k);
  ASSERT_TRUE(w.WaitForFrame());  // the overlays are drawn with the frame's image
  EXPECT_TRUE(w.view(c)->overlay().caption.contains("marked hidden"))
      << w.view(c)->overlay().caption.toStdString();
  QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_FALSE(s->document().at(c, t, k).hidden());
  EXPECT_NE(s->missing().Find(c, t, k), nullptr);
  // Shift+D: hidden in t, t + 1 and t + 2, one step; frame t + 3 keeps its label.
  QTest::keyClick(&w, Qt::Key_D, Qt::ShiftModifier);
  for (int u = t; u < t + 3; ++u) EXPECT_TRUE(s->document().at(c, u, k).hidden()) << u;
  EXPECT_TRUE(s->document().at(c, t + 3, k).present());
  EXPECT_EQ(s->document().undo_stack()->count(), steps + 1);
  EXPECT_TRUE(s->missing().RunFrom(c, t, k).empty());
  // The tools leave the marks: Fill Grid in frame t + 1 does not label the knot there.
  QTest::keyClick(&w, Qt::Key_F);
  ASSERT_EQ(w.frame(), t + 1);
  QTest::keyClick(&w, Qt::Key_G);
  EXPECT_TRUE(s->document().at(c, t + 1, k).hidden());
}

// After a fix of an item of the queue (here D on a missing knot) the window goes on to the next
// item of the same frame by itself; after the frame's last item it stays; with Go > Advance…
// off it never moves.
TEST_F(MainWindowTest, AfterAFixTheWindowGoesOnToTheFramesNextItem) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("advance", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const int t = 12, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  // The knot lost in cameras 0 and 1 (cameras 2 and 3 still place it): two missing items.
  s->DeleteLabel(0, t, k);
  s->DeleteLabel(1, t, k);
  ASSERT_NE(s->missing().Find(0, t, k), nullptr);
  ASSERT_NE(s->missing().Find(1, t, k), nullptr);
  // Only these two in frame t: the others the queue lists there (the target hides them) hidden.
  for (const LabelKey& key : s->missing().Items())
    if (key.t == t && key.knot != k) s->MarkHidden(key.camera, t, key.knot);
  ASSERT_TRUE(SpaceTo(&w, 0, t, k));
  QTest::keyClick(&w, Qt::Key_D);  // hidden in camera 0: on to camera 1
  EXPECT_TRUE(s->document().at(0, t, k).hidden());
  EXPECT_EQ(w.frame(), t);
  EXPECT_EQ(w.camera(), 1);
  EXPECT_EQ(w.knot(), k);
  QTest::keyClick(&w, Qt::Key_D);  // the frame's last item: the window stays
  EXPECT_TRUE(s->document().at(1, t, k).hidden());
  EXPECT_EQ(w.frame(), t);
  EXPECT_EQ(w.camera(), 1);
  // Advance off: undo both, D on camera 0's item leaves the window there.
  QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  QAction* advance = nullptr;
  for (QAction* a : w.findChildren<QAction*>())
    if (a->text().startsWith("Advance")) advance = a;
  ASSERT_NE(advance, nullptr);
  advance->trigger();
  ASSERT_FALSE(advance->isChecked());
  ASSERT_TRUE(SpaceTo(&w, 0, t, k));
  QTest::keyClick(&w, Qt::Key_D);
  EXPECT_TRUE(s->document().at(0, t, k).hidden());
  EXPECT_EQ(w.camera(), 0);

  // After a label for review, the frame's missing knots wait (they are done a run at a time once
  // tracking is over): with camera 1's item missing and another knot's label in camera 0 for
  // review (before it in the queue), A on that label leaves the window there.
  advance->trigger();
  ASSERT_TRUE(advance->isChecked());
  const int other = KnotSeenByAll(truth, t, k + 1);
  ASSERT_GE(other, 0);
  recon::Label doubt = s->document().at(0, t, other);
  ASSERT_TRUE(doubt.present());
  doubt.state = recon::LabelState::kNeedsReview;
  s->document().Apply("doubt", {{0, t, other, doubt}});
  ASSERT_NE(s->missing().Find(1, t, k), nullptr);
  ASSERT_TRUE(SpaceTo(&w, 0, t, other));
  QTest::keyClick(&w, Qt::Key_A);
  EXPECT_TRUE(s->document().at(0, t, other).accepted());
  EXPECT_EQ(w.camera(), 0);
  EXPECT_EQ(w.knot(), other);
}

// ---------------------------------------------------------------------------------------------
// Keys and the camera a person acts on: keys typed as a keyboard types them, to the
// widget that has the focus, not sent to the window.

// Types `key` where the keyboard's keys go: the focus widget (the window when none has it).
void Type(MainWindow* w, Qt::Key key, Qt::KeyboardModifiers modifiers = Qt::NoModifier) {
  QWidget* focus = QApplication::focusWidget();
  QTest::keyClick(focus != nullptr ? focus : w, key, modifiers);
}

// The window on the true labels with every missing knot marked hidden, and two labels of frame t
// put under review: knot a in camera 0, knot b in camera 2 (the queue holds these two only).
struct TwoItems {
  int t = 5, a = -1, b = -1;
};
TwoItems PlantTwoItems(MainWindow* w, const recon::LabelSet& truth) {
  Session* s = w->session();
  TwoItems items;
  items.a = KnotSeenByAll(truth, items.t);
  items.b = KnotSeenByAll(truth, items.t, items.a + 1);
  for (const LabelKey& key : s->missing().Items()) s->MarkHidden(key.camera, key.t, key.knot);
  for (const auto& [c, k] : {std::pair{0, items.a}, std::pair{2, items.b}}) {
    recon::Label doubt = s->document().at(c, items.t, k);
    doubt.state = recon::LabelState::kNeedsReview;
    s->document().Apply("doubt", {{c, items.t, k, doubt}});
  }
  return items;
}

// The issue's reproduction: the window moves to another camera (the queue's next item, then the
// frame's next after a fix) while the person worked in camera 3; focus used to land in the frame
// spin box, where A, D, T did nothing and digits changed the frame. Now every camera change hands
// the keys to the current view; the spin box takes a number's keys only after a click into it,
// Enter goes back to the view, and the labeling keys work even while it has the focus.
TEST_F(MainWindowTest, LetterKeysReachTheViewAfterTheWindowMovesToAnotherCamera) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("focus", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const TwoItems items = PlantTwoItems(&w, truth);
  ASSERT_GE(items.b, 0);
  ASSERT_EQ(w.review_table()->model()->rowCount(), 2);
  // The person works in camera 3 at frame t: a click on one of its labels.
  w.SetFrame(items.t);
  ASSERT_TRUE(w.WaitForFrame());
  int k3 = -1;
  for (int k = 0; k < s->project().knots() && k3 < 0; ++k)
    if (k != items.a && k != items.b && s->document().at(3, items.t, k).present()) k3 = k;
  ASSERT_GE(k3, 0);
  QTest::mouseClick(w.view(3), Qt::LeftButton, Qt::NoModifier,
                    w.view(3)->ToWidget(s->document().at(3, items.t, k3).px).toPoint());
  ASSERT_EQ(w.camera(), 3);
  ASSERT_EQ(QApplication::focusWidget(), w.view(3));
  // Space: the queue's next item, camera 0 alone; the keys are its view's.
  Type(&w, Qt::Key_Space);
  ASSERT_EQ(w.camera(), 0);
  ASSERT_EQ(w.knot(), items.a);
  EXPECT_EQ(QApplication::focusWidget(), w.view(0));
  // Digits change nothing; A accepts; the window goes on to camera 2's item, and D deletes it.
  Type(&w, Qt::Key_7);
  EXPECT_EQ(w.frame(), items.t);
  Type(&w, Qt::Key_A);
  EXPECT_TRUE(s->document().at(0, items.t, items.a).accepted());
  ASSERT_EQ(w.camera(), 2);
  ASSERT_EQ(w.knot(), items.b);
  EXPECT_EQ(QApplication::focusWidget(), w.view(2));
  Type(&w, Qt::Key_D);
  EXPECT_FALSE(s->document().at(2, items.t, items.b).present());
  EXPECT_EQ(w.frame(), items.t);
  // The frame's spin box: a click into it, then F is still the window's key (next frame), the
  // typed number and Enter go to that frame, and the keys are the view's again.
  QSpinBox* box = nullptr;
  for (QSpinBox* b : w.findChildren<QSpinBox*>())
    if (b->prefix() == "frame ") box = b;
  ASSERT_NE(box, nullptr);
  EXPECT_EQ(box->focusPolicy(), Qt::ClickFocus);
  QTest::mouseClick(box, Qt::LeftButton, Qt::NoModifier,
                    QPoint(box->width() / 2, box->height() / 2));
  ASSERT_EQ(QApplication::focusWidget(), box);
  Type(&w, Qt::Key_F);
  EXPECT_EQ(w.frame(), items.t + 1);
  Type(&w, Qt::Key_A, Qt::ControlModifier);  // select the box's text
  QTest::keyClicks(box, QString::number(s->frame_number(12)));
  Type(&w, Qt::Key_Return);
  EXPECT_EQ(w.frame(), 12);
  EXPECT_TRUE(
      QTest::qWaitFor([&] { return QApplication::focusWidget() == w.view(w.camera()); }, 2000));
  Type(&w, Qt::Key_Z, Qt::ControlModifier);  // the delete undone: the keys are the window's
  EXPECT_TRUE(s->document().at(2, items.t, items.b).present());
}

// The issue's own steps: the person works in camera 3, T tracks from frame 0 and stops at frame
// 1 on a label for review in camera 0 (tracked from one under review); the keys typed then reach
// camera 0's view, and A accepts the label shown.
TEST_F(MainWindowTest, AfterTStopsInAnotherCameraItsKeysWork) {
  const recon::LabelSet truth = Truth();
  recon::LabelSet start = truth;
  for (int c = 0; c < static_cast<int>(start.cameras.size()); ++c)
    for (int t = 1; t < start.frames(); ++t)
      for (int k = 0; k < start.knots(); ++k) start.at(c, t, k) = recon::Label{};
  const int a = KnotSeenByAll(truth, 0);
  ASSERT_GE(a, 0);
  start.at(0, 0, a).state = recon::LabelState::kNeedsReview;
  start.reasons[{0, 0, a}] = "kept for review by the test";
  const std::string file = (Dir() / "t_stop_start.h5").string();
  recon::WriteLabels(file, start);
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile("t_stop", file)));
  Session* s = w.session();
  int k3 = -1;
  for (int k = 0; k < s->project().knots() && k3 < 0; ++k)
    if (s->document().at(3, 0, k).present()) k3 = k;
  ASSERT_GE(k3, 0);
  QTest::mouseClick(w.view(3), Qt::LeftButton, Qt::NoModifier,
                    w.view(3)->ToWidget(s->document().at(3, 0, k3).px).toPoint());
  ASSERT_EQ(w.camera(), 3);
  Type(&w, Qt::Key_T);
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w.busy(); }, 600000));
  QCoreApplication::processEvents();
  ASSERT_EQ(w.frame(), 1) << w.statusBar()->currentMessage().toStdString();
  ASSERT_EQ(w.camera(), 0);
  ASSERT_EQ(w.maximised(), 0);
  const int k = w.knot();
  ASSERT_EQ(s->document().at(0, 1, k).state, recon::LabelState::kNeedsReview);
  EXPECT_EQ(QApplication::focusWidget(), w.view(0));
  Type(&w, Qt::Key_A);
  EXPECT_TRUE(s->document().at(0, 1, k).accepted());
  EXPECT_EQ(w.frame(), 1);
}

// T stops at the first frame with a label for review and shows that label, not a missing knot
// the queue lists before it in that frame (the target's shadow in a lower camera).
TEST_F(MainWindowTest, TShowsTheLabelThatStoppedItNotAMissingKnotBeforeIt) {
  const recon::LabelSet truth = Truth();
  recon::LabelSet start = truth;
  for (int c = 0; c < static_cast<int>(start.cameras.size()); ++c)
    for (int t = 1; t < start.frames(); ++t)
      for (int k = 0; k < start.knots(); ++k) start.at(c, t, k) = recon::Label{};
  const int a = KnotSeenByAll(truth, 0);
  ASSERT_GE(a, 0);
  start.at(3, 0, a).state = recon::LabelState::kNeedsReview;
  start.reasons[{3, 0, a}] = "kept for review by the test";
  // Camera 0 unlabeled: its knots the others see are missing, in frame 1 too, before the label.
  for (int k = 0; k < start.knots(); ++k) start.at(0, 0, k) = recon::Label{};
  const std::string file = (Dir() / "t_label_start.h5").string();
  recon::WriteLabels(file, start);
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile("t_label", file)));
  Session* s = w.session();
  Type(&w, Qt::Key_T);
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w.busy(); }, 600000));
  QCoreApplication::processEvents();
  ASSERT_EQ(w.frame(), 1) << w.statusBar()->currentMessage().toStdString();
  const int c = w.camera(), k = w.knot();
  EXPECT_EQ(s->document().at(c, 1, k).state, recon::LabelState::kNeedsReview);
  EXPECT_EQ(s->missing().Find(c, 1, k), nullptr);
  // The test means something: frame 1 has a missing knot before that label in the queue.
  bool missing_before = false;
  for (const LabelKey& key : s->missing().Items())
    missing_before =
        missing_before || (key.t == 1 && std::pair(key.camera, key.knot) < std::pair(c, k));
  EXPECT_TRUE(missing_before) << "camera " << c << " knot " << k;
  EXPECT_TRUE(w.statusBar()->currentMessage().startsWith("Review"))
      << w.statusBar()->currentMessage().toStdString();
}

// A review row of another camera double-clicked while one camera is shown alone: that camera is
// shown alone (its frame, its caption), so A accepts the label the person sees.
TEST_F(MainWindowTest, ADoubleClickedReviewRowShowsItsCameraAlone) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("dclick", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const TwoItems items = PlantTwoItems(&w, truth);
  ASSERT_GE(items.b, 0);
  Type(&w, Qt::Key_Home, Qt::ControlModifier);  // the queue's first item: camera 0 alone
  ASSERT_EQ(w.camera(), 0);
  ASSERT_EQ(w.maximised(), 0);
  ASSERT_TRUE(w.WaitForFrame());
  // Camera 2's row, double-clicked.
  QTableView* table = w.review_table();
  int row = -1;
  for (int r = 0; r < table->model()->rowCount(); ++r)
    if (table->model()->index(r, 0).data(ReviewModel::kCameraRole).toInt() == 2) row = r;
  ASSERT_GE(row, 0);
  const QRect cell = table->visualRect(table->model()->index(row, ReviewModel::kKnot));
  // As a mouse double-clicks: press and release, press (the double click), release.
  QTest::mouseClick(table->viewport(), Qt::LeftButton, Qt::NoModifier, cell.center());
  QTest::mouseDClick(table->viewport(), Qt::LeftButton, Qt::NoModifier, cell.center());
  QTest::mouseRelease(table->viewport(), Qt::LeftButton, Qt::NoModifier, cell.center());
  ASSERT_EQ(w.camera(), 2);
  EXPECT_EQ(w.frame(), items.t);
  EXPECT_EQ(w.knot(), items.b);
  ASSERT_TRUE(w.WaitForFrame());
  // The view shown is camera 2's, at that frame; no other camera's view is.
  EXPECT_EQ(w.maximised(), 2);
  EXPECT_TRUE(w.view(2)->isVisible());
  for (int c = 0; c < s->cameras(); ++c) {
    if (c != 2) {
      EXPECT_FALSE(w.view(c)->isVisible()) << c;
    }
  }
  EXPECT_TRUE(w.view(2)->has_image());
  const QString caption = w.view(2)->overlay().caption;
  EXPECT_TRUE(caption.startsWith(QString::fromStdString(s->camera_names()[2]) + " · frame " +
                                 QString::number(s->frame_number(items.t))))
      << caption.toStdString();
  // A accepts the label shown.
  Type(&w, Qt::Key_A);
  EXPECT_TRUE(s->document().at(2, items.t, items.b).accepted());
  EXPECT_FALSE(s->document().at(0, items.t, items.a).accepted());
  QCoreApplication::processEvents();  // the layout of the camera shown alone (a posted event)
  w.grab().save((Dir() / "dclick.png").string().c_str());
}

// The queue's row of (camera, t, knot) in the table as sorted; -1 when it has none.
int TableRow(QTableView* table, int camera, int t, int knot) {
  const QAbstractItemModel* m = table->model();
  for (int row = 0; row < m->rowCount(); ++row) {
    const QModelIndex i = m->index(row, 0);
    if (i.data(ReviewModel::kCameraRole).toInt() == camera &&
        i.data(ReviewModel::kFrameRowRole).toInt() == t &&
        i.data(ReviewModel::kKnotRole).toInt() == knot)
      return row;
  }
  return -1;
}

// A click on the queue's Severity header puts the worst item first (a label flagged 1555.8 px
// off, behind a 0.5 px doubt in the queue's order); Home and Enter in the queue show it, and A
// accepts it, not the other.
TEST_F(MainWindowTest, ASeverityClickPutsTheWorstItemFirstAndEnterShowsIt) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("severity", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  const TwoItems items = PlantTwoItems(&w, truth);
  ASSERT_GE(items.b, 0);
  s->document().MergeReasons(
      {{{0, items.t, items.a}, "moved 0.5 px otherwise than its neighbours"},
       {{2, items.t, items.b}, "epipolar check: 1555.8 px off the point of all the cameras"}});
  QTableView* table = w.review_table();
  ASSERT_EQ(table->model()->rowCount(), 2);
  ASSERT_EQ(TableRow(table, 0, items.t, items.a), 0) << "the queue's order puts camera 0 first";
  QHeaderView* header = table->horizontalHeader();
  const int x = header->sectionViewportPosition(ReviewModel::kSeverity) +
                header->sectionSize(ReviewModel::kSeverity) / 2;
  QTest::mouseClick(header->viewport(), Qt::LeftButton, Qt::NoModifier,
                    QPoint(x, header->height() / 2));
  EXPECT_EQ(TableRow(table, 2, items.t, items.b), 0);
  EXPECT_EQ(table->model()->index(0, ReviewModel::kSeverity).data().toString(), "1.00");
  EXPECT_EQ(table->model()->index(1, ReviewModel::kSeverity).data().toString(), "0.05");
  // Into the queue (a click on its second row), Home, Enter: the worst item, its camera alone.
  QTest::mouseClick(table->viewport(), Qt::LeftButton, Qt::NoModifier,
                    table->visualRect(table->model()->index(1, ReviewModel::kKnot)).center());
  ASSERT_EQ(QApplication::focusWidget(), table);
  Type(&w, Qt::Key_Home);
  Type(&w, Qt::Key_Return);
  ASSERT_EQ(w.camera(), 2);
  EXPECT_EQ(w.frame(), items.t);
  EXPECT_EQ(w.knot(), items.b);
  EXPECT_EQ(w.maximised(), 2);
  EXPECT_TRUE(w.statusBar()->currentMessage().contains("1555.8 px off"))
      << w.statusBar()->currentMessage().toStdString();
  Type(&w, Qt::Key_A);
  EXPECT_TRUE(s->document().at(2, items.t, items.b).accepted());
  EXPECT_FALSE(s->document().at(0, items.t, items.a).accepted());
}

// A label under review for one reason, fixed by a Find Node click the other cameras disagree
// with: the queue's row says the new reason (and its severity), not the old one.
TEST_F(MainWindowTest, TheQueueSaysTheReasonOfTheLabelAsItIsAfterAFindNodeClick) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("stale", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  for (const auto& [mc, mt, mk] : s->missing().Items()) s->MarkHidden(mc, mt, mk);
  const int t = 12, c = 1, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  const Eigen::Vector2d where = s->document().at(c, t, k).px;
  ASSERT_NO_FATAL_FAILURE(MoveTheOthersBeside(s, c, t, k, 2.5));
  // c's label under review for an old reason.
  recon::Label doubt = s->document().at(c, t, k);
  doubt.state = recon::LabelState::kNeedsReview;
  s->document().Apply("doubt", {{c, t, k, doubt}});
  const std::string old_reason = "kept for review by the test";
  s->document().MergeReasons({{{c, t, k}, old_reason}});
  QTableView* table = w.review_table();
  const auto cell = [&](int column) {
    const int row = TableRow(table, c, t, k);
    return row < 0 ? QString("(not in the queue)")
                   : table->model()->index(row, column).data().toString();
  };
  ASSERT_EQ(cell(ReviewModel::kReason).toStdString(), old_reason);
  // The person goes to it (Space) and clicks Find Node on the junction.
  w.SetFrame(0);
  ASSERT_TRUE(SpaceTo(&w, c, t, k));
  ASSERT_TRUE(w.WaitForFrame());
  ClickAt(w.view(c), where);
  QCoreApplication::processEvents();
  ASSERT_EQ(s->document().at(c, t, k).state, recon::LabelState::kNeedsReview)
      << w.statusBar()->currentMessage().toStdString();
  const std::string now = s->document().Reason(c, t, k);
  ASSERT_NE(now.find("from where the other cameras' labels put the knot"), std::string::npos)
      << now;
  EXPECT_EQ(cell(ReviewModel::kReason).toStdString(), now);
  const int row = TableRow(table, c, t, k);
  ASSERT_GE(row, 0);
  EXPECT_EQ(table->model()->index(row, ReviewModel::kReason).data(Qt::ToolTipRole).toString(),
            QString::fromStdString(now));
  EXPECT_EQ(cell(ReviewModel::kSeverity), QString::number(ReasonSeverity(now), 'f', 2));
  EXPECT_GT(ReasonSeverity(now), 0.2);
}

// A labels file whose /review_reasons another tool wrote as a variable-length string: the window
// shows its reason as written, in the status bar when Ctrl+Home goes to the item and in the
// queue's row.
TEST_F(MainWindowTest, ReviewReasonsWrittenAsAVariableLengthStringAreShownAsWritten) {
  recon::LabelSet start = Truth();
  const int t = 5, k = KnotSeenByAll(start, t);
  ASSERT_GE(k, 0);
  start.at(0, t, k).state = recon::LabelState::kNeedsReview;
  start.reasons[{0, t, k}] = "placeholder";
  const std::string file = (Dir() / "vlen_reasons_start.h5").string();
  recon::WriteLabels(file, start);
  const std::string reason = "moved 2.1 px otherwise than its neighbours";
  {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    h5::Id f = h5::OpenFileReadWrite(file);
    ASSERT_GE(H5Ldelete(f.get(), "review_reasons", H5P_DEFAULT), 0);
    h5::Id type(H5Tcopy(H5T_C_S1));
    H5Tset_size(type.get(), H5T_VARIABLE);
    H5Tset_cset(type.get(), H5T_CSET_UTF8);
    h5::Id space(H5Screate(H5S_SCALAR));
    h5::Id dataset(H5Dcreate2(f.get(), "review_reasons", type.get(), space.get(), H5P_DEFAULT,
                              H5P_DEFAULT, H5P_DEFAULT));
    const std::string text =
        "0\t" + std::to_string(t) + "\t" + std::to_string(k) + "\t" + reason + "\n";
    const char* data = text.c_str();
    ASSERT_GE(H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &data), 0);
  }
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile("vlen_reasons", file)));
  Session* s = w.session();
  for (const auto& [mc, mt, mk] : s->missing().Items()) s->MarkHidden(mc, mt, mk);
  ASSERT_EQ(w.review_table()->model()->rowCount(), 1);
  Type(&w, Qt::Key_Home, Qt::ControlModifier);
  ASSERT_EQ(w.camera(), 0);
  ASSERT_EQ(w.frame(), t);
  ASSERT_EQ(w.knot(), k);
  EXPECT_TRUE(w.statusBar()->currentMessage().contains(QString::fromStdString(reason)))
      << w.statusBar()->currentMessage().toStdString();
  EXPECT_EQ(
      w.review_table()->model()->index(0, ReviewModel::kReason).data().toString().toStdString(),
      reason);
}

// The queue's Reason column in the window as it opens: one line per item, a row as high as one
// line of text, the whole reason in the cell's tooltip.
TEST_F(MainWindowTest, TheQueuesReasonColumnShowsAMissingKnotsReasonOnOneLine) {
  const recon::LabelSet truth = Truth();
  const std::string project =
      MakeProjectFile("reason_column", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  const int t = 7, c = 2, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  ASSERT_NO_FATAL_FAILURE(DeleteByHand(&w, c, t, k));
  w.SetFrame(0);
  ASSERT_TRUE(SpaceTo(&w, c, t, k));
  QCoreApplication::processEvents();
  QTableView* table = w.review_table();
  const int row = TableRow(table, c, t, k);
  ASSERT_GE(row, 0);
  const QModelIndex reason = table->model()->index(row, ReviewModel::kReason);
  const QString text = reason.data().toString();
  const int to = text.indexOf("expected near");
  ASSERT_GE(to, 0) << text.toStdString();
  EXPECT_FALSE(table->wordWrap());
  EXPECT_LE(table->rowHeight(row), 2 * table->fontMetrics().height());
  EXPECT_EQ(reason.data(Qt::ToolTipRole).toString(), text);
  w.grab().save((Dir() / "reason_column.png").string().c_str());
}

// The Knot colours panel follows the queue: Space to a missing knot (camera 2, frame 7) shows
// that knot, camera and frame with the link colours its code expects (it has no label to read
// at), not the knot selected before; a labeled knot clicked afterwards is read as before.
TEST_F(MainWindowTest, TheColoursPanelShowsTheSelectedMissingKnotsExpectedColours) {
  const recon::LabelSet truth = Truth();
  const std::string project =
      MakeProjectFile("colours_missing", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  auto* dock = w.findChild<QDockWidget*>("colours_dock");
  ASSERT_NE(dock, nullptr);
  auto* panel = qobject_cast<QLabel*>(dock->widget());
  ASSERT_NE(panel, nullptr);
  for (const auto& [mc, mt, mk] : s->missing().Items()) s->MarkHidden(mc, mt, mk);
  const int t = 7, c = 2, k = KnotSeenByAll(truth, t);
  ASSERT_GE(k, 0);
  ASSERT_NO_FATAL_FAILURE(DeleteByHand(&w, c, t, k));
  ASSERT_FALSE(s->document().at(c, t, k).present());
  // Elsewhere first (knot 0 of camera 0 at frame 0), then Space to the missing knot.
  w.SetFrame(0);
  ASSERT_TRUE(w.WaitForFrame());
  QTest::mouseClick(w.view(0), Qt::LeftButton, Qt::NoModifier,
                    QPoint(w.view(0)->width() / 2, CameraView::kCaptionHeight / 2));
  ASSERT_TRUE(SpaceTo(&w, c, t, k));
  QCoreApplication::processEvents();
  const QString where = QString("knot (%1, %2) in %3, frame %4")
                            .arg(k / truth.cols)
                            .arg(k % truth.cols)
                            .arg(QString::fromStdString(s->camera_names()[c]))
                            .arg(s->frame_number(t));
  const QString text = panel->text();
  EXPECT_TRUE(text.contains(where)) << text.toStdString() << " / " << where.toStdString();
  EXPECT_TRUE(text.contains("expected, by link")) << text.toStdString();
  EXPECT_GE(text.count("background-color"), 2) << text.toStdString();
  EXPECT_TRUE(text.contains("no label here")) << text.toStdString();
  w.grab().save((Dir() / "colours_missing.png").string().c_str());
}

// A camera is made current without a click that runs Find Node: a click on its view's caption
// bar, or its key (1-4); with one camera shown alone, the key shows that camera alone.
TEST_F(MainWindowTest, ACameraIsPickedByItsCaptionOrItsKeyWithoutLabeling) {
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile("pick_camera")));
  Session* s = w.session();
  const int steps = s->document().undo_stack()->count();
  QTest::mouseClick(w.view(2), Qt::LeftButton, Qt::NoModifier,
                    QPoint(w.view(2)->width() / 2, CameraView::kCaptionHeight / 2));
  EXPECT_EQ(w.camera(), 2);
  EXPECT_EQ(QApplication::focusWidget(), w.view(2));
  EXPECT_EQ(s->document().undo_stack()->count(), steps);
  EXPECT_EQ(s->document().labels().CountPresent(), 0);
  Type(&w, Qt::Key_4);
  EXPECT_EQ(w.camera(), 3);
  Type(&w, Qt::Key_M);  // camera 4 alone
  ASSERT_EQ(w.maximised(), 3);
  Type(&w, Qt::Key_2);
  EXPECT_EQ(w.camera(), 1);
  EXPECT_EQ(w.maximised(), 1);
  EXPECT_TRUE(w.view(1)->isVisible());
  EXPECT_FALSE(w.view(3)->isVisible());
  EXPECT_EQ(QApplication::focusWidget(), w.view(1));
  EXPECT_EQ(s->document().undo_stack()->count(), steps);
}

// Ctrl+arrows nudge the selected label even while the Net grid has the focus (its plain arrows
// still pick the knot).
TEST_F(MainWindowTest, CtrlArrowsNudgeTheLabelWhileTheNetGridHasTheFocus) {
  const std::string project = MakeProjectFile("nudge", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  Session* s = w.session();
  int k = -1;
  for (int i = 0; i + 1 < s->project().knots() && k < 0; ++i)
    if (s->document().at(0, 0, i).present() && i % s->project().cols + 1 < s->project().cols) k = i;
  ASSERT_GE(k, 0);
  KnotGrid* grid = w.knot_grid();
  QTest::mouseClick(grid, Qt::LeftButton, Qt::NoModifier, grid->KnotCentre(k).toPoint());
  ASSERT_EQ(w.knot(), k);
  ASSERT_EQ(QApplication::focusWidget(), grid);
  const Eigen::Vector2d before = s->document().at(0, 0, k).px;
  Type(&w, Qt::Key_Right, Qt::ControlModifier);
  EXPECT_EQ(w.knot(), k);
  EXPECT_GT(s->document().at(0, 0, k).px.x(), before.x() + 0.4);
  EXPECT_NEAR(s->document().at(0, 0, k).px.y(), before.y(), 1e-9);
  Type(&w, Qt::Key_Right);  // plain: the grid's pick
  EXPECT_EQ(w.knot(), k + 1);
}

// A panel closed with its title bar's button comes back from the View menu.
TEST_F(MainWindowTest, AClosedPanelIsReopenedFromTheViewMenu) {
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile("docks")));
  QMenu* view = nullptr;
  for (QAction* a : w.menuBar()->actions())
    if (a->text() == "&View") view = a->menu();
  ASSERT_NE(view, nullptr);
  for (const char* name : {"review_dock", "colours_dock", "knot_grid_dock"}) {
    auto* dock = w.findChild<QDockWidget*>(name);
    ASSERT_NE(dock, nullptr) << name;
    dock->close();
    QCoreApplication::processEvents();
    ASSERT_FALSE(dock->isVisible()) << name;
    ASSERT_TRUE(view->actions().contains(dock->toggleViewAction())) << name;
    // The menu opened and its entry clicked.
    view->popup(w.mapToGlobal(QPoint(10, 10)));
    ASSERT_TRUE(QTest::qWaitForWindowExposed(view));
    QTest::mouseClick(view, Qt::LeftButton, Qt::NoModifier,
                      view->actionGeometry(dock->toggleViewAction()).center());
    EXPECT_TRUE(QTest::qWaitFor([&] { return dock->isVisible(); }, 2000)) << name;
  }
}

// File > New project, its dialogs answered as a person does: the target (the shot's truth.h5,
// a simulation with its scenario); without a colouring it asks the rows and the columns (a net
// need not be square) and whether the net has knot balls; the project it writes says so, with
// paths relative to its folder, and opens.
TEST_F(MainWindowTest, NewProjectAsksRowsColumnsAndKnotBalls) {
  const std::string d = Dir().string();
  const std::string labels = d + "/wizard.h5", project = d + "/wizard.yaml";
  fs::remove(labels);
  fs::remove(project);
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  QStringList titles;
  QTimer answer;
  answer.setInterval(50);
  QObject::connect(&answer, &QTimer::timeout, [&] {
    QWidget* modal = QApplication::activeModalWidget();
    if (modal == nullptr ||
        (!titles.isEmpty() &&
         titles.back() == modal->windowTitle() + "#" + QString::number(quintptr(modal))))
      return;
    titles << modal->windowTitle() + "#" + QString::number(quintptr(modal));
    // Answered from within its own event loop (a dialog answered while it is being shown
    // leaves exec() waiting on a hidden dialog).
    QTimer::singleShot(100, modal, [&, modal] {
      const QString title = modal->windowTitle();
      if (auto* files = qobject_cast<QFileDialog*>(modal)) {
        const QString file =
            title.contains("target")       ? QString::fromStdString(d + "/shot/truth.h5")
            : title.contains("experiment") ? QString::fromStdString(d + "/shot/experiment.yaml")
            : title.contains("rig")        ? QString::fromStdString(d + "/shot/rig_true.yaml")
            : title.contains("labels")     ? QString::fromStdString(labels)
            : title.contains("project as") ? QString::fromStdString(project)
                                           : QString();
        if (file.isEmpty()) {
          files->reject();  // the colouring: none
        } else {
          // Typed into its file name box, then its Open / Save button.
          auto* name = files->findChild<QLineEdit*>("fileNameEdit");
          if (name != nullptr) name->setText(file);
          QMetaObject::invokeMethod(files, "accept");
        }
      } else if (auto* number = qobject_cast<QInputDialog*>(modal)) {
        number->setIntValue(number->labelText().contains("rows") ? 6 : 7);
        number->accept();
      } else if (auto* box = qobject_cast<QMessageBox*>(modal)) {
        box->button(QMessageBox::No)->click();  // no knot balls
      }
    });
  });
  answer.start();
  for (QAction* a : w.actions())
    if (a->text() == "New project…") a->trigger();
  answer.stop();
  ASSERT_TRUE(fs::exists(project)) << titles.join(" | ").toStdString();
  const Project p = LoadProject(project);
  EXPECT_EQ(p.rows, 6);
  EXPECT_EQ(p.cols, 7);
  EXPECT_TRUE(p.knotless);
  EXPECT_EQ(p.target, d + "/shot/truth.h5");
  // The files below the project's folder are written relative to it (the folder can move).
  std::ifstream in(project);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_NE(text.find("experiment: shot/experiment.yaml"), std::string::npos) << text;
  EXPECT_NE(text.find("target: shot/truth.h5"), std::string::npos) << text;
  EXPECT_EQ(text.find(d), std::string::npos) << text;
  ASSERT_NE(w.session(), nullptr);
  EXPECT_EQ(w.session()->project().cols, 7);
  for (const QString& t : titles) EXPECT_FALSE(t.contains(" of ")) << t.toStdString();
  EXPECT_EQ(titles.size(), 9) << titles.join(" | ").toStdString();
}

// Help > Manual shows docs/gui.md, in a window of its own.
TEST(MainWindowHelp, TheManualIsInTheHelpMenu) {
  MainWindow w;
  QAction* manual = nullptr;
  for (QAction* a : w.findChildren<QAction*>())
    if (a->text().startsWith("Manual")) manual = a;
  ASSERT_NE(manual, nullptr);
  manual->trigger();
  auto* dialog = w.findChild<QDialog*>("manual");
  ASSERT_NE(dialog, nullptr);
  EXPECT_TRUE(dialog->isVisible());
  auto* browser = dialog->findChild<QTextBrowser*>();
  ASSERT_NE(browser, nullptr);
  EXPECT_TRUE(browser->toPlainText().contains("The workstation: netlab gui"));
  EXPECT_TRUE(browser->toPlainText().contains("The recording room"));
  EXPECT_TRUE(browser->toPlainText().contains("Where the keys go"));
  dialog->close();
}

// After edits recovered from a crash's journal the title says they are unsaved ('*').
TEST_F(MainWindowTest, RecoveredEditsMarkTheTitleUnsaved) {
  const std::string project = MakeProjectFile("recover", (Dir() / "shot/labels_true.h5").string());
  {
    MainWindow crashed;
    ASSERT_NO_FATAL_FAILURE(OpenShown(crashed, project));
    Session* s = crashed.session();
    int k = 0;
    while (!s->document().at(0, 0, k).present()) ++k;
    crashed.SetKnot(k);
    crashed.SetCamera(0);
    Type(&crashed, Qt::Key_D);
    ASSERT_TRUE(s->document().modified());
    ASSERT_TRUE(crashed.isWindowModified());
  }  // gone without saving (no close event): the journal stays
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  bool asked = false;
  QTimer::singleShot(300, [&] {  // the question answered "Yes" with its button
    if (auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget())) {
      asked = true;
      QTest::mouseClick(box->button(QMessageBox::Yes), Qt::LeftButton);
    }
  });
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), true));
  EXPECT_TRUE(asked);
  EXPECT_TRUE(w.session()->document().modified());
  EXPECT_TRUE(w.isWindowModified());
  EXPECT_TRUE(w.windowTitle().contains("[*]"));
}

// A project that fails to open leaves the recent projects, and says why without a dialog when
// asked to (the command line).
TEST_F(MainWindowTest, AProjectThatFailsToOpenLeavesTheRecentProjects) {
  const QStringList before = Settings::RecentProjects();
  const QString bad = QString::fromStdString((Dir() / "gone_project.yaml").string());
  Settings::AddRecentProject(bad);
  ASSERT_TRUE(Settings::RecentProjects().contains(bad));
  MainWindow w;
  QString error;
  EXPECT_FALSE(w.OpenProject(bad, false, &error));
  EXPECT_TRUE(error.contains("gone_project.yaml")) << error.toStdString();
  EXPECT_FALSE(Settings::RecentProjects().contains(bad));
  QSettings("netlab", "netlab-gui").setValue(Settings::kRecentProjects, before);
}

// `netlab gui BROKEN --screenshot out.png` exits 1 at once with the reason on stderr (no dialog
// to wait on), as does a start without --screenshot; a screenshot never replaces the project or
// one of its files, and is written whole (no .partial left).
TEST_F(MainWindowTest, ABrokenProjectFailsAtOnceWithTheReasonOnStderr) {
  const fs::path d = Dir() / "broken";
  fs::create_directories(d);
  const std::string good = MakeProjectFile("broken_good");
  std::string text;
  {
    std::ifstream in(good);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto with_line = [&](const std::string& key, const std::string& line) {
    std::string t = text;
    const size_t at = t.find(key + ":");
    const size_t end = t.find('\n', at);
    return t.replace(at, end - at, line);
  };
  const std::map<std::string, std::pair<std::string, std::string>> cases = {
      // name: (contents, what stderr must say); "missing" is not written.
      {"missing", {"", "cannot open file"}},
      {"empty", {"", "is empty"}},
      {"list", {"- experiment\n- rig\n", "holds a list"}},
      {"no_rig", {with_line("rig", "rig: nowhere/rig.yaml"), "rig file not found"}},
      {"no_labels_folder", {with_line("labels", "labels: nowhere/labels.h5"), "does not exist"}},
      {"duplicate", {text + "rig: other.yaml\n", "rig: given twice"}},
      {"syntax", {"netlab_project: 1\nrig: [unclosed\n", "YAML syntax error"}},
  };
  for (const auto& [name, want] : cases) {
    const std::string path = (Dir() / (name + ".yaml")).string();
    fs::remove(path);
    if (name != "missing") std::ofstream(path) << want.first;
    const std::string png = (d / (name + ".png")).string();
    QElapsedTimer clock;
    clock.start();
    const auto shot = RunNetlab("gui " + path + " --screenshot " + png);
    EXPECT_LT(clock.elapsed(), 10000) << name;
    EXPECT_EQ(shot.status, 1) << name << ": " << shot.err;
    EXPECT_NE(shot.err.find(want.second), std::string::npos) << name << ": " << shot.err;
    EXPECT_FALSE(fs::exists(png)) << name;
    const auto window = RunNetlab("gui " + path);  // a window (offscreen here) that cannot start
    EXPECT_EQ(window.status, 1) << name << ": " << window.err;
    EXPECT_NE(window.err.find(want.second), std::string::npos) << name << ": " << window.err;
  }
  // Never over the project or a file it names.
  for (const std::string& target : {good, LoadProject(good).rig}) {
    std::ifstream before_in(target, std::ios::binary);
    const std::string before((std::istreambuf_iterator<char>(before_in)), {});
    const auto over = RunNetlab("gui " + good + " --screenshot " + target);
    EXPECT_EQ(over.status, 1) << over.err;
    EXPECT_NE(over.err.find("would replace the input"), std::string::npos) << over.err;
    std::ifstream after_in(target, std::ios::binary);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(after_in)), {}), before) << target;
  }
  const std::string png = (d / "good.png").string();
  const auto ok = RunNetlab("gui " + good + " --screenshot " + png);
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_FALSE(QImage(QString::fromStdString(png)).isNull());
  EXPECT_FALSE(fs::exists(png + ".partial"));
}

// ---------------------------------------------------------------------------------------------
// The Fill Grid preview (G, Enter, Esc).

// Labels that differ between two sets of one shape (presence, state, source, confidence, pixel).
int DifferentLabels(const recon::LabelSet& a, const recon::LabelSet& b) {
  int differ = 0;
  for (int c = 0; c < static_cast<int>(a.cameras.size()); ++c)
    for (int t = 0; t < a.frames(); ++t)
      for (int k = 0; k < a.knots(); ++k) {
        const recon::Label &x = a.at(c, t, k), &y = b.at(c, t, k);
        differ += x.present() != y.present() || x.state != y.state || x.source != y.source ||
                  x.confidence != y.confidence || (x.present() && x.px != y.px);
      }
  return differ;
}

// Whether a pixel of the ghosts' pink is within `radius` widget pixels of `centre` in `image`.
bool GhostPinkNear(const QImage& image, const QPoint& centre, int radius) {
  const QColor pink = QColor::fromRgb(CameraView::kGhostColour);
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const QPoint p = centre + QPoint(dx, dy);
      if (!image.rect().contains(p)) continue;
      const QColor c = image.pixelColor(p);
      if (std::abs(c.red() - pink.red()) < 40 && std::abs(c.green() - pink.green()) < 45 &&
          std::abs(c.blue() - pink.blue()) < 45)
        return true;
    }
  return false;
}

class FillGridPreviewTest : public MainWindowTest {
 protected:
  // A window on a new project: the corners of frame 0 seeded with Find Node clicks (as the
  // scripted person does), Find Path from them (Ctrl+P), and the epipolar check and Fill Grid
  // that Find Path ends with taken back (Ctrl+Z), so that frame 0 has knots left to fill.
  void Open(const std::string& name) {
    window_ = std::make_unique<MainWindow>();
    MainWindow& w = *window_;
    ASSERT_NO_FATAL_FAILURE(OpenShown(w, MakeProjectFile(name)));
    const recon::LabelSet truth = Truth();
    Session* s = w.session();
    const int rows = s->project().rows, cols = s->project().cols;
    for (int c = 0; c < s->cameras(); ++c)
      for (int k : {0, cols - 1, (rows - 1) * cols, rows * cols - 1}) {
        const recon::Label& want = truth.at(truth.FindCamera(s->camera_names()[c]), 0, k);
        if (!want.present()) continue;
        PickKnot(&w, k);
        ZoomAt(w.view(c), want.px, 8);
        actions_.push_back({Action::kFindNode, c, 0, k, ClickAt(w.view(c), want.px)});
        if (!s->document().at(c, 0, k).present())
          actions_.push_back(
              {Action::kPlace, c, 0, k, ClickAt(w.view(c), want.px, Qt::ShiftModifier)});
        QTest::keyClick(&w, Qt::Key_F, Qt::ControlModifier);
      }
    QTest::keyClick(&w, Qt::Key_P, Qt::ControlModifier);  // a preview on a worker
    ASSERT_TRUE(w.WaitForIdle(120000));
    ASSERT_NE(w.fill_grid_preview(), nullptr) << w.statusBar()->currentMessage().toStdString();
    EXPECT_TRUE(w.fill_grid_preview()->from_corners);
    QTest::keyClick(&w, Qt::Key_Return);
    ASSERT_TRUE(w.WaitForIdle());
    QCoreApplication::processEvents();  // the layout without the preview's bar (a posted event)
    QUndoStack* undo = s->document().undo_stack();
    while (undo->undoText().startsWith("Fill Grid") || undo->undoText().startsWith("epipolar")) {
      QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
      ++undone_;
    }
    ASSERT_GT(undone_, 0) << "Find Path ended without a check step";
  }
  // The same actions on the engine of a second project, without a window.
  std::unique_ptr<Session> Replay(const std::string& name) {
    auto engine = Session::Open(LoadProject(MakeProjectFile(name)));
    for (const Action& a : actions_)
      if (a.kind == Action::kFindNode)
        engine->FindNode(a.camera, a.t, a.knot, a.px, 6.0);
      else
        engine->PlaceLabel(a.camera, a.t, a.knot, a.px);
    engine->FindPathFromCorners(0);
    QUndoStack* undo = engine->document().undo_stack();
    // The engine's check is several steps (epipolar, Fill Grid passes, colour, Find Path between
    // the labeled knots and its own check), the window's one.
    while (undo->undoText().startsWith("Fill Grid") || undo->undoText().startsWith("epipolar") ||
           undo->undoText().startsWith("colour check") ||
           undo->undoText().startsWith("Find Path between labeled knots"))
      undo->undo();
    return engine;
  }
  // Presses G and waits for the preview's answer.
  bool PressGAndWait() {
    QTest::keyClick(window_.get(), Qt::Key_G);
    return window_->WaitForIdle(120000);
  }
  // Picks the knot and camera of an edit (the knot picker, then a click would label it).
  void SetKnotOf(const recon::LabelEdit& e) {
    PickKnot(window_.get(), e.knot);
    window_->SetCamera(e.camera);
  }
  QWidget* Banner() const { return window_->findChild<QWidget*>("preview_banner"); }
  QString BannerText() const {
    const auto* label = Banner()->findChild<QLabel*>();
    return label ? label->text() : QString();
  }
  int Ghosts() const {
    int n = 0;
    for (int c = 0; c < window_->session()->cameras(); ++c)
      n += static_cast<int>(window_->view(c)->overlay().ghosts.size());
    return n;
  }

  std::unique_ptr<MainWindow> window_;
  std::vector<Action> actions_;
  int undone_ = 0;  // check steps taken back after Find Path
};

// G changes nothing: the candidates are drawn as ghosts (in the overlay and in the pixels) under a
// banner. Enter applies them as one undo step, giving the labels Session::FillGrid gives on the
// same start, and Ctrl+Z takes exactly that step back.
TEST_F(FillGridPreviewTest, GPreviewsAndEnterAppliesWhatFillGridGivesAsOneStep) {
  ASSERT_NO_FATAL_FAILURE(Open("preview_accept"));
  MainWindow& w = *window_;
  Session* s = w.session();
  QUndoStack* undo = s->document().undo_stack();
  const recon::LabelSet start = s->document().labels();
  const int steps = undo->count(), index = undo->index();
  std::vector<QImage> plain;
  for (int c = 0; c < s->cameras(); ++c) plain.push_back(w.view(c)->grab().toImage());

  // G: a preview, and no change.
  ASSERT_TRUE(PressGAndWait());
  const Session::FillGridPreview* preview = w.fill_grid_preview();
  ASSERT_NE(preview, nullptr) << w.statusBar()->currentMessage().toStdString();
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->count(), steps);
  EXPECT_EQ(undo->index(), index);
  EXPECT_GT(preview->added, 0);
  EXPECT_EQ(
      preview->added + preview->to_review + preview->confirmed + preview->moved + preview->changed,
      static_cast<int>(preview->edits.size()));
  EXPECT_TRUE(Banner()->isVisible());
  EXPECT_TRUE(
      BannerText().contains(QString("Fill Grid preview, frame %1:").arg(s->frame_number(0))))
      << BannerText().toStdString();
  EXPECT_TRUE(BannerText().contains(QString("%1 new labels").arg(preview->added)));
  EXPECT_TRUE(BannerText().contains("<b>Enter</b> accepts")) << BannerText().toStdString();
  EXPECT_TRUE(BannerText().contains("<b>Esc</b> discards")) << BannerText().toStdString();
  // Every edit is a ghost in its camera's view, drawn in pink where the frame had none.
  int ghosts = 0, checked = 0, pink_before = 0, pink_after = 0;
  for (int c = 0; c < s->cameras(); ++c) {
    const std::vector<ViewOverlay::Ghost>& g = w.view(c)->overlay().ghosts;
    int edits = 0;
    for (const recon::LabelEdit& e : preview->edits) edits += e.camera == c;
    EXPECT_EQ(static_cast<int>(g.size()), edits) << c;
    ghosts += static_cast<int>(g.size());
    const QImage shot = w.view(c)->grab().toImage();
    for (const ViewOverlay::Ghost& ghost : g) {
      if (ghost.kind != ViewOverlay::Ghost::kNew) continue;
      const recon::LabelEdit* e = nullptr;
      for (const recon::LabelEdit& edit : preview->edits)
        if (edit.camera == c && edit.knot == ghost.knot) e = &edit;
      ASSERT_NE(e, nullptr);
      EXPECT_EQ(ghost.px, e->label.px);
      EXPECT_EQ(ghost.review, e->label.state == recon::LabelState::kNeedsReview);
      const QPoint at = w.view(c)->ToWidget(ghost.px).toPoint();
      ++checked;
      pink_before += GhostPinkNear(plain[c], at, 12);
      pink_after += GhostPinkNear(shot, at, 12);
    }
    if (c == 0) shot.save((Dir() / "fill_grid_preview.png").string().c_str());
  }
  EXPECT_EQ(ghosts, static_cast<int>(preview->edits.size()));
  EXPECT_GT(checked, 0);
  EXPECT_EQ(pink_before, 0);
  EXPECT_EQ(pink_after, checked);
  w.grab().save((Dir() / "fill_grid_preview_window.png").string().c_str());

  // Enter: what Session::FillGrid gives on a second project after the same actions.
  const Session::FillGridPreview shown = *preview;
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(w.fill_grid_preview(), nullptr);
  EXPECT_FALSE(Banner()->isVisible());
  EXPECT_EQ(Ghosts(), 0);
  EXPECT_EQ(undo->count(), index + 1);
  EXPECT_EQ(undo->undoText(), "Fill Grid");
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), static_cast<int>(shown.edits.size()));
  const std::unique_ptr<Session> engine = Replay("preview_accept_engine");
  ASSERT_EQ(DifferentLabels(engine->document().labels(), start), 0) << "the replay differs";
  engine->FillGrid(0);
  EXPECT_EQ(DifferentLabels(s->document().labels(), engine->document().labels()), 0);
  int review = 0;
  for (const auto& [c, t, k] : s->document().ReviewItems()) {
    if (t != 0) continue;
    ++review;
    EXPECT_EQ(s->document().Reason(c, t, k), engine->document().Reason(c, t, k)) << c << " " << k;
    EXPECT_NE(s->document().Reason(c, t, k), "") << c << " " << k;
  }
  // Ctrl+Z takes back exactly that step, and Enter then does nothing.
  QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->index(), index);
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(undo->index(), index);
  std::printf(
      "Fill Grid preview on the small shot: %zu edits (%d new, %d of them for review; %d "
      "under review accepted; %d to review; %d moved; %d other); %d labels under review "
      "in frame 0 once applied\n",
      shown.edits.size(), shown.added, shown.added_review, shown.confirmed, shown.to_review,
      shown.moved, shown.changed, review);
}

// Esc discards a preview; so do a label edit, a frame change, an undo and a tracking run, even
// while the preview is still being computed: Enter afterwards changes nothing.
// Each view's caption says how many knots it has to fix in the frame (labels under review and
// missing knots), so that the person can work the camera with the fewest first; accepting a
// label takes one off.
TEST_F(FillGridPreviewTest, EachViewSaysHowManyKnotsItHasToFix) {
  ASSERT_NO_FATAL_FAILURE(Open("to_fix"));
  MainWindow& w = *window_;
  Session* s = w.session();
  const auto to_fix = [&](int c) {
    int n = 0;
    for (int k = 0; k < s->project().knots(); ++k) {
      const recon::Label& l = s->document().at(c, 0, k);
      n += (l.present() && l.state == recon::LabelState::kNeedsReview) ||
           s->missing().Find(c, 0, k) != nullptr;
    }
    return n;
  };
  const auto says = [&](int n) {
    const QString frame = QString("frame %1 · ").arg(s->frame_number(0));
    return frame + (n > 0 ? QString("%1 to fix · ").arg(n) : QString("nothing to fix · "));
  };
  int review_camera = -1, review_knot = -1;
  for (int c = 0; c < s->cameras(); ++c) {
    EXPECT_TRUE(w.view(c)->overlay().caption.contains(says(to_fix(c))))
        << c << ": " << w.view(c)->overlay().caption.toStdString();
    for (int k = 0; k < s->project().knots() && review_knot < 0; ++k)
      if (s->document().at(c, 0, k).present() &&
          s->document().at(c, 0, k).state == recon::LabelState::kNeedsReview)
        review_camera = c, review_knot = k;
  }
  ASSERT_GE(review_knot, 0) << "Find Path left nothing for review";
  const int before = to_fix(review_camera);
  s->AcceptLabel(review_camera, 0, review_knot);
  QCoreApplication::processEvents();
  EXPECT_EQ(to_fix(review_camera), before - 1);
  EXPECT_TRUE(w.view(review_camera)->overlay().caption.contains(says(before - 1)))
      << w.view(review_camera)->overlay().caption.toStdString();
}

TEST_F(FillGridPreviewTest, EscAnEditAFrameChangeOrAnUndoDiscardThePreview) {
  ASSERT_NO_FATAL_FAILURE(Open("preview_discard"));
  MainWindow& w = *window_;
  Session* s = w.session();
  QUndoStack* undo = s->document().undo_stack();
  const recon::LabelSet start = s->document().labels();
  const int index = undo->index();
  const auto expect_none_pending = [&](const char* after) {
    EXPECT_EQ(w.fill_grid_preview(), nullptr) << after;
    EXPECT_FALSE(w.previewing()) << after;
    EXPECT_FALSE(Banner()->isVisible()) << after;
    EXPECT_EQ(Ghosts(), 0) << after;
  };

  // Esc. (A zoomed view keeps its zoom and centre when the bar above the views appears.)
  CameraView* zoomed = w.view(1);
  ZoomAt(zoomed, zoomed->ToImage(QPointF(zoomed->width() / 2.0, zoomed->height() / 2.0)), 4);
  const double scale = zoomed->scale();
  const Eigen::Vector2d centre =
      zoomed->ToImage(QPointF(zoomed->width() / 2.0, zoomed->height() / 2.0));
  const int height = zoomed->height();
  ASSERT_TRUE(PressGAndWait());
  ASSERT_NE(w.fill_grid_preview(), nullptr);
  EXPECT_GT(Ghosts(), 0);
  // The bar takes its room once the layout has run (a posted event: wait for it).
  EXPECT_TRUE(QTest::qWaitFor([&] { return zoomed->height() < height; }, 5000))
      << "the view kept its height " << height << " under the bar";
  EXPECT_EQ(zoomed->scale(), scale);
  EXPECT_LT(
      (zoomed->ToImage(QPointF(zoomed->width() / 2.0, zoomed->height() / 2.0)) - centre).norm(),
      1.0);
  QTest::keyClick(&w, Qt::Key_Escape);
  expect_none_pending("Esc");
  EXPECT_EQ(w.statusBar()->currentMessage(), "Fill Grid preview discarded");
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->index(), index);

  // A label placed by hand (Shift+click) while a preview is pending.
  ASSERT_TRUE(PressGAndWait());
  ASSERT_NE(w.fill_grid_preview(), nullptr);
  const recon::LabelEdit first = w.fill_grid_preview()->edits.front();
  SetKnotOf(first);
  ClickAt(w.view(first.camera), first.label.px + Eigen::Vector2d(0.5, 0.5), Qt::ShiftModifier);
  EXPECT_EQ(undo->index(), index + 1);
  expect_none_pending("an edit");
  const recon::LabelSet edited = s->document().labels();
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(DifferentLabels(s->document().labels(), edited), 0);
  EXPECT_EQ(undo->index(), index + 1);

  // An undo (of that edit).
  ASSERT_TRUE(PressGAndWait());
  ASSERT_NE(w.fill_grid_preview(), nullptr);
  QTest::keyClick(&w, Qt::Key_Z, Qt::ControlModifier);
  expect_none_pending("an undo");
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->index(), index);

  // A frame change, there and back.
  ASSERT_TRUE(PressGAndWait());
  ASSERT_NE(w.fill_grid_preview(), nullptr);
  QTest::keyClick(&w, Qt::Key_F);
  QTest::keyClick(&w, Qt::Key_B);
  ASSERT_EQ(w.frame(), 0);
  expect_none_pending("a frame change");
  EXPECT_EQ(w.statusBar()->currentMessage(), "Fill Grid preview discarded: the frame changed");
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->index(), index);

  // A frame change while the preview is still computed: its answer is dropped.
  QTest::keyClick(&w, Qt::Key_G);
  EXPECT_TRUE(w.previewing());
  EXPECT_TRUE(Banner()->isVisible());
  QTest::keyClick(&w, Qt::Key_F);
  ASSERT_TRUE(w.WaitForIdle(120000));
  expect_none_pending("a frame change during the computation");
  QTest::keyClick(&w, Qt::Key_B);
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(DifferentLabels(s->document().labels(), start), 0);
  EXPECT_EQ(undo->index(), index);

  // A tracking run (one frame).
  ASSERT_TRUE(PressGAndWait());
  ASSERT_NE(w.fill_grid_preview(), nullptr);
  w.TrackTo(1, true);
  expect_none_pending("a tracking run");
  const int tracked = undo->index();
  EXPECT_EQ(tracked, index + 1);
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(undo->index(), tracked);
}

// A preview with nothing to add says so and leaves nothing pending (frame 0 labeled with the
// shot's true labels: every visible knot is there).
TEST_F(MainWindowTest, AFillGridPreviewWithNothingToAddLeavesNothingPending) {
  const std::string project =
      MakeProjectFile("preview_nothing", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  const int index = w.session()->document().undo_stack()->index();
  QTest::keyClick(&w, Qt::Key_G);
  ASSERT_TRUE(w.WaitForIdle(120000));
  EXPECT_EQ(w.fill_grid_preview(), nullptr);
  EXPECT_FALSE(w.findChild<QWidget*>("preview_banner")->isVisible());
  EXPECT_TRUE(w.statusBar()->currentMessage().contains("nothing to add or change"))
      << w.statusBar()->currentMessage().toStdString();
  QTest::keyClick(&w, Qt::Key_Return);
  EXPECT_EQ(w.session()->document().undo_stack()->index(), index);
}

// The session without a window: PreviewFillGrid (on another thread) leaves the document as it
// was and says what FillGrid would do; applied, it gives FillGrid's labels and reasons on a
// second session of the same start, as one undo step that undo takes back. It judges with the
// session's link length, and hands over its own to a session without one.
TEST_F(MainWindowTest, PreviewFillGridAppliesAsFillGridDoesWithTheSessionsLinkLength) {
  // Frame 0 of the true labels with every third inner knot taken out, and one label 6 px off.
  recon::LabelSet start = Truth();
  int removed = 0;
  for (int c = 0; c < static_cast<int>(start.cameras.size()); ++c)
    for (int k = 0; k < start.knots(); ++k) {
      const int row = k / start.cols, col = k % start.cols;
      if (row > 0 && col > 0 && row + 1 < start.rows && col + 1 < start.cols &&
          (row + col) % 3 == 0 && start.at(c, 0, k).present())
        start.at(c, 0, k) = recon::Label{}, ++removed;
    }
  const int moved_knot = start.cols + 1;  // (1, 1): (1 + 1) % 3 != 0, kept
  ASSERT_TRUE(start.at(0, 0, moved_knot).present());
  start.at(0, 0, moved_knot).px += Eigen::Vector2d(6.0, 0.0);
  const std::string file = (Dir() / "preview_start.h5").string();
  recon::WriteLabels(file, start);
  auto previewed = Session::Open(LoadProject(MakeProjectFile("preview_session", file)));
  auto direct = Session::Open(LoadProject(MakeProjectFile("preview_direct", file)));
  const recon::LabelSet before = previewed->document().labels();

  // The preview, on another thread (the frames decoded first in both sessions, for the timing).
  for (int c = 0; c < previewed->cameras(); ++c) previewed->Image(c, 0), direct->Image(c, 0);
  QElapsedTimer timer;
  timer.start();
  const Session::FillGridPreview preview =
      std::async(std::launch::async, [&] { return previewed->PreviewFillGrid(before, 0); }).get();
  const double preview_ms = timer.elapsed();
  EXPECT_EQ(DifferentLabels(previewed->document().labels(), before), 0);
  EXPECT_EQ(previewed->document().undo_stack()->count(), 0);
  EXPECT_EQ(preview.t, 0);
  EXPECT_GT(preview.added, removed / 2);
  EXPECT_LE(preview.added, removed);
  EXPECT_EQ(preview.added + preview.to_review + preview.confirmed + preview.moved + preview.changed,
            static_cast<int>(preview.edits.size()));
  bool moved_judged = false;  // the label 6 px off is flagged or put right
  for (const recon::LabelEdit& e : preview.edits) {
    EXPECT_EQ(e.t, 0);
    if (e.camera == 0 && e.knot == moved_knot)
      moved_judged = e.label.state == recon::LabelState::kNeedsReview ||
                     (e.label.px - Truth().at(0, 0, moved_knot).px).norm() < 1.0;
  }
  EXPECT_TRUE(moved_judged);

  // Applied: FillGrid's labels and reasons, one step.
  timer.restart();
  direct->FillGrid(0);
  const double direct_ms = timer.elapsed();
  EXPECT_EQ(previewed->ApplyFillGridPreview(preview), static_cast<int>(preview.edits.size()));
  EXPECT_EQ(previewed->document().undo_stack()->count(), 1);
  EXPECT_EQ(previewed->document().undo_stack()->undoText(), "Fill Grid");
  EXPECT_EQ(DifferentLabels(previewed->document().labels(), direct->document().labels()), 0);
  const std::vector<LabelKey> review = direct->document().ReviewItems();
  EXPECT_EQ(previewed->document().ReviewItems(), review);
  for (const auto& [c, t, k] : review)
    EXPECT_EQ(previewed->document().Reason(c, t, k), direct->document().Reason(c, t, k));
  // Undo: the start again.
  previewed->document().undo_stack()->undo();
  EXPECT_EQ(DifferentLabels(previewed->document().labels(), before), 0);
  std::printf(
      "PreviewFillGrid: %zu edits in %.0f ms (the process's first engine run, warm-up "
      "included); FillGrid %.0f ms (%d labels removed)\n",
      preview.edits.size(), preview_ms, direct_ms, removed);

  // The link length: a preview judges with the one the session's engine already has (estimated
  // on another frame), not an estimate of its own; a preview applied to a session without one
  // gives it the preview's estimate. Either way the next Fill Grid judges as after FillGrid.
  {
    // The true labels, each moved by up to 0.3 px (the exact ones give 0.1 m in every frame).
    recon::LabelSet noisy = Truth();
    for (int c = 0; c < static_cast<int>(noisy.cameras.size()); ++c)
      for (int t = 0; t < noisy.frames(); ++t)
        for (int k = 0; k < noisy.knots(); ++k)
          noisy.at(c, t, k).px += 0.3 * Eigen::Vector2d(std::sin(7.1 * (c + 3 * t + 11 * k)),
                                                        std::cos(5.3 * (2 * c + t + 7 * k)));
    const std::string truth = (Dir() / "link_noisy.h5").string();
    recon::WriteLabels(truth, noisy);
    auto estimated = Session::Open(LoadProject(MakeProjectFile("link_estimated", truth)));
    auto fresh = Session::Open(LoadProject(MakeProjectFile("link_fresh", truth)));
    ASSERT_EQ(estimated->project().mesh_m, 0.0);  // estimated by the engine
    EXPECT_EQ(estimated->link_length_m(), 0.0);
    estimated->FillGrid(0);
    const double frame0 = estimated->link_length_m();
    ASSERT_GT(frame0, 0.0);
    // Frame 20 alone estimates another length (other labels, other noise).
    const recon::LabelSet labels = fresh->document().labels();
    const double frame20 = fresh->PreviewFillGrid(labels, 20).link_length_m;
    ASSERT_GT(frame20, 0.0);
    ASSERT_NE(frame20, frame0);
    EXPECT_EQ(estimated->PreviewFillGrid(labels, 20).link_length_m, frame0);
    // Applied, a preview hands its estimate to a session that has none.
    EXPECT_EQ(fresh->link_length_m(), 0.0);
    fresh->ApplyFillGridPreview(fresh->PreviewFillGrid(labels, 20));
    EXPECT_EQ(fresh->link_length_m(), frame20);
    std::printf("link length: %.9f m from frame 0, %.9f m from frame 20\n", frame0, frame20);
  }
}

// netlab gui --keys G --screenshot: the screenshot shows the preview's ghosts (pink below the
// bar, where a screenshot without it has none); an unknown key, or --keys without a screenshot,
// is named.
TEST_F(MainWindowTest, TheScreenshotCanPressGFirstAndNamesAKeyNoActionHas) {
  recon::LabelSet start = Truth();
  for (int c = 0; c < static_cast<int>(start.cameras.size()); ++c)
    for (int k = 0; k < start.knots(); ++k)
      if (k % start.cols > 0 && k % start.cols + 1 < start.cols && k / start.cols % 2 == 1)
        start.at(c, 0, k) = recon::Label{};
  const std::string file = (Dir() / "keys_start.h5").string();
  recon::WriteLabels(file, start);
  const std::string project = MakeProjectFile("keys_cli", file);
  const auto pink_below_bar = [](const std::string& png) {
    const QImage image(QString::fromStdString(png));
    const QColor pink = QColor::fromRgb(CameraView::kGhostColour);
    int n = 0;
    for (int y = 150; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        const QColor c = image.pixelColor(x, y);
        n += std::abs(c.red() - pink.red()) < 30 && std::abs(c.green() - pink.green()) < 30 &&
             std::abs(c.blue() - pink.blue()) < 30;
      }
    return n;
  };
  const std::string plain = (Dir() / "keys_plain.png").string();
  const std::string preview = (Dir() / "keys_preview.png").string();
  const auto without = RunNetlab("gui " + project + " --screenshot " + plain);
  ASSERT_EQ(without.status, 0) << without.err;
  const auto with = RunNetlab("gui " + project + " --keys G --screenshot " + preview);
  ASSERT_EQ(with.status, 0) << with.err;
  // Without a preview no ghost: at most a few antialiased edge pixels of the magenta marks
  // (a missing knot's ring, the reprojected cross, the timeline's marks) blend into the pink's
  // tolerance.
  const int plain_pink = pink_below_bar(plain);
  EXPECT_LE(plain_pink, 5);
  EXPECT_GT(pink_below_bar(preview), 100 + plain_pink);
  const auto unknown = RunNetlab("gui " + project + " --keys Ctrl+Alt+F12 --screenshot " + plain);
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.err.find("no action of the window has the key 'Ctrl+Alt+F12'"),
            std::string::npos)
      << unknown.err;
  const auto alone = RunNetlab("gui " + project + " --keys G");
  EXPECT_EQ(alone.status, 2);
  EXPECT_NE(alone.err.find("--keys needs --screenshot"), std::string::npos) << alone.err;
}

// netlab gui EXPERIMENT.yaml ... --knotless makes the project of a knotless net (Net B), and
// opens it.
// The recording room on the shot with one frame file of cam2 removed: the check lists it as
// missing in cam2, the room's timeline marks it, the screenshot is drawn, and a click on its row
// takes the person to that frame in the labeling room. The calibration room lists the rig's four
// cameras with their baselines.
TEST_F(MainWindowTest, TheRecordingRoomListsAMissingFrameAndAClickGoesToIt) {
  const fs::path shot = Dir() / "shot_damaged";
  fs::remove_all(shot);
  fs::copy(Dir() / "shot", shot, fs::copy_options::recursive);
  ASSERT_TRUE(fs::remove(shot / "cam2/frame_000005.pgm"));
  const std::string d = Dir().string(), project = d + "/damaged.yaml";
  fs::remove(d + "/damaged.h5");
  SaveProject(MakeProject((shot / "experiment.yaml").string(), (shot / "rig_true.yaml").string(),
                          d + "/coloring.yaml", d + "/damaged.h5", 0, 0),
              project);
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenShown(w, project));
  EXPECT_EQ(w.room(), MainWindow::Room::kLabeling);
  w.ShowRoom(MainWindow::Room::kRecording);
  ASSERT_TRUE(w.WaitForIdle());
  ASSERT_NE(w.recording(), nullptr);
  ASSERT_TRUE(w.recording()->report().has_value());
  QTableWidget* table = w.recording_room()->table();
  int row = -1;
  for (int r = 0; r < table->rowCount(); ++r)
    if (table->item(r, 0)->text() == "cam2" && table->item(r, 1)->text() == "missing") row = r;
  ASSERT_GE(row, 0) << "no row says cam2 misses a frame";
  EXPECT_EQ(table->item(row, 2)->text(), "5 (1 frame)");
  EXPECT_TRUE(
      w.recording_room()->timeline()->review_frames().count(5 - w.session()->frame_number(0)));
  // The labeling room's docks and keys are not the recording room's.
  EXPECT_FALSE(w.findChild<QDockWidget*>("review_dock")->isVisible());
  const QImage image = w.grab().toImage();
  image.save(QString::fromStdString(d + "/recording_room.png"));
  std::set<QRgb> colours;
  for (int y = 0; y < image.height(); y += 7)
    for (int x = 0; x < image.width(); x += 7) colours.insert(image.pixel(x, y));
  EXPECT_GT(colours.size(), 20u) << "the screenshot is (nearly) blank";
  // A click on the row: the labeling room at frame 5.
  QTest::mouseClick(table->viewport(), Qt::LeftButton, Qt::NoModifier,
                    table->visualItemRect(table->item(row, 0)).center());
  EXPECT_EQ(w.room(), MainWindow::Room::kLabeling);
  EXPECT_EQ(w.session()->frame_number(w.frame()), 5);
  EXPECT_TRUE(w.findChild<QDockWidget*>("review_dock")->isVisible());
  // The calibration room: one row per rig camera, the baselines said.
  w.ShowRoom(MainWindow::Room::kCalibration);
  QTableWidget* rig = w.calibration_room()->table();
  ASSERT_EQ(rig->rowCount(), w.session()->cameras());
  EXPECT_EQ(rig->item(0, 0)->text(), QString::fromStdString(w.session()->rig().cameras[0].name));
  EXPECT_TRUE(w.findChild<QLabel*>("calibration_summary")->text().contains("baselines"));
  // The sketch draws every camera where it places its centre (a frustum's apex), and turns.
  RigSketch* sketch = w.calibration_room()->sketch();
  const QImage drawn = sketch->grab().toImage();
  const QRgb background = drawn.pixel(drawn.width() - 3, drawn.height() - 3);
  const auto drawn_near = [&](const QPointF& at) {
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const QPoint p = at.toPoint() + QPoint(dx, dy);
        if (drawn.rect().contains(p) && drawn.pixel(p) != background) return true;
      }
    return false;
  };
  for (const calib::Camera& camera : w.session()->rig().cameras)
    EXPECT_TRUE(drawn_near(sketch->ToScreen(camera.Center()))) << camera.name << " not drawn";
  EXPECT_FALSE(drawn_near(QPointF(drawn.width() - 8, drawn.height() - 8)));
  const QPointF before = sketch->ToScreen(w.session()->rig().cameras[0].Center());
  QTest::mousePress(sketch, Qt::LeftButton, Qt::NoModifier, QPoint(100, 100));
  QMouseEvent drag(QEvent::MouseMove, QPointF(160, 110), QPointF(160, 110), Qt::NoButton,
                   Qt::LeftButton, Qt::NoModifier);
  QApplication::sendEvent(sketch, &drag);
  EXPECT_GT((sketch->ToScreen(w.session()->rig().cameras[0].Center()) - before).manhattanLength(),
            5.0)
      << "dragging did not turn the rig";
}

// A recording alone (no rig, no labels): the recording room checks it, the other rooms wait for
// a project; from the command line too (--room recording --screenshot).
TEST_F(MainWindowTest, ARecordingAloneOpensInTheRecordingRoom) {
  const fs::path shot = Dir() / "shot_alone";
  fs::remove_all(shot);
  fs::copy(Dir() / "shot", shot, fs::copy_options::recursive);
  ASSERT_TRUE(fs::remove(shot / "cam1/frame_000007.pgm"));
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  QString error;
  ASSERT_TRUE(w.OpenRecording(QString::fromStdString((shot / "experiment.yaml").string()), &error))
      << error.toStdString();
  ASSERT_TRUE(w.WaitForIdle(20000));
  EXPECT_EQ(w.room(), MainWindow::Room::kRecording);
  EXPECT_EQ(w.session(), nullptr);
  QTableWidget* table = w.recording_room()->table();
  ASSERT_EQ(table->rowCount(), 1);
  EXPECT_EQ(table->item(0, 0)->text(), "cam1");
  EXPECT_EQ(table->item(0, 2)->text(), "7 (1 frame)");
  auto* rooms = w.findChild<QTabBar*>("rooms");
  ASSERT_NE(rooms, nullptr);
  EXPECT_FALSE(rooms->isTabEnabled(static_cast<int>(MainWindow::Room::kLabeling)));
  EXPECT_FALSE(w.findChild<QDockWidget*>("review_dock")->isVisible())
      << "the labeling room's docks without a labeling room";
  w.ShowRoom(MainWindow::Room::kLabeling);
  EXPECT_EQ(w.room(), MainWindow::Room::kRecording) << "no labeling room without a project";
  EXPECT_FALSE(w.OpenRecording("/nonexistent/experiment.yaml", &error));
  EXPECT_TRUE(error.contains("/nonexistent/experiment.yaml")) << error.toStdString();
  const std::string png = (Dir() / "alone.png").string();
  const auto run = RunNetlab("gui " + (shot / "experiment.yaml").string() +
                             " --room recording --screenshot " + png);
  EXPECT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(fs::exists(png));
  const auto refused = RunNetlab("gui " + (shot / "experiment.yaml").string() + " --frame 3");
  EXPECT_EQ(refused.status, 1);
  EXPECT_NE(refused.err.find("--room recording"), std::string::npos) << refused.err;
}

TEST_F(MainWindowTest, TheCommandLineMakesAKnotlessProject) {
  const std::string d = Dir().string();
  const std::string project = d + "/knotless_cli.yaml";
  fs::remove(d + "/knotless_cli.h5");
  const auto made = RunNetlab("gui " + d + "/shot/experiment.yaml --rig " + d +
                              "/shot/rig_true.yaml --coloring " + d + "/coloring.yaml --labels " +
                              d + "/knotless_cli.h5 --knotless --project " + project +
                              " --screenshot " + d + "/knotless_cli.png");
  ASSERT_EQ(made.status, 0) << made.err;
  EXPECT_TRUE(LoadProject(project).knotless);
  EXPECT_TRUE(fs::exists(d + "/knotless_cli.png"));
}

// The preview's two actions are in F1's cheat sheet with their keys, and in the shortcut editor
// (changeable as the others), where their defaults clash with no other action's.
// (No project: the actions are there from the start, so no shot is rendered for this test.)
TEST(FillGridPreviewKeys, AreInTheCheatSheetAndTheShortcutEditor) {
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
  std::map<QString, QString> listed;
  QTimer::singleShot(200, [&] {
    QWidget* dialog = QApplication::activeModalWidget();
    if (dialog == nullptr) return;
    if (const auto* table = dialog->findChild<QTableWidget*>())
      for (int r = 0; r < table->rowCount(); ++r)
        listed[table->item(r, 0)->text()] = table->item(r, 1)->text();
    dialog->close();
  });
  QTest::keyClick(&w, Qt::Key_F1);
  const auto native = [](const char* keys) {
    return QKeySequence(keys).toString(QKeySequence::NativeText);
  };
  EXPECT_EQ(listed["Accept Fill Grid preview"], native("Return") + "  or  " + native("Enter"));
  EXPECT_EQ(listed["Discard preview"], native("Esc"));
  EXPECT_EQ(listed["Fill Grid in this frame"], native("G"));
  const QList<QAction*> all = w.actions();
  ShortcutEditor editor({all.begin(), all.end()});
  const int accept = editor.RowOf("Accept Fill Grid preview");
  const int discard = editor.RowOf("Discard preview");
  ASSERT_GE(accept, 0);
  ASSERT_GE(discard, 0);
  EXPECT_EQ(editor.DefaultKeys(accept),
            (QList<QKeySequence>{QKeySequence(Qt::Key_Return), QKeySequence(Qt::Key_Enter)}));
  EXPECT_EQ(editor.DefaultKeys(discard), QList<QKeySequence>{QKeySequence(Qt::Key_Escape)});
  EXPECT_TRUE(editor.Conflicts().isEmpty()) << editor.Conflicts().join("; ").toStdString();
}

}  // namespace
}  // namespace netlab::gui
