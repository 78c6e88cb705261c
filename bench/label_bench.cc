// The labeling engine against a scripted user, on a rendered shot with its truth.
//
//   bench_label --shot DIR [--coloring FILE] [--target SIM.h5] [--frames A:B]
//               [--cameras cam0,cam1] [--radius PX] [--seed N] [--detector] [--fill-grid-between]
//
// DIR is the output of `netlab render` (experiment.yaml, rig_true.yaml, labels_true.h5). The
// script plays the person: it seeds the four corners of the first frame in every camera that
// sees them (one action each), runs the engine (Find Path in the first frame; then tracking, the
// epipolar check and Fill Grid frame by frame), and after each frame, wherever a visible knot is
// unlabeled or flagged for review, performs one Find Node at the true position (brush radius
// --radius); when Find Node says none or several, it clicks the knot by hand (a second action,
// the true position off by up to 0.5 px). A label under review on a knot the truth says is
// hidden is deleted (one action). Accepted labels are never checked by the script: a wrong one
// stays wrong and is counted. After the person's labels of a frame the engine checks the knots'
// other labels against them (LabelEngine::CheckAgainstPerson), and the person fixes what that
// turns to review, as in the window. --target (the simulation or scenario the shot was rendered
// from, as a project's `target`): the engine knows the target and doubts a label of a knot it
// hides (LabelEngine::SetTarget).
//
// --fill-grid-between: the person works a frame's cameras from the one with the fewest knots to
// fix, and before each next one with a dozen or more to fix presses G and Enter (Fill Grid's
// preview, accepted: two actions) where the cameras before got labels from the person: the
// labels just given fix knots in the cameras still to do (a placed label, or a junction
// confirmed), as the workstation's G does.
//
// Printed per camera and in all: knot-frames (visible knots x frames), actions (per kind),
// actions per knot-frame, wrong accepted labels (hidden knot, or > 2 px from the truth: the
// knots are >= 20 px apart), labels the engine left for review, the error of the accepted
// labels (median, 99th percentile, by source), the engine's throughput, and why the person had
// to act on a visible knot (no label, or the engine's reason for review; NETLAB_FULL_CAUSES=1:
// the whole reason, and whether a missing label was in the first frame, on the border). With
// --coloring (the colouring the shot was rendered with) the engine also checks every label
// against the yarn colours. NETLAB_WRONG_CROPS=DIR writes a crop of each wrong label there;
// NETLAB_WRONG_CSV=FILE lists every wrong label (camera, frame, knot, source, px off);
// NETLAB_WRONG_HISTORY=1 names every wrong label on stderr (not only the first ten) with the
// knot's labels in that camera over the eight frames before, and in the other cameras.
//
// --detector: no engine and no script; Find Node at every visible knot's true place (the brush
// of --radius, and tracking's 3 px snap), what it answers per camera, with and without the
// checks on a junction's lone yarn. With NETLAB_STEP=1, each three-yarn junction found at the
// snap radius on stderr: its distance from the truth, from where its colour changes
// (Junction::colour_step), and that place's from the truth (-1: not told).

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/gui/document/missing_knots.h"
#include "bench/person_time.h"
#include "calibration/rig.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labeling/label_setup.h"
#include "libreconstruct/labels/label_set.h"
#include "libreconstruct/recording/experiment.h"
#include "libreconstruct/recording/sequence.h"

namespace {

using namespace netlab;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + i, v.end());
  return v[i];
}

struct Tally {
  int64_t knot_frames = 0, seeds = 0, find_node = 0, manual = 0, deletes = 0;
  int64_t find_node_missing = 0;  // of find_node: on a knot with no label (searched for)
  int64_t fill_grid = 0;          // --fill-grid-between: G and Enter, two actions a press
  int64_t engine_accepted = 0, engine_review = 0, wrong = 0, over_1px = 0;
  std::vector<double> error;
  std::map<std::string, std::vector<double>> error_by_source;
  int64_t actions() const { return seeds + find_node + manual + deletes + fill_grid; }
  // The person's time for these actions, s (bench/person_time.h).
  double seconds() const {
    using P = bench::PersonTime;
    return seeds * P::Seed() + (find_node - find_node_missing) * P::FindNodeOnReview() +
           find_node_missing * P::FindNodeOnMissing() + manual * P::PlaceByHand() +
           deletes * P::DeleteReview() + fill_grid / 2 * P::FillGrid();
  }
};

const char* SourceName(recon::LabelSource s) {
  switch (s) {
    case recon::LabelSource::kManual: return "manual";
    case recon::LabelSource::kFindNode: return "Find Node";
    case recon::LabelSource::kFindPath: return "Find Path";
    case recon::LabelSource::kFillGrid: return "Fill Grid";
    case recon::LabelSource::kTracked: return "tracked";
    case recon::LabelSource::kColour: return "colour";
    case recon::LabelSource::kImported: return "seed";
    case recon::LabelSource::kProjected: return "projected";
    default: return "other";
  }
}

void Usage() {
  std::fprintf(stderr,
               "usage: bench_label --shot DIR [--coloring FILE] [--target SIM.h5] [--frames A:B] "
               "[--cameras cam0,cam1,...] [--radius PX] [--seed N] [--knotless] [--detector]\n"
               "               [--fill-grid-between]\n"
               "--target: the simulation (or scenario) the shot was rendered from: the engine\n"
               "  doubts a label of a knot its target hides (LabelEngine::SetTarget)\n"
               "--fill-grid-between: the person works the cameras from the one with the fewest\n"
               "  knots to fix, pressing G and Enter (Fill Grid: two actions) before each next\n"
               "  one\n"
               "--knotless: the net has no knot balls (Net B): an edge knot is where its straight\n"
               "  links' colours change (LabelEngineOptions::edge_colour_step_px)\n"
               "--detector: no engine, no script; Find Node at every visible knot's true place\n"
               "  (the brush of --radius, and tracking's 3 px snap), its answers per camera\n"
               "DIR: `netlab render` output, e.g.\n"
               "  netlab simulate scenarios/net_a_0.5.yaml --duration 1.15 --out sim.h5\n"
               "  netlab color-net --knots 11x11 --out coloring.yaml\n"
               "  netlab render --sim sim.h5 --out shot --frames 0:199 --coloring coloring.yaml\n");
}

struct BenchOptions {
  std::string shot, coloring_path, target_path;
  int first = -1, last = -1;       // frame numbers; -1: the truth's
  double radius = 6.0;             // Find Node's brush, px
  uint64_t seed = 1;               // of the clicks' error
  std::vector<std::string> only;   // cameras; empty: all
  bool detector_only = false;      // --detector: the knot detector alone at every true knot
  bool knotless = false;           // --knotless
  bool fill_grid_between = false;  // --fill-grid-between
};

// The command line; false on a usage error.
bool ParseArgs(int argc, char** argv, BenchOptions* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--shot" && more) {
      o->shot = argv[++i];
    } else if (a == "--coloring" && more) {
      o->coloring_path = argv[++i];
    } else if (a == "--target" && more) {
      o->target_path = argv[++i];
    } else if (a == "--frames" && more) {
      if (std::sscanf(argv[++i], "%d:%d", &o->first, &o->last) != 2) return false;
    } else if (a == "--radius" && more) {
      o->radius = std::atof(argv[++i]);
    } else if (a == "--seed" && more) {
      o->seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--detector") {
      o->detector_only = true;
    } else if (a == "--knotless") {
      o->knotless = true;
    } else if (a == "--fill-grid-between") {
      o->fill_grid_between = true;
    } else if (a == "--cameras" && more) {
      std::stringstream ss(argv[++i]);
      for (std::string name; std::getline(ss, name, ',');) o->only.push_back(name);
    } else {
      return false;
    }
  }
  return !o->shot.empty();
}

// The frames and cameras benchmarked, and where each is in the truth and the experiment.
struct Shot {
  recon::LabelSet truth;
  int rows = 0, cols = 0, knots = 0;
  std::vector<int> frames, truth_row;  // per frame row: its frame number, its row in the truth
  std::vector<std::string> cameras;
  std::vector<int> truth_camera, sequence_camera;  // per camera: its index in each

  int n_cam() const { return static_cast<int>(cameras.size()); }
  int n_t() const { return static_cast<int>(frames.size()); }
  const recon::Label& Truth(int c, int t, int k) const {
    return truth.at(truth_camera[c], truth_row[t], k);
  }
};

// The truth's frames within --frames and its cameras among --cameras (each in the experiment).
Shot SelectShot(recon::LabelSet truth, const recon::SynchronizedSequence& sequence,
                BenchOptions* o) {
  Shot shot;
  shot.truth = std::move(truth);
  const recon::LabelSet& tr = shot.truth;
  shot.rows = tr.rows, shot.cols = tr.cols, shot.knots = tr.knots();
  if (o->first < 0) o->first = tr.frame_index.front(), o->last = tr.frame_index.back();
  for (int t = 0; t < tr.frames(); ++t)
    if (tr.frame_index[t] >= o->first && tr.frame_index[t] <= o->last) {
      shot.frames.push_back(tr.frame_index[t]);
      shot.truth_row.push_back(t);
    }
  for (size_t c = 0; c < tr.cameras.size(); ++c) {
    const auto& only = o->only;
    if (!only.empty() && std::find(only.begin(), only.end(), tr.cameras[c]) == only.end()) continue;
    shot.cameras.push_back(tr.cameras[c]);
    shot.truth_camera.push_back(static_cast<int>(c));
    int s = -1;
    for (size_t j = 0; j < sequence.experiment().cameras.size(); ++j)
      if (sequence.experiment().cameras[j].name == tr.cameras[c]) s = static_cast<int>(j);
    if (s < 0) throw std::runtime_error("no camera " + tr.cameras[c] + " in the experiment");
    shot.sequence_camera.push_back(s);
  }
  if (shot.frames.empty() || shot.cameras.empty()) throw std::runtime_error("no frames or cameras");
  return shot;
}

// The person's first actions: the four corners of the first frame, in every camera that sees
// them (counted as seeds).
recon::LabelSet SeedCorners(const Shot& shot, std::vector<Tally>* tally) {
  const int rows = shot.rows, cols = shot.cols;
  recon::LabelSet initial = recon::LabelSet::Empty(rows, cols, shot.cameras, shot.frames);
  for (int c = 0; c < shot.n_cam(); ++c)
    for (int k : {0, cols - 1, (rows - 1) * cols, shot.knots - 1}) {
      const recon::Label& l = shot.Truth(c, 0, k);
      if (!l.present()) continue;
      recon::Label s = l;
      s.source = recon::LabelSource::kImported;
      s.state = recon::LabelState::kAccepted;
      initial.at(c, 0, k) = s;
      ++(*tally)[c].seeds;
    }
  return initial;
}

// The person after the engine's pass over a frame (see the top of this file).
struct ScriptedUser {
  const Shot& shot;
  recon::LabelEngine& engine;
  recon::LabelStore& store;
  double radius;
  std::vector<Tally>& tally;
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> click{-0.5, 0.5};
  // Find Node results kept for review, by the check that doubted them: (count, > 1 px off).
  std::map<std::string, std::pair<int, int>> doubts{};
  // Why the person had to act on a visible knot: no label, or the engine's reason for review
  // (its words up to the first number or bracket), with how many of those labels were > 1 px off.
  std::map<std::string, std::pair<int, int>> causes{};
  // NETLAB_ACTIONS_CSV=FILE: one row per visible knot the person acted on (for analysis).
  std::FILE* actions_csv = nullptr;
  bool fill_grid_between = false;  // --fill-grid-between
  // The knots the person labeled in the frame row at hand, with the cameras (FixKnot).
  std::map<int, std::vector<int>> touched{};
  // Labels the check after the person's labels turned to review; of them > 1 px off or hidden.
  int recheck_flags = 0, recheck_flags_off = 0;
  static constexpr int kWorthAFillGrid = 12;  // knots to fix in a camera worth G and Enter

  // Every knot of frame row t in every camera: the engine's labels counted, and corrected.
  void PlayFrame(int t) {
    std::vector<int> order(shot.n_cam());
    std::iota(order.begin(), order.end(), 0);
    if (fill_grid_between)
      std::stable_sort(order.begin(), order.end(),
                       [&](int a, int b) { return ToFix(a, t) < ToFix(b, t); });
    bool placed = false;  // the person labeled a knot since the last G
    for (const int c : order) {
      if (fill_grid_between && placed && ToFix(c, t) >= kWorthAFillGrid) {
        tally[c].fill_grid += 2;  // G, Enter
        engine.CrossCheck(t);
        placed = false;
      }
      const int64_t brushed = tally[c].find_node;
      std::vector<recon::LabelEdit> edits;
      for (int k = 0; k < shot.knots; ++k) PlayKnot(c, t, k, &edits);
      // A click or a Find Node (its result a label too, where it found one).
      for (const recon::LabelEdit& e : edits) placed = placed || e.label.present();
      placed = placed || tally[c].find_node > brushed;
      if (!edits.empty()) store.Apply("scripted user", edits);
    }
    CheckAfterPerson(t);
  }

  // The engine checks each knot the person labeled in frame row t against its other cameras'
  // labels (LabelEngine::CheckAgainstPerson); what it turns to review the person fixes too, and
  // so on while it finds more.
  void CheckAfterPerson(int t) {
    for (int round = 0; round < 4 && !touched.empty(); ++round) {
      std::map<int, std::vector<int>> asked;
      asked.swap(touched);
      std::vector<std::pair<int, int>> flagged;  // (camera, knot)
      for (const auto& [k, cams] : asked) {
        std::vector<recon::Label> before(shot.n_cam());
        for (int c = 0; c < shot.n_cam(); ++c) before[c] = store.at(c, t, k);
        if (engine.CheckAgainstPerson(t, k, cams) == 0) continue;
        for (int c = 0; c < shot.n_cam(); ++c)
          if (before[c].accepted() && !store.at(c, t, k).accepted()) flagged.push_back({c, k});
      }
      for (int c = 0; c < shot.n_cam(); ++c) {
        std::vector<recon::LabelEdit> edits;
        for (const auto& [fc, k] : flagged) {
          if (fc != c) continue;
          ++recheck_flags;
          const recon::Label& l = store.at(c, t, k);
          recheck_flags_off +=
              (l.px - shot.Truth(c, t, k).px).norm() > 1.0 || !shot.Truth(c, t, k).present();
          if (!shot.Truth(c, t, k).present()) {
            ++tally[c].deletes;
            edits.push_back({c, t, k, recon::Label{}});
            continue;
          }
          FixKnot(c, t, k, &edits);
        }
        if (!edits.empty()) store.Apply("scripted user", edits);
      }
    }
    touched.clear();
  }

  // The visible knots of (c, t) without an accepted label, and hidden ones under review: what
  // the person has to fix there (the workstation shows each camera's count).
  int ToFix(int c, int t) const {
    int n = 0;
    for (int k = 0; k < shot.knots; ++k) {
      const recon::Label& l = store.at(c, t, k);
      n += shot.Truth(c, t, k).present() ? !l.accepted() : l.present() && !l.accepted();
    }
    return n;
  }

  // Why the person acts on visible knot k of camera c, frame row t (for `causes`).
  std::string Cause(int c, int t, int k) const {
    const bool full = std::getenv("NETLAB_FULL_CAUSES") != nullptr;
    if (store.at(c, t, k).present()) {
      const auto why = engine.reasons().find({c, t, k});
      const std::string cause = why == engine.reasons().end() ? "review, no reason" : why->second;
      return full ? cause : cause.substr(0, cause.find_first_of("(0123456789"));
    }
    if (!full) return "no label";
    const int r = k / shot.cols, col = k % shot.cols;
    const bool border = r == 0 || col == 0 || r == shot.rows - 1 || col == shot.cols - 1;
    return std::string("no label") + (t == 0 ? " (first frame" : " (later frame") +
           (border ? ", border)" : ", inner)") +
           (t > 0 && store.at(c, t - 1, k).accepted() ? " accepted before" : "");
  }

  // A hidden knot's label under review deleted; a visible knot without an accepted label given
  // one by Find Node at its true position, else by a click.
  void PlayKnot(int c, int t, int k, std::vector<recon::LabelEdit>* edits) {
    Tally& y = tally[c];
    const recon::Label& l = store.at(c, t, k);
    const recon::Label& truth_l = shot.Truth(c, t, k);
    if (l.present())
      (l.state == recon::LabelState::kAccepted ? y.engine_accepted : y.engine_review)++;
    if (!truth_l.present()) {
      if (l.present() && l.state == recon::LabelState::kNeedsReview) {
        ++y.deletes;
        edits->push_back({c, t, k, recon::Label{}});
      }
      return;
    }
    ++y.knot_frames;
    if (l.accepted()) return;
    FixKnot(c, t, k, edits);
  }

  // Visible knot k of (c, t) without an accepted label: Find Node at its true position, else a
  // click. The person's label is noted in `touched` for the check after the frame.
  void FixKnot(int c, int t, int k, std::vector<recon::LabelEdit>* edits) {
    Tally& y = tally[c];
    const recon::Label& l = store.at(c, t, k);
    const recon::Label& truth_l = shot.Truth(c, t, k);
    touched[k].push_back(c);
    ++y.find_node;
    y.find_node_missing += !l.present();
    auto& [n, n_off] = causes[Cause(c, t, k)];
    ++n, n_off += l.present() && (l.px - truth_l.px).norm() > 1.0;
    std::string before = engine.reasons().count({c, t, k}) ? engine.reasons().at({c, t, k}) : "";
    const recon::FindNodeResult r = engine.FindNodeAt(c, t, k, truth_l.px, radius);
    if (actions_csv) {
      std::replace(before.begin(), before.end(), ',', ';');
      std::fprintf(
          actions_csv, "%s,%d,%d,%d,%d,%d,%.3f,%d,%.3f,%d,%s\n", shot.cameras[c].c_str(),
          shot.frames[t], k, k / shot.cols, k % shot.cols, l.present() ? 1 : 0,
          l.present() ? (l.px - truth_l.px).norm() : -1.0, static_cast<int>(r.status),
          r.status == recon::FindNodeStatus::kFound ? (r.knot.px - truth_l.px).norm() : -1.0,
          store.at(c, t, k).accepted() ? 1 : 0, before.c_str());
    }
    // Found and accepted: done. Found but in doubt (its yarns or the other cameras
    // disagree), or not found: the person clicks the knot.
    if (r.status == recon::FindNodeStatus::kFound &&
        store.at(c, t, k).state == recon::LabelState::kAccepted)
      return;
    if (r.status == recon::FindNodeStatus::kFound) {
      const auto why = engine.reasons().find({c, t, k});
      const std::string reason = why == engine.reasons().end() ? "" : why->second;
      const bool off = (r.knot.px - truth_l.px).norm() > 1.0;
      auto& [count, count_off] =
          doubts[reason.find("cameras") != std::string::npos ? "the other cameras" : "its yarns"];
      ++count, count_off += off;
    }
    ++y.manual;
    recon::Label m;
    m.px = truth_l.px + Eigen::Vector2d(click(rng), click(rng));
    m.source = recon::LabelSource::kManual;
    m.confidence = 1.0f;
    m.state = recon::LabelState::kAccepted;
    edits->push_back({c, t, k, m});
  }
};

// A 61 x 61 px crop of `img` around `truth` (green) with `label` (red), 8 times enlarged, to
// `path`.
void SaveCrop(const cv::Mat& img, const Eigen::Vector2d& truth, const Eigen::Vector2d& label,
              const std::string& path) {
  const cv::Rect box =
      cv::Rect(static_cast<int>(truth.x()) - 30, static_cast<int>(truth.y()) - 30, 61, 61) &
      cv::Rect(0, 0, img.cols, img.rows);
  cv::Mat crop;
  cv::resize(img(box), crop, cv::Size(), 8, 8, cv::INTER_NEAREST);
  const auto mark = [&](const Eigen::Vector2d& q, const cv::Scalar& colour) {
    cv::circle(crop,
               cv::Point(static_cast<int>((q.x() - box.x + 0.5) * 8),
                         static_cast<int>((q.y() - box.y + 0.5) * 8)),
               6, colour, 2);
  };
  mark(truth, cv::Scalar(0, 255, 0));
  if (label.allFinite()) mark(label, cv::Scalar(0, 0, 255));
  cv::imwrite(path, crop);
}

// The errors of the accepted labels at the end (the first ten wrong ones named on stderr).
// `image(c, t)`: the frame, for the diagnosis of the first wrong labels (what the detector finds
// at the true place: a junction placed off is the detector's, another junction taken is the
// search's).
void TallyErrors(const Shot& shot, const recon::LabelStore& store, std::vector<Tally>* tally,
                 const std::function<cv::Mat(int, int)>& image) {
  // NETLAB_WRONG_CSV=FILE: every wrong accepted label, a row each (camera, frame, knot, row,
  // col, source, px off; -1: the knot is hidden).
  std::FILE* wrong_csv = nullptr;
  if (const char* path = std::getenv("NETLAB_WRONG_CSV")) wrong_csv = std::fopen(path, "w");
  for (int c = 0; c < shot.n_cam(); ++c)
    for (int t = 0; t < shot.n_t(); ++t)
      for (int k = 0; k < shot.knots; ++k) {
        const recon::Label& l = store.at(c, t, k);
        if (!l.present() || l.state != recon::LabelState::kAccepted) continue;
        const recon::Label& truth_l = shot.Truth(c, t, k);
        const double e = truth_l.present() ? (l.px - truth_l.px).norm() : -1.0;
        Tally& y = (*tally)[c];
        if (!truth_l.present() || e > 2.0) {
          if (wrong_csv)
            std::fprintf(wrong_csv, "%s,%d,%d,%d,%d,%s,%.3f\n", shot.cameras[c].c_str(),
                         shot.frames[t], k, k / shot.cols, k % shot.cols, SourceName(l.source), e);
          const int named = std::getenv("NETLAB_WRONG_HISTORY") ? 1000 : 10;
          if (++y.wrong <= named)
            std::fprintf(stderr, "wrong: %s frame %d knot %d (%d,%d) %s: %s\n",
                         shot.cameras[c].c_str(), shot.frames[t], k, k / shot.cols, k % shot.cols,
                         SourceName(l.source),
                         e < 0 ? "the knot is hidden" : (std::to_string(e) + " px off").c_str());
          if (e > 0 && y.wrong <= named) {
            const recon::FindNodeResult r = recon::FindNode(image(c, t), truth_l.px, 6.0);
            const Eigen::Vector2d off = l.px - truth_l.px;
            std::fprintf(stderr, "  label - truth (%.2f, %.2f); Find Node at the truth: %s",
                         off.x(), off.y(),
                         r.status == recon::FindNodeStatus::kFound  ? "found"
                         : r.status == recon::FindNodeStatus::kNone ? "none"
                                                                    : "several");
            if (r.status == recon::FindNodeStatus::kFound)
              std::fprintf(stderr,
                           " %.2f px from the truth, %.2f px from the label, %d branches, "
                           "fit rms %.2f px, confidence %.2f",
                           (r.knot.px - truth_l.px).norm(), (r.knot.px - l.px).norm(),
                           r.knot.branches, r.knot.fit_rms_px, r.knot.confidence);
            // And with rings half as far out (6 px): a link that bends within the default rings
            // (Net B's far pair: ~25 px links) moves the junction the detector finds.
            recon::KnotDetectorOptions near;
            near.ring_radius_px = 6.0;
            near.fit_from_px = 3.0;
            const recon::FindNodeResult r2 = recon::FindNode(image(c, t), truth_l.px, 6.0, near);
            if (r2.status == recon::FindNodeStatus::kFound)
              std::fprintf(stderr, " | near rings: %.2f px from the truth (%.2f, %.2f)",
                           (r2.knot.px - truth_l.px).norm(), r2.knot.px.x() - truth_l.px.x(),
                           r2.knot.px.y() - truth_l.px.y());
            std::fprintf(stderr, "\n");
          }
          if (y.wrong <= named) {
            // NETLAB_WRONG_HISTORY: the knot's labels in this camera over the frames before,
            // each as source, state (a: accepted, r: review) and px off the truth.
            if (std::getenv("NETLAB_WRONG_HISTORY")) {
              std::fprintf(stderr, "  before:");
              for (int s = std::max(0, t - 8); s <= t; ++s) {
                const recon::Label& h = store.at(c, s, k);
                const recon::Label& ht = shot.Truth(c, s, k);
                if (!h.present()) {
                  std::fprintf(stderr, " [%d -]", shot.frames[s]);
                  continue;
                }
                std::fprintf(stderr, " [%d %s %c %.2f]", shot.frames[s], SourceName(h.source),
                             h.state == recon::LabelState::kAccepted ? 'a' : 'r',
                             ht.present() ? (h.px - ht.px).norm() : -1.0);
              }
              std::fprintf(stderr, "\n  other cameras:");
              for (int o = 0; o < shot.n_cam(); ++o) {
                const recon::Label& h = store.at(o, t, k);
                const recon::Label& ht = shot.Truth(o, t, k);
                if (o == c) continue;
                if (!h.present()) {
                  std::fprintf(stderr, " [%s -%s]", shot.cameras[o].c_str(),
                               ht.present() ? "" : " hidden");
                  continue;
                }
                std::fprintf(stderr, " [%s %s %c %.2f]", shot.cameras[o].c_str(),
                             SourceName(h.source),
                             h.state == recon::LabelState::kAccepted ? 'a' : 'r',
                             ht.present() ? (h.px - ht.px).norm() : -1.0);
              }
              std::fprintf(stderr, "\n");
            }
          }
          if (e > 0 && y.wrong <= named) {
            if (const char* dir = std::getenv("NETLAB_WRONG_CROPS"))  // a look at the place
              SaveCrop(image(c, t), truth_l.px, l.px,
                       std::string(dir) + "/wrong_" + shot.cameras[c] + "_" +
                           std::to_string(shot.frames[t]) + "_" + std::to_string(k) + ".png");
          }
          if (e < 0) continue;
        }
        if (e > 1.0) ++y.over_1px;
        if (e > 1.0 && e <= 2.0 && std::getenv("NETLAB_SHOW_OVER_1PX")) {
          const recon::FindNodeResult r = recon::FindNode(image(c, t), truth_l.px, 6.0);
          std::fprintf(
              stderr, "over 1 px: %s frame %d knot %d %s: %.2f px (%.2f, %.2f)%s\n",
              shot.cameras[c].c_str(), shot.frames[t], k, SourceName(l.source), e,
              l.px.x() - truth_l.px.x(), l.px.y() - truth_l.px.y(),
              r.status == recon::FindNodeStatus::kFound
                  ? (", Find Node at the truth " + std::to_string((r.knot.px - truth_l.px).norm()) +
                     " px off, " + std::to_string(r.knot.branches) + " branches")
                        .c_str()
                  : ", Find Node at the truth: not found");
        }
        y.error.push_back(e);
        y.error_by_source[SourceName(l.source)].push_back(e);
      }
  if (wrong_csv) std::fclose(wrong_csv);
}

// One row of the table (with_g: the G presses of --fill-grid-between too).
void PrintRow(const std::string& name, const Tally& y, bool with_g) {
  const std::string g = with_g ? " / " + std::to_string(y.fill_grid) : "";
  std::printf(
      "| %s | %lld | %lld (%lld / %lld / %lld / %lld%s) | %.4f | %lld | %lld | %lld / "
      "%lld | %.3f | %.3f |\n",
      name.c_str(), (long long)y.knot_frames, (long long)y.actions(), (long long)y.seeds,
      (long long)y.find_node, (long long)y.manual, (long long)y.deletes, g.c_str(),
      y.knot_frames ? static_cast<double>(y.actions()) / y.knot_frames : 0.0, (long long)y.wrong,
      (long long)y.over_1px, (long long)y.engine_accepted, (long long)y.engine_review,
      Quantile(y.error, 0.5), Quantile(y.error, 0.99));
}

// The table per camera and in all; then the errors by source. Returns the sum over cameras.
Tally PrintTables(const BenchOptions& o, const Shot& shot, const std::vector<Tally>& tally) {
  std::printf("Scripted user on %s, frames %d:%d (%d), %dx%d knots, Find Node radius %.0f px\n\n",
              o.shot.c_str(), shot.frames.front(), shot.frames.back(), shot.n_t(), shot.rows,
              shot.cols, o.radius);
  // How long a link is in each image (the detector's rings are 9 to 18 px out).
  std::printf("true link length in the image, px (5th percentile / median):");
  for (int c = 0; c < shot.n_cam(); ++c) {
    std::vector<double> px;
    for (int t = 0; t < shot.n_t(); ++t)
      for (int k = 0; k < shot.knots; ++k) {
        const recon::Label& a = shot.Truth(c, t, k);
        for (const int n : {k % shot.cols + 1 < shot.cols ? k + 1 : -1,
                            k + shot.cols < shot.knots ? k + shot.cols : -1})
          if (n >= 0 && a.present() && shot.Truth(c, t, n).present())
            px.push_back((shot.Truth(c, t, n).px - a.px).norm());
      }
    std::printf(" %s %.1f / %.1f", shot.cameras[c].c_str(), Quantile(px, 0.05), Quantile(px, 0.5));
  }
  std::printf("\n\n");
  std::printf(
      "| camera | knot-frames | actions (seed / Find Node / manual / delete%s) | actions "
      "per knot-frame | wrong accepted | > 1 px | engine: accepted / review | "
      "median px | p99 px |\n|---|---|---|---|---|---|---|---|---|\n",
      o.fill_grid_between ? " / G, Enter" : "");
  Tally all;
  for (int c = 0; c < shot.n_cam(); ++c) {
    PrintRow(shot.cameras[c], tally[c], o.fill_grid_between);
    const Tally& y = tally[c];
    all.knot_frames += y.knot_frames, all.seeds += y.seeds, all.find_node += y.find_node;
    all.manual += y.manual, all.deletes += y.deletes, all.wrong += y.wrong;
    all.find_node_missing += y.find_node_missing;
    all.fill_grid += y.fill_grid;
    all.over_1px += y.over_1px;
    all.engine_accepted += y.engine_accepted, all.engine_review += y.engine_review;
    all.error.insert(all.error.end(), y.error.begin(), y.error.end());
    for (const auto& [s, v] : y.error_by_source)
      all.error_by_source[s].insert(all.error_by_source[s].end(), v.begin(), v.end());
  }
  PrintRow("all", all, o.fill_grid_between);
  // The person's time (bench/person_time.h, docs/gui.md), and a whole 6 s shot at this rate: the
  // same visible knot-views per frame over kShotFrames frames.
  if (all.knot_frames > 0) {
    const double per_kf = all.seconds() / all.knot_frames;
    const double shot_kf = static_cast<double>(all.knot_frames) / shot.n_t() * bench::kShotFrames;
    std::printf(
        "\nthe person's time: %.1f min (%.4f s per knot-frame; Find Node on %lld review "
        "labels and %lld missing knots, %lld by hand, %lld deletes, %lld seeds); a 6 s "
        "shot at this rate (%.0f knot-frames): %.1f h\n",
        all.seconds() / 60.0, per_kf, (long long)(all.find_node - all.find_node_missing),
        (long long)all.find_node_missing, (long long)all.manual, (long long)all.deletes,
        (long long)all.seeds, shot_kf, per_kf * shot_kf / 3600.0);
  }
  std::printf("\n| source | labels | median px | p99 px | max px |\n|---|---|---|---|---|\n");
  for (const auto& [s, v] : all.error_by_source)
    std::printf("| %s | %zu | %.3f | %.3f | %.3f |\n", s.c_str(), v.size(), Quantile(v, 0.5),
                Quantile(v, 0.99), Quantile(v, 1.0));
  return all;
}

// --detector: what Find Node answers at every visible knot's true place, per camera, with the
// person's brush (--radius) and with tracking's snap (3 px, the knot's degree required):
// found (and how far off), found with another number of yarns, several, none (and whether the
// rings alone found it: then the yarn fit refused it).
void BenchDetector(const Shot& shot, const BenchOptions& o,
                   const std::function<cv::Mat(int, int)>& image) {
  std::printf("Find Node at the true knots of %s, frames %d:%d\n\n", o.shot.c_str(),
              shot.frames.front(), shot.frames.back());
  std::printf(
      "| camera | brush | knots | found | other degree | several | none (rings found) | "
      "median px | p99 px | > 1 px | > 2 px | without the lone yarn checks: found, "
      "> 1 px, > 2 px |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  recon::KnotDetectorOptions rings_only, unchecked, asked;
  asked.colour_step = std::getenv("NETLAB_STEP") != nullptr;  // where edge colours change
  rings_only.fit_yarns = false;
  unchecked.lone_bend_px = 0.0;
  unchecked.lone_agree_px = 0.0;
  for (int c = 0; c < shot.n_cam(); ++c)
    for (const double radius : {o.radius, 3.0}) {
      int64_t n = 0, found = 0, degree = 0, several = 0, none = 0, rings = 0, over1 = 0, over2 = 0;
      int64_t u_found = 0, u_over1 = 0, u_over2 = 0;
      std::vector<double> err;
      for (int t = 0; t < shot.n_t(); ++t) {
        const cv::Mat img = image(c, t);
        for (int k = 0; k < shot.knots; ++k) {
          const recon::Label& truth_l = shot.Truth(c, t, k);
          if (!truth_l.present()) continue;
          ++n;
          const int r = k / shot.cols, col = k % shot.cols;
          const int want = (r > 0) + (r + 1 < shot.rows) + (col > 0) + (col + 1 < shot.cols);
          const recon::FindNodeResult f = recon::FindNode(img, truth_l.px, radius, asked);
          const recon::FindNodeResult u = recon::FindNode(img, truth_l.px, radius, unchecked);
          if (u.status == recon::FindNodeStatus::kFound) {
            const double e = (u.knot.px - truth_l.px).norm();
            ++u_found, u_over1 += e > 1.0, u_over2 += e > 2.0;
          }
          const char* dir = std::getenv("NETLAB_WRONG_CROPS");
          const std::string crop = dir ? std::string(dir) + "/" + shot.cameras[c] + "_" +
                                             std::to_string(shot.frames[t]) + "_" +
                                             std::to_string(k)
                                       : "";
          if (f.status == recon::FindNodeStatus::kSeveral) {
            ++several;
          } else if (f.status == recon::FindNodeStatus::kNone) {
            ++none;
            if (dir && radius == 3.0)
              SaveCrop(img, truth_l.px, Eigen::Vector2d::Constant(NAN), crop + "_none.png");
            rings += recon::FindNode(img, truth_l.px, radius, rings_only).status ==
                     recon::FindNodeStatus::kFound;
          } else {
            ++found;
            degree += !f.knot.solid && f.knot.branches != want;
            if (dir && radius == 3.0 && !f.knot.solid && f.knot.branches != want)
              SaveCrop(img, truth_l.px, f.knot.px,
                       crop + "_has" + std::to_string(f.knot.branches) + ".png");
            const double e = (f.knot.px - truth_l.px).norm();
            err.push_back(e);
            if (radius == 3.0 && std::getenv("NETLAB_STEP") && f.knot.branches == 3)
              std::fprintf(
                  stderr, "step: %s frame %d knot %d junction %.2f apart %.2f step %.2f\n",
                  shot.cameras[c].c_str(), shot.frames[t], k, e,
                  f.knot.colour_step.allFinite() ? (f.knot.colour_step - f.knot.px).norm() : -1.0,
                  f.knot.colour_step.allFinite() ? (f.knot.colour_step - truth_l.px).norm() : -1.0);
            over1 += e > 1.0, over2 += e > 2.0;
            if (e > 2.0 && radius == 3.0) {
              std::fprintf(stderr,
                           "over 2 px: %s frame %d knot %d at (%.2f, %.2f), found "
                           "(%.2f, %.2f)\n",
                           shot.cameras[c].c_str(), shot.frames[t], k, truth_l.px.x(),
                           truth_l.px.y(), f.knot.px.x(), f.knot.px.y());
              if (dir) SaveCrop(img, truth_l.px, f.knot.px, crop + "_off.png");
            }
          }
        }
      }
      std::printf(
          "| %s | %.0f px | %lld | %lld | %lld | %lld | %lld (%lld) | %.3f | %.3f | %lld | "
          "%lld | %lld, %lld, %lld |\n",
          shot.cameras[c].c_str(), radius, (long long)n, (long long)found, (long long)degree,
          (long long)several, (long long)none, (long long)rings, Quantile(err, 0.5),
          Quantile(err, 0.99), (long long)over1, (long long)over2, (long long)u_found,
          (long long)u_over1, (long long)u_over2);
    }
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions o;
  if (!ParseArgs(argc, argv, &o)) return Usage(), 2;
  try {
    recon::SynchronizedSequence sequence(recon::LoadExperiment(o.shot + "/experiment.yaml"));
    const calib::Rig rig = calib::ReadRig(o.shot + "/rig_true.yaml");
    const Shot shot = SelectShot(recon::ReadLabels(o.shot + "/labels_true.h5"), sequence, &o);
    const int n_t = shot.n_t();
    // Camera c's frame at row t, as the window shows it.
    const auto read_frame = [&](int c, int t) {
      std::string error;
      return sequence.ReadDisplay(shot.sequence_camera[c], shot.frames[t], 0, &error);
    };
    if (o.detector_only) return BenchDetector(shot, o, read_frame), 0;

    // The person seeds the corners; the engine reads the shot's frames (timed).
    std::vector<Tally> tally(shot.n_cam());
    recon::LabelStore store(SeedCorners(shot, &tally));
    double read_s = 0.0;
    // The engine set up as netlab label sets it up, with the colour check when given a colouring.
    recon::LabelingNet net;
    net.knotless = o.knotless;
    recon::NetColoring coloring;
    if (!o.coloring_path.empty()) {
      coloring = recon::ReadColoring(o.coloring_path, &net.dyes);
      net.coloring = &coloring;
      net.bayer = sequence.experiment().cameras.front().bayer;
    }
    const recon::LabelingSetup setup = recon::SetUpLabeling(net);
    recon::LabelEngine engine(
        &store, &rig,
        [&](int c, int t) {
          const auto t0 = Clock::now();
          cv::Mat image = read_frame(c, t);
          read_s += Since(t0);
          return image;
        },
        setup.options);
    setup.ApplyColourCheck(&engine);
    if (!o.target_path.empty())
      engine.SetTarget(gui::LoadTarget(o.target_path, sequence.experiment().fps));
    // The engine frame by frame, the person after each frame.
    ScriptedUser user{shot, engine, store, o.radius, tally, std::mt19937_64(o.seed)};
    user.fill_grid_between = o.fill_grid_between;
    if (const char* path = std::getenv("NETLAB_ACTIONS_CSV")) {
      user.actions_csv = std::fopen(path, "w");
      if (!user.actions_csv) throw std::runtime_error(std::string("cannot write ") + path);
      std::fprintf(user.actions_csv,
                   "camera,frame,knot,row,col,had_label,label_px_off,"
                   "find_node,found_px_off,accepted_after,cause\n");
    }
    double engine_s = 0.0, user_s = 0.0;
    auto t0 = Clock::now();
    engine.LabelFrames(0, n_t - 1, [&](int t) {
      engine_s += Since(t0);
      t0 = Clock::now();
      user.PlayFrame(t);
      user_s += Since(t0);
      if ((t + 1) % 20 == 0 || t + 1 == n_t) {
        int64_t kf = 0, act = 0;
        for (const auto& y : tally) kf += y.knot_frames, act += y.actions();
        std::fprintf(stderr, "frame %d/%d: %.4f actions per knot-frame, engine %.1f s\n", t + 1,
                     n_t, kf ? static_cast<double>(act) / kf : 0.0, engine_s);
      }
      t0 = Clock::now();
    });
    TallyErrors(shot, store, &tally, read_frame);

    const Tally all = PrintTables(o, shot, tally);
    std::printf(
        "\nengine %.1f s (of which frame reading %.1f s): %.0f knot-frames/s; the "
        "script's Find Node calls %.1f s; link length %.4f m\n",
        engine_s, read_s, engine_s > 0 ? all.knot_frames / engine_s : 0.0, user_s,
        engine.link_length_m());
    std::printf("\nwhy the person acted on a visible knot (count; labels > 1 px off):\n");
    for (const auto& [cause, n] : user.causes)
      std::printf("  %6d  %5d  %s\n", n.first, n.second, cause.c_str());
    for (const auto& [check, n] : user.doubts)
      std::printf("Find Node kept for review by %s: %d (%d of them > 1 px off)\n", check.c_str(),
                  n.first, n.second);
    std::printf(
        "the check after the person's labels turned %d accepted labels to review (%d of "
        "them > 1 px off, or of a hidden knot)\n",
        user.recheck_flags, user.recheck_flags_off);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_label: %s\n", e.what());
    return 1;
  }
}
