// bench_gui: the workstation's speed as a person feels it, on a rendered shot (Qt's offscreen
// platform, raster drawing; a printed table, never a test).
//
//   netlab simulate scenarios/net_a_0.5.yaml --duration 0.4 --out sim.h5
//   netlab color-net --knots 11x11 --out coloring.yaml
//   netlab render --sim sim.h5 --out shot --frames 0:59 --coloring coloring.yaml
//   build/bench/bench_gui --shot shot --coloring coloring.yaml [--target sim.h5] [--frames 40]
//                         [--part A|B|C] [--json]
//
// A. Frame change latency: from the key press (Right) to all four 2048^2 views painted with the
//    frame's labels (labels_true.h5: every visible knot) and overlays, over `--frames` frames:
//    uncached (first visit, the cache emptied by a new window) and cached (the same frames
//    again), at full and half resolution.
// B. The scripted person (tests/app/gui/scripted_person.h) labeling the shot through the window:
//    actions per knot-frame and wall time per action, and the visible knot-frames the review
//    queue never offered (left unlabeled), by how many other cameras labeled the knot there, and
//    each on a line: camera, frame, knot, where the truth has it and why the missing knots do
//    not list it (recon::WhyNotMissing).
//    --target (the project's target: the simulation the shot was rendered from, or the shot's
//    truth.h5) keeps the knots the target hides off the queue, as a project with a target does.
// C. Frame change with the 3D view open: the reconstruction room over the true labels
//    triangulated (netlab triangulate's engine, --ba points), each step of its frame slider
//    timed until the 3D view has painted the new frame (the window's frame follows it).
// --json prints cached_ms, uncached_half_ms and three_d_ms ({median, p95}),
// actions_per_knot_frame, never_offered and wrong (part B).

#include <QApplication>
#include <QElapsedTimer>
#include <QPushButton>
#include <QSlider>
#include <QTest>
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

#include "app/gui/document/missing_knots.h"
#include "app/gui/document/project.h"
#include "app/gui/main_window.h"
#include "app/gui/reconstruction_room.h"
#include "libreconstruct/labeling/missing_knots.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/gui/scripted_person.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

struct Stats {
  double median = 0, p95 = 0, max = 0;
};

Stats Summarise(std::vector<double> ms) {
  Stats s;
  if (ms.empty()) return s;
  std::sort(ms.begin(), ms.end());
  s.median = ms[ms.size() / 2];
  s.p95 = ms[std::min(ms.size() - 1, static_cast<size_t>(0.95 * ms.size()))];
  s.max = ms.back();
  return s;
}

// A project over the shot whose labels start as `start` (copied) or empty.
std::string ProjectFile(const std::string& shot, const std::string& coloring,
                        const std::string& dir, const std::string& name, const std::string& start,
                        const std::string& target = "") {
  const std::string labels = dir + "/" + name + ".h5";
  fs::remove(labels);
  fs::remove(labels + ".journal");
  if (!start.empty()) fs::copy_file(start, labels);
  const std::string path = dir + "/" + name + ".yaml";
  Project project =
      MakeProject(shot + "/experiment.yaml", shot + "/rig_true.yaml", coloring, labels, 0, 0);
  if (!target.empty()) project.target = fs::absolute(target).string();
  SaveProject(project, path);
  return path;
}

// Frame changes by key presses, each timed until the four views are painted.
std::vector<double> ScrubTimes(MainWindow* w, int frames) {
  std::vector<double> ms;
  for (int i = 0; i < frames; ++i) {
    QElapsedTimer timer;
    timer.start();
    std::array<long, 4> painted{};
    for (int c = 0; c < 4; ++c) painted[c] = w->view(c)->paints();
    QTest::keyClick(w, Qt::Key_Right);
    if (!w->WaitForFrame(60000)) break;
    // Until every view has painted the new frame with its overlays (the window's event loop
    // paints them once the frame is shown; a repaint here would paint them twice).
    const auto all_painted = [&] {
      for (int c = 0; c < w->session()->cameras() && c < 4; ++c)
        if (w->view(c)->isVisible() && w->view(c)->paints() == painted[c]) return false;
      return true;
    };
    while (!all_painted() && timer.elapsed() < 60000)
      QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents, 5);
    ms.push_back(timer.nsecsElapsed() * 1e-6);
  }
  return ms;
}

// Uncached, then cached, latency at one resolution (a new window: an empty cache).
std::pair<Stats, Stats> Latency(const std::string& project, bool half, int frames) {
  MainWindow w;
  w.resize(1600, 1000);
  w.show();
  w.OpenProject(QString::fromStdString(project), false);
  w.SetHalfResolution(half);
  w.WaitForFrame(60000);
  // Uncached: the prefetch is not given time to run ahead (the person scrubs at once).
  const Stats uncached = Summarise(ScrubTimes(&w, frames));
  w.SetFrame(0);
  w.WaitForFrame(60000);
  const auto before = w.session()->cache().stats();
  const Stats cached = Summarise(ScrubTimes(&w, frames));
  const auto after = w.session()->cache().stats();
  // Whether the second pass really came from the cache (a budget too small for the shot at this
  // level evicts frames ahead of the playhead).
  std::printf(
      "(%s resolution, second pass: %ld cache hits, %ld misses, %ld evicted; %.0f of "
      "%.0f MiB cached)\n",
      half ? "half" : "full", after.hits - before.hits, after.misses - before.misses,
      after.evicted - before.evicted, after.bytes / 1048576.0,
      w.session()->cache().limit() / 1048576.0);
  return {uncached, cached};
}

// C: the reconstruction room's frame changes with the 3D view, after triangulating the labels.
Stats ThreeDTimes(const std::string& project, int frames) {
  MainWindow w;
  w.resize(1600, 1000);
  w.show();
  w.OpenProject(QString::fromStdString(project), false);
  w.WaitForFrame(60000);
  w.ShowRoom(MainWindow::Room::kReconstruction);
  ReconstructionRoom* room = w.reconstruction_room();
  QTest::mouseClick(room->triangulate_button(), Qt::LeftButton);
  QElapsedTimer wait;
  wait.start();
  while (room->busy() && wait.elapsed() < 600000) QTest::qWait(20);
  room->SetFrame(0);
  QTest::qWait(50);
  std::vector<double> ms;
  for (int t = 1; t <= frames; ++t) {
    const long painted = room->view()->paints();
    QElapsedTimer timer;
    timer.start();
    room->frame_slider()->setValue(t);
    while (room->view()->paints() == painted && timer.elapsed() < 60000)
      QCoreApplication::processEvents(QEventLoop::AllEvents | QEventLoop::WaitForMoreEvents, 5);
    ms.push_back(timer.nsecsElapsed() * 1e-6);
  }
  return Summarise(ms);
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  using namespace netlab::gui;
  std::string shot, coloring, target;
  int frames = 40;
  bool json = false;
  std::string part = "ABC";  // --part A, B or C: that part only
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--shot" && i + 1 < argc)
      shot = argv[++i];
    else if (a == "--coloring" && i + 1 < argc)
      coloring = argv[++i];
    else if (a == "--target" && i + 1 < argc)
      target = argv[++i];
    else if (a == "--frames" && i + 1 < argc)
      frames = std::stoi(argv[++i]);
    else if (a == "--json")
      json = true;
    else if (a == "--part" && i + 1 < argc &&
             (std::string(argv[i + 1]) == "A" || std::string(argv[i + 1]) == "B" ||
              std::string(argv[i + 1]) == "C"))
      part = argv[++i];
    else {
      std::fprintf(
          stderr,
          "usage: bench_gui --shot DIR --coloring coloring.yaml [--target FILE] [--frames N] "
          "[--part A|B|C] [--json]\n");
      return 2;
    }
  }
  if (shot.empty() || coloring.empty()) {
    std::fprintf(stderr,
                 "bench_gui: --shot and --coloring are needed (see the top of "
                 "bench/gui_bench.cc for how to make them)\n");
    return 2;
  }
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
  int qt_argc = 1;
  QApplication app(qt_argc, argv);
  const std::string dir = (fs::temp_directory_path() / "netlab_bench_gui").string();
  fs::create_directories(dir);
  const netlab::recon::LabelSet truth = netlab::recon::ReadLabels(shot + "/labels_true.h5");
  frames = std::min(frames, truth.frames() - 1);

  // A. Latency with every visible knot labeled.
  Stats full_uncached, full_cached, half_uncached, half_cached;
  if (part.find('A') != std::string::npos) {
    const std::string labeled =
        ProjectFile(shot, coloring, dir, "latency", shot + "/labels_true.h5");
    std::tie(full_uncached, full_cached) = Latency(labeled, false, frames);
    std::tie(half_uncached, half_cached) = Latency(labeled, true, frames);
    std::printf(
        "A. frame change latency, 4 cameras, %d labels per camera-frame at most, %d frames "
        "(ms: median / p95 / max)\n",
        truth.knots(), frames);
    std::printf("| resolution | uncached | from cache |\n|---|---|---|\n");
    auto row = [](const char* name, const Stats& u, const Stats& c) {
      std::printf("| %s | %.1f / %.1f / %.1f | %.1f / %.1f / %.1f |\n", name, u.median, u.p95,
                  u.max, c.median, c.p95, c.max);
    };
    row("full", full_uncached, full_cached);
    row("half", half_uncached, half_cached);
  }

  // B. The scripted person through the window.
  double per_knot_frame = 0;
  long never_offered = 0, wrong_accepted = 0;
  if (part.find('B') != std::string::npos) {
    MainWindow w;
    w.resize(1600, 1000);
    w.show();
    w.OpenProject(QString::fromStdString(ProjectFile(shot, coloring, dir, "session", "", target)),
                  false);
    w.WaitForFrame(60000);
    QElapsedTimer timer;
    timer.start();
    // No cap on the review items: the queue is walked to its end.
    const ScriptedSession session = PlayScriptedSession(&w, truth, 1 << 30);
    const double wall_s = timer.nsecsElapsed() * 1e-9;
    // Person actions: the labeling ones, plus the keys that start Find Path and each run (counted
    // in actions), plus the keys that only went to a review item (Ctrl+Home, Space).
    const int actions = static_cast<int>(session.actions.size()) + session.navigation;
    std::array<int, Action::kKinds> kinds{};
    for (const Action& a : session.actions) ++kinds[a.kind];
    long knot_frames = 0;
    for (int c = 0; c < static_cast<int>(truth.cameras.size()); ++c)
      for (int t = 0; t < truth.frames(); ++t)
        for (int k = 0; k < truth.knots(); ++k) knot_frames += truth.at(c, t, k).present();
    per_knot_frame = knot_frames > 0 ? double(actions) / knot_frames : 0.0;
    // What the session left: accepted labels right (<= 2 px) and wrong, visible knots unlabeled.
    long right = 0, wrong = 0, unlabeled = 0;
    // The unlabeled ones by how many other cameras have a label of the knot in that frame, and
    // each with why the missing knots do not list it.
    std::array<long, 4> unlabeled_by_others{};
    std::vector<std::string> unlabeled_lines;
    const netlab::recon::LabelSet& got = w.session()->document().labels();
    const MissingKnots& missing = w.session()->missing();
    for (int c = 0; c < static_cast<int>(got.cameras.size()); ++c)
      for (int t = 0; t < got.frames(); ++t)
        for (int k = 0; k < got.knots(); ++k) {
          const auto& l = got.at(c, t, k);
          const auto& want = truth.at(truth.FindCamera(got.cameras[c]), t, k);
          const bool accepted = l.accepted();
          if (accepted && want.present() && (l.px - want.px).norm() <= 2.0)
            ++right;
          else if (accepted)
            ++wrong;
          else if (want.present()) {
            ++unlabeled;
            int others = 0;
            for (int o = 0; o < static_cast<int>(got.cameras.size()); ++o)
              others += o != c && got.at(o, t, k).present();
            ++unlabeled_by_others[std::min(others, 3)];
            char head[160];
            std::snprintf(head, sizeof head,
                          "   never offered: %s frame %d knot %d (row %d, col %d) at (%.1f, "
                          "%.1f) in the truth, labeled in %d other cameras: ",
                          got.cameras[c].c_str(), got.frame_index[t], k, k / got.cols, k % got.cols,
                          want.px.x(), want.px.y(), others);
            unlabeled_lines.push_back(head + netlab::recon::WhyNotMissing(got, w.session()->rig(),
                                                                          missing.rig_index(), c, t,
                                                                          k, missing.options()));
          }
        }
    std::printf(
        "\nB. the scripted person through the window: %d actions (%d review items) for %ld "
        "visible knot-frames: %.4f actions per knot-frame; %.1f s in all, %.0f ms per "
        "action%s\n",
        actions, session.review_items, knot_frames, per_knot_frame, wall_s,
        actions > 0 ? 1000.0 * wall_s / actions : 0.0,
        session.finished ? "" : " (the tracking run did not end)");
    std::printf(
        "   actions: %d Find Node clicks, %d by hand (Shift+click), %d deletes, %d hidden marks "
        "(D), %d hidden runs (Shift+D), %d accepts, %d Find Path, %d tracking runs, %d keys to go "
        "to a review item; %d review items fixed\n",
        kinds[Action::kFindNode], kinds[Action::kPlace], kinds[Action::kDelete],
        kinds[Action::kHide], kinds[Action::kHideRun], kinds[Action::kAccept],
        kinds[Action::kFindPath], kinds[Action::kTrack], session.navigation, session.review_items);
    std::printf(
        "   left: %ld accepted labels right, %ld wrong, %ld visible knot-frames never offered "
        "(unlabeled: the review queue never listed them; labeled in 0 / 1 / 2 / 3 other "
        "cameras: %ld / %ld / %ld / %ld), %zu labels still for review, %d missing knots "
        "listed\n",
        right, wrong, unlabeled, unlabeled_by_others[0], unlabeled_by_others[1],
        unlabeled_by_others[2], unlabeled_by_others[3],
        w.session()->document().ReviewItems().size(), w.session()->missing().size());
    for (const std::string& line : unlabeled_lines) std::printf("%s\n", line.c_str());
    never_offered = unlabeled;
    wrong_accepted = wrong;
  }
  // C. The 3D view.
  Stats three_d;
  if (part.find('C') != std::string::npos) {
    three_d =
        ThreeDTimes(ProjectFile(shot, coloring, dir, "three_d", shot + "/labels_true.h5"), frames);
    std::printf(
        "\nC. frame change with the 3D view open (the reconstruction room, the true labels "
        "triangulated), %d frames: %.1f / %.1f / %.1f ms (median / p95 / max)\n",
        frames, three_d.median, three_d.p95, three_d.max);
  }
  if (json)
    std::printf(
        "{\"cached_ms\": {\"median\": %.3f, \"p95\": %.3f}, \"uncached_half_ms\": "
        "{\"median\": %.3f, \"p95\": %.3f}, \"three_d_ms\": {\"median\": %.3f, \"p95\": "
        "%.3f}, \"actions_per_knot_frame\": %.6f, \"never_offered\": %ld, \"wrong\": %ld}\n",
        full_cached.median, full_cached.p95, half_uncached.median, half_uncached.p95,
        three_d.median, three_d.p95, per_knot_frame, never_offered, wrong_accepted);
  fs::remove_all(dir);
  return 0;
}
