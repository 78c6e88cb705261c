// netlab label EXPERIMENT.yaml --rig rig.yaml --coloring coloring.yaml --seed SEEDS --out labels.h5
//              [--frames A:B] [--json]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <map>
#include <optional>

#include "app/command_line.h"
#include "app/commands.h"
#include "app/json_writer.h"
#include "calibration/rig.h"
#include "libreconstruct/experiment.h"
#include "libreconstruct/knot_detect.h"
#include "libreconstruct/knot_track.h"
#include "libreconstruct/label_store.h"
#include "libreconstruct/labels.h"
#include "libreconstruct/net_coloring.h"
#include "libreconstruct/sequence.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab label EXPERIMENT.yaml --rig rig.yaml --coloring coloring.yaml --seed SEEDS\n"
    "                    --out labels.h5 [--frames A:B] [--json]\n\n"
    "Runs the automatic part of the labeling from seed labels: in the first frame of each\n"
    "camera whose four corner knots are seeded, Find Path along the four sides, then along every\n"
    "row and every column (an inner knot is accepted when its row and its column agree); then\n"
    "tracks every label frame by frame. Labels whose checks disagree are kept for review, never\n"
    "accepted silently (docs/labeling.md).\n\n"
    "options:\n"
    "  --rig FILE          the calibrated rig (its camera names must match the experiment's)\n"
    "  --coloring FILE     coloring.yaml (netlab color-net): the net's knots\n"
    "  --seed SEEDS        labels.h5 or a DLTdv8-style xypts.csv (cameras in the experiment's\n"
    "                      order), e.g. the four corners in the first frame of each camera\n"
    "  --out FILE          labels.h5 (written via a .partial file, then renamed)\n"
    "  --frames A:B        frames A to B inclusive (default: the whole recording)\n"
    "  --quiet             no progress or summary on stderr\n"
    "  --json              print one JSON summary object on stdout as the last output: labeled,\n"
    "                      needs_review, frames, wall_s, and per camera\n\n"
    "exit status: 0 done, 1 bad input, 2 usage error.\n";

recon::Label Made(const Eigen::Vector2d& px, recon::LabelSource source, double confidence,
                  bool accepted) {
  recon::Label l;
  l.px = px;
  l.source = source;
  l.confidence = static_cast<float>(confidence);
  l.state = accepted ? recon::LabelState::kAccepted : recon::LabelState::kNeedsReview;
  return l;
}

struct CameraCounts {
  int64_t labeled = 0, needs_review = 0;
  std::string first_frame_note;
};

// The first frame of one camera from its four corners: the sides, then rows and columns.
void LabelFirstFrame(const cv::Mat& image, int camera, int t, int rows, int cols,
                     recon::LabelStore* store, CameraCounts* counts) {
  const recon::LabelSet& set = store->labels();
  const int corners[4] = {0, cols - 1, (rows - 1) * cols, rows * cols - 1};
  for (int k : corners)
    if (!set.at(camera, t, k).present()) {
      counts->first_frame_note = "not every corner is seeded in the first frame";
      return;
    }
  std::vector<recon::LabelEdit> edits;
  auto px = [&](int k) -> std::optional<Eigen::Vector2d> {
    for (const auto& e : edits)
      if (e.knot == k) return e.label.px;
    const recon::Label& l = set.at(camera, t, k);
    if (l.present()) return l.px;
    return std::nullopt;
  };
  auto path = [&](int a, int b) {
    const auto pa = px(a), pb = px(b);
    if (!pa || !pb) return recon::FindPathResult{};
    return recon::FindPath(image, cols, a, *pa, b, *pb);
  };
  // The four sides: each knot from one path (its junction count checked against the grid).
  for (const auto& [a, b] : {std::pair(corners[0], corners[1]), std::pair(corners[2], corners[3]),
                             std::pair(corners[0], corners[2]), std::pair(corners[1], corners[3])}) {
    const recon::FindPathResult r = path(a, b);
    for (size_t i = 0; i < r.knots.size(); ++i)
      if (!set.at(camera, t, r.knots[i]).present())
        edits.push_back({camera, t, r.knots[i],
                         Made(r.junctions[i].px, recon::LabelSource::kFindPath,
                              r.junctions[i].confidence, true)});
  }
  // Inner knots: along their row and along their column; both must agree.
  std::map<int, Eigen::Vector2d> by_row, by_column;
  std::map<int, double> confidence;
  for (int row = 1; row + 1 < rows; ++row) {
    const recon::FindPathResult r = path(row * cols, row * cols + cols - 1);
    for (size_t i = 0; i < r.knots.size(); ++i) {
      by_row[r.knots[i]] = r.junctions[i].px;
      confidence[r.knots[i]] = r.junctions[i].confidence;
    }
  }
  for (int col = 1; col + 1 < cols; ++col) {
    const recon::FindPathResult r = path(col, (rows - 1) * cols + col);
    for (size_t i = 0; i < r.knots.size(); ++i) {
      by_column[r.knots[i]] = r.junctions[i].px;
      confidence[r.knots[i]] = std::min(confidence.count(r.knots[i]) ? confidence[r.knots[i]] : 1.0,
                                        r.junctions[i].confidence);
    }
  }
  for (int row = 1; row + 1 < rows; ++row)
    for (int col = 1; col + 1 < cols; ++col) {
      const int k = row * cols + col;
      if (set.at(camera, t, k).present()) continue;
      const auto a = by_row.find(k), b = by_column.find(k);
      if (a == by_row.end() && b == by_column.end()) continue;
      const bool agree = a != by_row.end() && b != by_column.end() &&
                         (a->second - b->second).norm() < 0.5;
      const Eigen::Vector2d where = a != by_row.end() ? a->second : b->second;
      edits.push_back({camera, t, k, Made(where, recon::LabelSource::kFindPath, confidence[k],
                                          agree)});
    }
  store->Apply("Find Path (first frame, camera " + std::to_string(camera) + ")", edits);
}

}  // namespace

int RunLabel(const std::vector<std::string>& args) {
  try {
    const CommandLine cl(args, {"json", "quiet", "help"},
                         {"rig", "coloring", "seed", "out", "frames"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() != 1)
      throw UsageError("expected one experiment file, got " +
                       std::to_string(cl.positional().size()) + " arguments");
    const auto start = std::chrono::steady_clock::now();
    const bool quiet = cl.Flag("quiet");
    const std::string out = cl.Required("out");
    const calib::Rig rig = calib::ReadRig(cl.Required("rig"));
    const recon::NetColoring coloring = recon::ReadColoring(cl.Required("coloring"));
    const int rows = coloring.rows, cols = coloring.cols;
    recon::SynchronizedSequence sequence(recon::LoadExperiment(cl.positional()[0]));
    std::vector<std::string> cameras;
    for (const auto& c : sequence.experiment().cameras) {
      if (rig.Find(c.name) < 0)
        throw std::runtime_error(cl.Required("rig") + ": no camera '" + c.name +
                                 "' (the experiment's cameras must be in the rig)");
      cameras.push_back(c.name);
    }
    int first = sequence.first_frame(), last = sequence.last_frame();
    int a = first, b = last;
    if (cl.FrameRange("frames", &a, &b)) {
      if (a < first || b > last)
        throw UsageError("--frames " + *cl.Option("frames") + " lies outside the recording's " +
                         "frames " + std::to_string(first) + ":" + std::to_string(last));
      first = a, last = b;
    }
    std::vector<int> frame_index;
    for (int f = first; f <= last; ++f) frame_index.push_back(f);
    const recon::LabelSet seeds = recon::ReadLabelsAny(cl.Required("seed"), rows, cols, cameras);

    recon::LabelSet initial = recon::LabelSet::Empty(rows, cols, cameras, frame_index);
    int64_t seeded = 0;
    for (size_t sc = 0; sc < seeds.cameras.size(); ++sc) {
      const int c = initial.FindCamera(seeds.cameras[sc]);
      if (c < 0)
        throw std::runtime_error(cl.Required("seed") + ": camera '" + seeds.cameras[sc] +
                                 "' is not in the experiment");
      for (int st = 0; st < seeds.frames(); ++st) {
        const int t = seeds.frame_index[st] - first;
        if (t < 0 || t >= initial.frames()) continue;
        for (int k = 0; k < rows * cols; ++k) {
          const recon::Label& l = seeds.at(static_cast<int>(sc), st, k);
          if (!l.present()) continue;
          initial.at(c, t, k) = l;
          ++seeded;
        }
      }
    }
    if (seeded == 0) throw std::runtime_error(cl.Required("seed") + ": no seed label in the frames");
    recon::LabelStore store(std::move(initial));

    std::vector<CameraCounts> counts(cameras.size());
    for (size_t c = 0; c < cameras.size(); ++c) {
      const int ci = static_cast<int>(c);
      std::string error;
      cv::Mat previous = sequence.ReadDisplay(ci, first, 0, &error);
      if (previous.empty()) throw std::runtime_error(cameras[c] + " frame " + std::to_string(first) + ": " + error);
      LabelFirstFrame(previous, ci, 0, rows, cols, &store, &counts[c]);
      for (int t = 1; t < static_cast<int>(frame_index.size()); ++t) {
        cv::Mat image = sequence.ReadDisplay(ci, frame_index[t], 0, &error);
        if (image.empty()) {
          counts[c].first_frame_note += (counts[c].first_frame_note.empty() ? "" : "; ") +
                                        std::string("frame ") + std::to_string(frame_index[t]) +
                                        " unreadable: tracking stops";
          break;
        }
        std::vector<std::pair<int, Eigen::Vector2d>> knots;
        std::vector<bool> was_accepted;
        for (int k = 0; k < rows * cols; ++k) {
          const recon::Label& l = store.at(ci, t - 1, k);
          if (!l.present() || store.at(ci, t, k).present()) continue;
          knots.emplace_back(k, l.px);
          was_accepted.push_back(l.state == recon::LabelState::kAccepted);
        }
        const std::vector<recon::TrackedKnot> tracked =
            recon::TrackKnots(previous, image, knots, rows, cols);
        std::vector<recon::LabelEdit> edits;
        for (size_t i = 0; i < tracked.size(); ++i)
          edits.push_back({ci, t, tracked[i].knot,
                           Made(tracked[i].px, recon::LabelSource::kTracked,
                                tracked[i].confidence, tracked[i].accepted && was_accepted[i])});
        store.Apply("track to frame " + std::to_string(frame_index[t]), edits);
        previous = image;
        if (!quiet && t % 10 == 0)
          std::fprintf(stderr, "%s: frame %d of %d\n", cameras[c].c_str(), t,
                       static_cast<int>(frame_index.size()));
      }
      for (int t = 0; t < store.labels().frames(); ++t)
        for (int k = 0; k < rows * cols; ++k) {
          const recon::Label& l = store.at(ci, t, k);
          if (!l.present()) continue;
          ++counts[c].labeled;
          counts[c].needs_review += l.state == recon::LabelState::kNeedsReview;
        }
    }
    store.Save(out);

    int64_t labeled = 0, review = 0;
    for (const auto& c : counts) labeled += c.labeled, review += c.needs_review;
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!quiet) {
      for (size_t c = 0; c < cameras.size(); ++c)
        std::fprintf(stderr, "%s: %lld labels, %lld for review%s%s\n", cameras[c].c_str(),
                     static_cast<long long>(counts[c].labeled),
                     static_cast<long long>(counts[c].needs_review),
                     counts[c].first_frame_note.empty() ? "" : "; ",
                     counts[c].first_frame_note.c_str());
      std::fprintf(stderr, "%lld labels (%lld for review) over %zu frames in %.1f s; written %s\n",
                   static_cast<long long>(labeled), static_cast<long long>(review),
                   frame_index.size(), wall_s, out.c_str());
    }
    if (cl.Flag("json")) {
      JsonWriter json;
      json.BeginObject();
      json.Key("labeled").Int(labeled);
      json.Key("needs_review").Int(review);
      json.Key("frames").Int(static_cast<int64_t>(frame_index.size()));
      json.Key("knots").Int(rows * cols);
      json.Key("seeded").Int(seeded);
      json.Key("cameras").BeginArray();
      for (size_t c = 0; c < cameras.size(); ++c) {
        json.BeginObject();
        json.Key("name").String(cameras[c]);
        json.Key("labeled").Int(counts[c].labeled);
        json.Key("needs_review").Int(counts[c].needs_review);
        json.Key("note").String(counts[c].first_frame_note);
        json.EndObject();
      }
      json.EndArray();
      json.Key("wall_s").Number(wall_s);
      json.EndObject();
      std::cout << json.str() << std::endl;
    }
    return 0;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "netlab label: %s\n(see netlab label --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "netlab label: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace netlab::app
