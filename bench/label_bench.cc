// The labeling engine against a scripted user, on a rendered shot with its truth.
//
//   bench_label --shot DIR [--coloring FILE] [--frames A:B] [--cameras cam0,cam1] [--radius PX]
//               [--seed N]
//
// DIR is the output of `netlab render` (experiment.yaml, rig_true.yaml, labels_true.h5). The
// script plays the person: it seeds the four corners of the first frame in every camera that
// sees them (one action each), runs the engine (Find Path in the first frame; then tracking, the
// epipolar check and Fill Grid frame by frame), and after each frame, wherever a visible knot is
// unlabeled or flagged for review, performs one Find Node at the true position (brush radius
// --radius); when Find Node says none or several, it clicks the knot by hand (a second action,
// the true position off by up to 0.5 px). A label under review on a knot the truth says is
// hidden is deleted (one action). Accepted labels are never checked by the script: a wrong one
// stays wrong and is counted.
//
// Printed per camera and in all: knot-frames (visible knots x frames), actions (per kind),
// actions per knot-frame, wrong accepted labels (hidden knot, or > 2 px from the truth: the
// knots are >= 20 px apart), labels the engine left for review, the error of the accepted
// labels (median, 99th percentile, by source), and the engine's throughput. With --coloring (the
// colouring the shot was rendered with) the engine also checks every label against the yarn
// colours.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labeling/label_engine.h"
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
  int64_t engine_accepted = 0, engine_review = 0, wrong = 0, over_1px = 0;
  std::vector<double> error;
  std::map<std::string, std::vector<double>> error_by_source;
  int64_t actions() const { return seeds + find_node + manual + deletes; }
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
    default: return "other";
  }
}

void Usage() {
  std::fprintf(stderr,
               "usage: bench_label --shot DIR [--coloring FILE] [--frames A:B] "
               "[--cameras cam0,cam1,...] [--radius PX] [--seed N]\n"
               "DIR: `netlab render` output, e.g.\n"
               "  netlab simulate scenarios/net_a_0.5.yaml --duration 1.15 --out sim.h5\n"
               "  netlab color-net --knots 11x11 --out coloring.yaml\n"
               "  netlab render --sim sim.h5 --out shot --frames 0:199 --coloring coloring.yaml\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string shot, coloring_path;
  int first = -1, last = -1;
  double radius = 6.0;
  uint64_t seed = 1;
  std::vector<std::string> only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--shot" && more) {
      shot = argv[++i];
    } else if (a == "--coloring" && more) {
      coloring_path = argv[++i];
    } else if (a == "--frames" && more) {
      if (std::sscanf(argv[++i], "%d:%d", &first, &last) != 2) return Usage(), 2;
    } else if (a == "--radius" && more) {
      radius = std::atof(argv[++i]);
    } else if (a == "--seed" && more) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--cameras" && more) {
      std::stringstream ss(argv[++i]);
      for (std::string name; std::getline(ss, name, ',');) only.push_back(name);
    } else {
      Usage();
      return 2;
    }
  }
  if (shot.empty()) return Usage(), 2;
  try {
    recon::SynchronizedSequence sequence(recon::LoadExperiment(shot + "/experiment.yaml"));
    const calib::Rig rig = calib::ReadRig(shot + "/rig_true.yaml");
    const recon::LabelSet truth = recon::ReadLabels(shot + "/labels_true.h5");
    const int rows = truth.rows, cols = truth.cols, knots = truth.knots();
    if (first < 0) first = truth.frame_index.front(), last = truth.frame_index.back();
    std::vector<int> frames, truth_row;
    for (int t = 0; t < truth.frames(); ++t)
      if (truth.frame_index[t] >= first && truth.frame_index[t] <= last) {
        frames.push_back(truth.frame_index[t]);
        truth_row.push_back(t);
      }
    std::vector<std::string> cameras;
    std::vector<int> truth_camera, sequence_camera;
    for (size_t c = 0; c < truth.cameras.size(); ++c) {
      if (!only.empty() && std::find(only.begin(), only.end(), truth.cameras[c]) == only.end())
        continue;
      cameras.push_back(truth.cameras[c]);
      truth_camera.push_back(static_cast<int>(c));
      int s = -1;
      for (size_t j = 0; j < sequence.experiment().cameras.size(); ++j)
        if (sequence.experiment().cameras[j].name == truth.cameras[c]) s = static_cast<int>(j);
      if (s < 0) throw std::runtime_error("no camera " + truth.cameras[c] + " in the experiment");
      sequence_camera.push_back(s);
    }
    if (frames.empty() || cameras.empty()) throw std::runtime_error("no frames or cameras");
    const int n_cam = static_cast<int>(cameras.size()), n_t = static_cast<int>(frames.size());
    auto truth_at = [&](int c, int t, int k) -> const recon::Label& {
      return truth.at(truth_camera[c], truth_row[t], k);
    };

    std::vector<Tally> tally(n_cam);
    recon::LabelSet initial = recon::LabelSet::Empty(rows, cols, cameras, frames);
    for (int c = 0; c < n_cam; ++c)
      for (int k : {0, cols - 1, (rows - 1) * cols, knots - 1}) {
        const recon::Label& l = truth_at(c, 0, k);
        if (!l.present()) continue;
        recon::Label s = l;
        s.source = recon::LabelSource::kImported;
        s.state = recon::LabelState::kAccepted;
        initial.at(c, 0, k) = s;
        ++tally[c].seeds;
      }
    recon::LabelStore store(std::move(initial));
    double read_s = 0.0;
    recon::LabelEngine engine(&store, &rig, [&](int c, int t) {
      const auto t0 = Clock::now();
      std::string error;
      cv::Mat image = sequence.ReadDisplay(sequence_camera[c], frames[t], 0, &error);
      read_s += Since(t0);
      return image;
    });
    if (!coloring_path.empty()) {
      std::vector<std::array<int, 3>> dyes;
      const recon::NetColoring coloring = recon::ReadColoring(coloring_path, &dyes);
      recon::Lighting lighting;
      lighting.exposure = 0.85;  // netlab render's illumination
      engine.SetCodebook(recon::CodebookFromColoring(coloring, dyes, lighting));
    }
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> click(-0.5, 0.5);
    double engine_s = 0.0, user_s = 0.0;
    // Find Node results kept for review, by the check that doubted them: (count, > 1 px off).
    std::map<std::string, std::pair<int, int>> doubts;
    for (int t = 0; t < n_t; ++t) {
      auto t0 = Clock::now();
      if (t == 0) {
        engine.LabelFirstFrame(0);
      } else {
        engine.Track(t - 1, t);
      }
      engine.CrossCheck(t);
      engine_s += Since(t0);
      t0 = Clock::now();
      for (int c = 0; c < n_cam; ++c) {
        Tally& y = tally[c];
        std::vector<recon::LabelEdit> edits;
        for (int k = 0; k < knots; ++k) {
          const recon::Label& l = store.at(c, t, k);
          const recon::Label& truth_l = truth_at(c, t, k);
          if (l.present()) (l.state == recon::LabelState::kAccepted ? y.engine_accepted
                                                                      : y.engine_review)++;
          if (!truth_l.present()) {
            if (l.present() && l.state == recon::LabelState::kNeedsReview) {
              ++y.deletes;
              edits.push_back({c, t, k, recon::Label{}});
            }
            continue;
          }
          ++y.knot_frames;
          if (l.present() && l.state == recon::LabelState::kAccepted) continue;
          ++y.find_node;
          const recon::FindNodeResult r = engine.FindNodeAt(c, t, k, truth_l.px, radius);
          // Found and accepted: done. Found but in doubt (its yarns or the other cameras
          // disagree), or not found: the person clicks the knot.
          if (r.status == recon::FindNodeStatus::kFound &&
              store.at(c, t, k).state == recon::LabelState::kAccepted)
            continue;
          if (r.status == recon::FindNodeStatus::kFound) {
            const auto why = engine.reasons().find({c, t, k});
            const std::string reason = why == engine.reasons().end() ? "" : why->second;
            const bool off = (r.knot.px - truth_l.px).norm() > 1.0;
            auto& [count, count_off] = doubts[reason.find("cameras") != std::string::npos
                                                  ? "the other cameras"
                                                  : "its yarns"];
            ++count, count_off += off;
          }
          ++y.manual;
          recon::Label m;
          m.px = truth_l.px + Eigen::Vector2d(click(rng), click(rng));
          m.source = recon::LabelSource::kManual;
          m.confidence = 1.0f;
          m.state = recon::LabelState::kAccepted;
          edits.push_back({c, t, k, m});
        }
        if (!edits.empty()) store.Apply("scripted user", edits);
      }
      user_s += Since(t0);
      if ((t + 1) % 20 == 0 || t + 1 == n_t) {
        int64_t kf = 0, act = 0;
        for (const auto& y : tally) kf += y.knot_frames, act += y.actions();
        std::fprintf(stderr, "frame %d/%d: %.4f actions per knot-frame, engine %.1f s\n", t + 1,
                     n_t, kf ? static_cast<double>(act) / kf : 0.0, engine_s);
      }
    }
    // Errors of the accepted labels at the end.
    for (int c = 0; c < n_cam; ++c)
      for (int t = 0; t < n_t; ++t)
        for (int k = 0; k < knots; ++k) {
          const recon::Label& l = store.at(c, t, k);
          if (!l.present() || l.state != recon::LabelState::kAccepted) continue;
          const recon::Label& truth_l = truth_at(c, t, k);
          const double e = truth_l.present() ? (l.px - truth_l.px).norm() : -1.0;
          if (!truth_l.present() || e > 2.0) {
            if (++tally[c].wrong <= 10)
              std::fprintf(stderr, "wrong: %s frame %d knot %d (%d,%d) %s: %s\n",
                           cameras[c].c_str(), frames[t], k, k / cols, k % cols,
                           SourceName(l.source),
                           e < 0 ? "the knot is hidden" : (std::to_string(e) + " px off").c_str());
            if (e < 0) continue;
          }
          if (e > 1.0) ++tally[c].over_1px;
          tally[c].error.push_back(e);
          tally[c].error_by_source[SourceName(l.source)].push_back(e);
        }

    std::printf("Scripted user on %s, frames %d:%d (%d), %dx%d knots, Find Node radius %.0f px\n\n",
                shot.c_str(), frames.front(), frames.back(), n_t, rows, cols, radius);
    std::printf("| camera | knot-frames | actions (seed / Find Node / manual / delete) | actions "
                "per knot-frame | wrong accepted | > 1 px | engine: accepted / review | "
                "median px | p99 px |\n|---|---|---|---|---|---|---|---|---|\n");
    Tally all;
    auto row = [](const std::string& name, const Tally& y) {
      std::printf("| %s | %lld | %lld (%lld / %lld / %lld / %lld) | %.4f | %lld | %lld | %lld / %lld "
                  "| %.3f | %.3f |\n",
                  name.c_str(), (long long)y.knot_frames, (long long)y.actions(),
                  (long long)y.seeds, (long long)y.find_node, (long long)y.manual,
                  (long long)y.deletes,
                  y.knot_frames ? static_cast<double>(y.actions()) / y.knot_frames : 0.0,
                  (long long)y.wrong, (long long)y.over_1px, (long long)y.engine_accepted,
                  (long long)y.engine_review, Quantile(y.error, 0.5), Quantile(y.error, 0.99));
    };
    for (int c = 0; c < n_cam; ++c) {
      row(cameras[c], tally[c]);
      const Tally& y = tally[c];
      all.knot_frames += y.knot_frames, all.seeds += y.seeds, all.find_node += y.find_node;
      all.manual += y.manual, all.deletes += y.deletes, all.wrong += y.wrong;
      all.over_1px += y.over_1px;
      all.engine_accepted += y.engine_accepted, all.engine_review += y.engine_review;
      all.error.insert(all.error.end(), y.error.begin(), y.error.end());
      for (const auto& [s, v] : y.error_by_source)
        all.error_by_source[s].insert(all.error_by_source[s].end(), v.begin(), v.end());
    }
    row("all", all);
    std::printf("\n| source | labels | median px | p99 px | max px |\n|---|---|---|---|---|\n");
    for (const auto& [s, v] : all.error_by_source)
      std::printf("| %s | %zu | %.3f | %.3f | %.3f |\n", s.c_str(), v.size(), Quantile(v, 0.5),
                  Quantile(v, 0.99), Quantile(v, 1.0));
    std::printf("\nengine %.1f s (of which frame reading %.1f s): %.0f knot-frames/s; the "
                "script's Find Node calls %.1f s; link length %.4f m\n",
                engine_s, read_s, engine_s > 0 ? all.knot_frames / engine_s : 0.0, user_s,
                engine.link_length_m());
    for (const auto& [check, n] : doubts)
      std::printf("Find Node kept for review by %s: %d (%d of them > 1 px off)\n", check.c_str(),
                  n.first, n.second);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_label: %s\n", e.what());
    return 1;
  }
}
