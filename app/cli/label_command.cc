// netlab label EXPERIMENT.yaml --rig rig.yaml --coloring coloring.yaml --seed SEEDS --out labels.h5
//              [--frames A:B] [--json]

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <map>
#include <optional>

#include "app/cli/command_line.h"
#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "calibration/rig.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labeling/label_store.h"
#include "libreconstruct/labels/label_set.h"
#include "libreconstruct/recording/experiment.h"
#include "libreconstruct/recording/sequence.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab label EXPERIMENT.yaml --rig rig.yaml --coloring coloring.yaml --seed SEEDS\n"
    "                    --out labels.h5 [--xypts xypts.csv] [--frames A:B] [--mesh M]\n"
    "                    [--illumination F] [--no-colour-check] [--json]\n\n"
    "Runs the automatic part of the labeling from seed labels (docs/labeling.md):\n"
    "  1. first frame, each camera whose four corner knots are seeded: Find Path along the four\n"
    "     sides, then along every row and every column (an inner knot is accepted when its row\n"
    "     and its column agree);\n"
    "  2. every frame: labels tracked from the previous frame; the cameras cross-checked with\n"
    "     epipolar geometry; Fill Grid labels the knots still missing where their triangulated\n"
    "     point, or the spheres of link length around their triangulated neighbours, project;\n"
    "     every label a tool made is checked against its knot's yarn colours (coloring.yaml).\n"
    "Labels whose checks disagree are kept for review, never accepted silently.\n\n"
    "options:\n"
    "  --rig FILE          the calibrated rig (its camera names must match the experiment's)\n"
    "  --coloring FILE     coloring.yaml (netlab color-net): the net's knots\n"
    "  --seed SEEDS        labels.h5 or a DLTdv8-style xypts.csv (cameras in the experiment's\n"
    "                      order), e.g. the four corners in the first frame of each camera\n"
    "  --out FILE          labels.h5 (written via a .partial file, then renamed)\n"
    "  --xypts FILE        also export the labels as DLTdv8-style xypts.csv (accepted and\n"
    "                      under review alike; labels.h5 keeps the states)\n"
    "  --frames A:B        frames A to B inclusive (default: the whole recording)\n"
    "  --mesh M            link length in m, knot to knot (default: estimated from the first\n"
    "                      frame's triangulated knots)\n"
    "  --illumination F    how brightly the yarns are lit, for the colour check: a white dye\n"
    "                      reads F of sensor white (default 0.85, netlab render's)\n"
    "  --no-colour-check   skip the colour check (frames of another colouring, or none)\n"
    "  --quiet             no progress or summary on stderr\n"
    "  --json              print one JSON summary object on stdout as the last output: labeled,\n"
    "                      needs_review, frames, wall_s, and per camera\n\n"
    "exit status: 0 done, 1 bad input, 2 usage error.\n";

struct CameraCounts {
  int64_t labeled = 0, needs_review = 0;
  std::string first_frame_note;
};

}  // namespace

int RunLabel(const std::vector<std::string>& args) {
  try {
    const CommandLine cl(args, {"json", "quiet", "help", "no-colour-check"},
                         {"rig", "coloring", "seed", "out", "frames", "mesh", "xypts", "illumination"});
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
    std::vector<std::array<int, 3>> dyes;
    const recon::NetColoring coloring = recon::ReadColoring(cl.Required("coloring"), &dyes);
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

    recon::LabelEngineOptions options;
    if (cl.Option("mesh")) options.link_length_m = cl.DoubleOption("mesh", 0.1, 1e-4, 10.0);
    std::vector<std::string> notes(cameras.size());
    recon::LabelEngine engine(
        &store, &rig,
        [&](int c, int t) {
          std::string error;
          cv::Mat image = sequence.ReadDisplay(c, frame_index[t], 0, &error);
          if (image.empty() && notes[c].find("unreadable") == std::string::npos)
            notes[c] += (notes[c].empty() ? "" : "; ") + std::string("frame ") +
                        std::to_string(frame_index[t]) + " unreadable: " + error;
          return image;
        },
        options);
    if (!cl.Flag("no-colour-check")) {
      recon::Lighting lighting;
      lighting.exposure = cl.DoubleOption("illumination", 0.85, 1e-3, 100.0);
      recon::IdentityCheckOptions identity;
      identity.identify.bayer = sequence.experiment().cameras.front().bayer;
      engine.SetCodebook(recon::CodebookFromColoring(coloring, dyes, lighting), identity);
    }
    const int rows_t = static_cast<int>(frame_index.size());
    engine.LabelFirstFrame(0);
    engine.CrossCheck(0);
    for (int t = 1; t < rows_t; ++t) {
      engine.Track(t - 1, t);
      engine.CrossCheck(t);
      if (!quiet && t % 10 == 0)
        std::fprintf(stderr, "frame %d of %d\n", t + 1, rows_t);
    }
    const int corners[4] = {0, cols - 1, (rows - 1) * cols, rows * cols - 1};
    std::vector<CameraCounts> counts(cameras.size());
    for (size_t c = 0; c < cameras.size(); ++c) {
      const int ci = static_cast<int>(c);
      bool corners_seeded = true;
      for (int k : corners) corners_seeded = corners_seeded && store.at(ci, 0, k).present();
      if (!corners_seeded) notes[c] = "not every corner is seeded in the first frame" +
                              std::string(notes[c].empty() ? "" : "; ") + notes[c];
      counts[c].first_frame_note = notes[c];
      for (int t = 0; t < store.labels().frames(); ++t)
        for (int k = 0; k < rows * cols; ++k) {
          const recon::Label& l = store.at(ci, t, k);
          if (!l.present()) continue;
          ++counts[c].labeled;
          counts[c].needs_review += l.state == recon::LabelState::kNeedsReview;
        }
    }
    store.Save(out);
    if (const auto xypts = cl.Option("xypts")) recon::WriteXyPts(*xypts, store.labels());

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
