// The workstation's window on a shot rendered by `netlab render`, driven by real mouse and key
// events (Qt's offscreen platform): a scripted person seeds the corners, runs Find Path and a
// tracking run, fixes every review item with Find Node at the true place, saves. The labels file
// must equal what the same actions give on the engine without a window, with no wrong accepted
// label. And a screenshot: the overlays are drawn where the labels are.

#include "app/gui/main_window.h"

#include <gtest/gtest.h>

#include <QAction>
#include <QApplication>
#include <QDockWidget>
#include <QLabel>
#include <QStatusBar>
#include <QTableView>
#include <QTableWidget>
#include <QTimer>
#include <QTest>
#include <QWheelEvent>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "app/gui/camera_view.h"
#include "app/gui/document/project.h"
#include "app/gui/timeline.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"
#include "tests/app/gui/scripted_person.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;
using testing::RunNetlab;

// The command tests' small shot (a 6 x 6-knot net past a box), 0.2 s long (36 frames).
std::string Shot() {
  std::string scenario = testing::kSmallShotScenario;
  const std::string from = "duration: 0.06", to = "duration: 0.2";
  return scenario.replace(scenario.find(from), from.size(), to);
}
constexpr int kLastFrame = 30;  // frames 0..30: a tracking run of 30 frames

const fs::path& Dir() {
  static const fs::path dir =
      fs::temp_directory_path() / ("netlab_gui_test_" + std::to_string(getpid()));
  return dir;
}

class MainWindowTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Dir());
    fs::create_directories(Dir());
    std::ofstream((Dir() / "shot.yaml").string()) << Shot();
    const std::string d = Dir().string();
    ASSERT_EQ(RunNetlab("simulate " + d + "/shot.yaml --out " + d + "/sim.h5 --quiet").status, 0);
    ASSERT_EQ(RunNetlab("color-net --knots 6x6 --out " + d + "/coloring.yaml --quiet").status, 0);
    const auto render =
        RunNetlab("render --sim " + d + "/sim.h5 --out " + d +
                  "/shot --frames 0:" + std::to_string(kLastFrame) +
                  " --calibration-views 0 --coloring " + d + "/coloring.yaml --quiet");
    ASSERT_EQ(render.status, 0) << render.err;
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
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
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
      case Action::kFindNode:
        engine->FindNode(a.camera, a.t, a.knot, a.px, 6.0);
        break;
      case Action::kPlace:
        engine->PlaceLabel(a.camera, a.t, a.knot, a.px);
        break;
      case Action::kDelete:
        engine->DeleteLabel(a.camera, a.t, a.knot);
        break;
      case Action::kAccept:
        engine->AcceptLabel(a.camera, a.t, a.knot);
        break;
      case Action::kFindPath:
        engine->FindPathFromCorners(0);
        break;
      case Action::kTrack:
        engine->ApplyTrackRun(engine->Track(engine->document().labels(), a.t, kLastFrame, nullptr,
                                            {}, MainWindow::kMaxReviewPerFrame));
        break;
      case Action::kHide:
        engine->MarkHidden(a.camera, a.t, a.knot);
        break;
      case Action::kHideRun:
        engine->MarkHiddenRun(a.camera, a.t, a.knot);
        break;
    }
  const recon::LabelSet& direct = engine->document().labels();
  int differ = 0;
  for (int c = 0; c < s->cameras(); ++c)
    for (int t = 0; t < saved.frames(); ++t)
      for (int k = 0; k < saved.knots(); ++k) {
        const recon::Label &a = saved.at(c, t, k), &b = direct.at(c, t, k);
        const bool different = a.present() != b.present() || a.state != b.state ||
                               a.source != b.source ||
                               (a.present() && (a.px - b.px).norm() > 1e-9);
        if (different && ++differ <= 5)
          ADD_FAILURE() << "camera " << c << " frame " << t << " knot " << k << ": window "
                        << (a.present() ? "present" : "absent") << " state "
                        << int(a.state) << " source " << int(a.source) << ", engine "
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
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
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
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
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
int KnotSeenByAll(const recon::LabelSet& truth, int t) {
  for (int k = 0; k < truth.knots(); ++k) {
    const int row = k / truth.cols, col = k % truth.cols;
    if (row == 0 || col == 0 || row + 1 == truth.rows || col + 1 == truth.cols) continue;
    bool seen = true;
    for (int c = 0; c < static_cast<int>(truth.cameras.size()); ++c)
      seen = seen && truth.at(c, t, k).present() && truth.at(c, t, k).px.minCoeff() > 60;
    if (seen) return k;
  }
  return -1;
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
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
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
  const auto* timeline = w.findChild<Timeline*>();
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

// D on a missing knot (no label selected) marks it hidden, one undo step, and it leaves the
// queue; Ctrl+Z lists it again. Shift+D marks it hidden through the frames it is missing in,
// one step, and stops where the camera has a label again.
TEST_F(MainWindowTest, DMarksAMissingKnotHiddenAndShiftDTheFramesAfterIt) {
  const recon::LabelSet truth = Truth();
  const std::string project = MakeProjectFile("hidden", (Dir() / "shot/labels_true.h5").string());
  MainWindow w;
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
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
  w.resize(1400, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
  w.activateWindow();
  ASSERT_TRUE(QTest::qWaitForWindowActive(&w));
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
    if (std::get<1>(key) == t && std::get<2>(key) != k)
      s->MarkHidden(std::get<0>(key), t, std::get<2>(key));
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
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
  QApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
