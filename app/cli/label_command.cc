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
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "calibration/rig.h"
#include "common/errors.h"
#include "common/files.h"
#include "common/output_paths.h"
#include "libreconstruct/coloring/net_coloring.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labeling/label_setup.h"
#include "libreconstruct/labeling/label_store.h"
#include "libreconstruct/labels/label_set.h"
#include "libreconstruct/recording/experiment.h"
#include "libreconstruct/recording/sequence.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab label EXPERIMENT.yaml --rig rig.yaml --coloring coloring.yaml --seed SEEDS\n"
    "                    --out labels.h5 [--xypts xypts.csv] [--frames A:B] [--mesh M]\n"
    "                    [--knotless] [--illumination F] [--no-colour-check] [--json]\n\n"
    "Runs the automatic part of the labeling from seed labels (docs/labeling.md):\n"
    "  1. first frame, each camera with four corner knots seeded, or three (one hidden): Find\n"
    "     Path along the sides, then along every row and every column (an inner knot is\n"
    "     accepted when its row and its column agree);\n"
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
    "  --knotless          the net has no knot balls (Net B): an edge knot Fill Grid or Find\n"
    "                      Node finds must lie where its straight links' colours change\n"
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

// What is labeled: the net's shape, the experiment's cameras (each in the rig), the frames.
struct LabelJob {
  int rows = 0, cols = 0;
  std::vector<std::string> cameras;
  int first = 0, last = -1;      // frame numbers, inclusive
  std::vector<int> frame_index;  // first to last: the frame number of each frame row
};

// What the command reports on stderr and as JSON.
struct LabelReport {
  std::vector<CameraCounts> counts;  // per camera of the job
  int64_t labeled = 0, needs_review = 0, seeded = 0;
  double wall_s = 0.0;
};

// The experiment's camera names, in its order; each must be in the rig.
std::vector<std::string> ExperimentCameras(const recon::SynchronizedSequence& sequence,
                                           const calib::Rig& rig, const std::string& rig_path) {
  std::vector<std::string> cameras;
  for (const auto& c : sequence.experiment().cameras) {
    if (rig.Find(c.name) < 0)
      throw std::runtime_error(rig_path + ": no camera '" + c.name +
                               "' (the experiment's cameras must be in the rig)");
    cameras.push_back(c.name);
  }
  return cameras;
}

// The frames to label (job->first, last, frame_index): --frames A:B, which must lie within the
// recording, else the whole recording.
void SelectFrames(const CommandLine& cl, const recon::SynchronizedSequence& sequence,
                  LabelJob* job) {
  int first = sequence.first_frame(), last = sequence.last_frame();
  int a = first, b = last;
  if (cl.FrameRange("frames", &a, &b)) {
    if (a < first || b > last)
      throw UsageError("--frames " + *cl.Option("frames") + " lies outside the recording's " +
                       "frames " + std::to_string(first) + ":" + std::to_string(last));
    first = a, last = b;
  }
  job->first = first, job->last = last;
  for (int f = first; f <= last; ++f) job->frame_index.push_back(f);
}

// Empty labels over the job's frames with the seed labels of those frames in; *seeded: how
// many. Throws when a seed's camera is not in the experiment, or no seed lies in the frames.
recon::LabelSet SeededLabels(const LabelJob& job, const recon::LabelSet& seeds,
                             const std::string& seed_path, const calib::Rig& rig, int64_t* seeded) {
  recon::LabelSet initial =
      recon::LabelSet::Empty(job.rows, job.cols, job.cameras, job.frame_index);
  *seeded = 0;
  for (size_t sc = 0; sc < seeds.cameras.size(); ++sc) {
    const int c = initial.FindCamera(seeds.cameras[sc]);
    if (c < 0)
      throw std::runtime_error(seed_path + ": camera '" + seeds.cameras[sc] +
                               "' is not in the experiment");
    const calib::CameraIntrinsics* size = nullptr;
    for (const calib::Camera& camera : rig.cameras)
      if (camera.name == seeds.cameras[sc]) size = &camera.intrinsics;
    for (int st = 0; st < seeds.frames(); ++st) {
      const int t = seeds.frame_index[st] - job.first;
      if (t < 0 || t >= initial.frames()) continue;
      for (int k = 0; k < job.rows * job.cols; ++k) {
        const recon::Label& l = seeds.at(static_cast<int>(sc), st, k);
        if (!l.present()) continue;
        // A seed off the image (one at (-1e9, 5) was imported as is) is a broken file, not a
        // label: the tools would track from it.
        if (size && size->width > 0 &&
            !(l.px.x() >= -0.5 && l.px.x() <= size->width - 0.5 && l.px.y() >= -0.5 &&
              l.px.y() <= size->height - 0.5)) {
          std::ostringstream os;
          os << seed_path << ": camera " << seeds.cameras[sc] << ", frame " << seeds.frame_index[st]
             << ", knot (" << k / job.cols << "," << k % job.cols << "): seed (" << l.px.x() << ", "
             << l.px.y() << ") is outside the " << size->width << "x" << size->height << " image";
          throw InputError(os.str());
        }
        initial.at(c, t, k) = l;
        ++*seeded;
      }
    }
  }
  if (*seeded == 0) throw std::runtime_error(seed_path + ": no seed label in the frames");
  return initial;
}

// Per camera: its labels, those for review, and its note (what went wrong: corners not seeded
// in the first frame, frames unreadable).
std::vector<CameraCounts> CountLabels(const LabelJob& job, const recon::LabelStore& store,
                                      std::vector<std::string> notes) {
  const int rows = job.rows, cols = job.cols;
  const int corners[4] = {0, cols - 1, (rows - 1) * cols, rows * cols - 1};
  std::vector<CameraCounts> counts(job.cameras.size());
  for (size_t c = 0; c < job.cameras.size(); ++c) {
    const int ci = static_cast<int>(c);
    int corners_labeled = 0;
    for (int k : corners) corners_labeled += store.at(ci, 0, k).present();
    if (corners_labeled < 3)
      notes[c] =
          "fewer than three corners in the first frame: labeled where the other cameras "
          "see the knots" +
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
  return counts;
}

// The summary on stderr: per camera, then in all.
void PrintReport(const LabelJob& job, const LabelReport& r, const std::string& out) {
  for (size_t c = 0; c < job.cameras.size(); ++c)
    std::fprintf(stderr, "%s: %lld labels, %lld for review%s%s\n", job.cameras[c].c_str(),
                 static_cast<long long>(r.counts[c].labeled),
                 static_cast<long long>(r.counts[c].needs_review),
                 r.counts[c].first_frame_note.empty() ? "" : "; ",
                 r.counts[c].first_frame_note.c_str());
  std::fprintf(stderr, "%lld labels (%lld for review) over %zu frames in %.1f s; written %s\n",
               static_cast<long long>(r.labeled), static_cast<long long>(r.needs_review),
               job.frame_index.size(), r.wall_s, out.c_str());
}

// The summary as one JSON object on stdout (--json).
void PrintJson(const LabelJob& job, const LabelReport& r) {
  JsonWriter json;
  json.BeginObject();
  json.Key("labeled").Int(r.labeled);
  json.Key("needs_review").Int(r.needs_review);
  json.Key("frames").Int(static_cast<int64_t>(job.frame_index.size()));
  json.Key("knots").Int(job.rows * job.cols);
  json.Key("seeded").Int(r.seeded);
  json.Key("cameras").BeginArray();
  for (size_t c = 0; c < job.cameras.size(); ++c) {
    json.BeginObject();
    json.Key("name").String(job.cameras[c]);
    json.Key("labeled").Int(r.counts[c].labeled);
    json.Key("needs_review").Int(r.counts[c].needs_review);
    json.Key("note").String(r.counts[c].first_frame_note);
    json.EndObject();
  }
  json.EndArray();
  json.Key("wall_s").Number(r.wall_s);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunLabel(const std::vector<std::string>& args) {
  return RunGuarded("label", [&] {
    const CommandLine cl(
        args, {"json", "quiet", "help", "no-colour-check", "knotless"},
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
    // Before any work: no output over an input or the other output, both outputs writable.
    CheckOutputPaths({{"experiment", cl.positional()[0]},
                      {"--rig", cl.Required("rig")},
                      {"--coloring", cl.Required("coloring")},
                      {"--seed", cl.Required("seed")}},
                     {{"--out", out}, {"--xypts", cl.Option("xypts").value_or("")}});
    // The inputs: rig, colouring, experiment, frames, seeds.
    const calib::Rig rig = calib::ReadRig(cl.Required("rig"));
    std::vector<std::array<int, 3>> dyes;
    const recon::NetColoring coloring = recon::ReadColoring(cl.Required("coloring"), &dyes);
    LabelJob job;
    job.rows = coloring.rows, job.cols = coloring.cols;
    recon::SynchronizedSequence sequence(recon::LoadExperiment(cl.positional()[0]));
    job.cameras = ExperimentCameras(sequence, rig, cl.Required("rig"));
    SelectFrames(cl, sequence, &job);
    const recon::LabelSet seeds =
        recon::ReadLabelsAny(cl.Required("seed"), job.rows, job.cols, job.cameras);
    LabelReport report;
    recon::LabelStore store(SeededLabels(job, seeds, cl.Required("seed"), rig, &report.seeded));

    // The engine over the experiment's frames (the first unreadable one noted per camera), with
    // the colour check against the net's colouring as netlab render lights it (--illumination).
    recon::LabelingNet net;
    if (cl.Option("mesh")) net.link_length_m = cl.DoubleOption("mesh", 0.1, 1e-4, 10.0);
    net.knotless = cl.Flag("knotless");
    if (!cl.Flag("no-colour-check")) {
      net.coloring = &coloring;
      net.dyes = dyes;
      net.illumination = cl.DoubleOption("illumination", recon::kRenderIllumination, 1e-3, 100.0);
      net.bayer = sequence.experiment().cameras.front().bayer;
    }
    const recon::LabelingSetup setup = recon::SetUpLabeling(net);
    std::vector<std::string> notes(job.cameras.size());
    recon::LabelEngine engine(
        &store, &rig,
        [&](int c, int t) {
          std::string error;
          cv::Mat image = sequence.ReadDisplay(c, job.frame_index[t], 0, &error);
          if (image.empty() && notes[c].find("unreadable") == std::string::npos)
            notes[c] += (notes[c].empty() ? "" : "; ") + std::string("frame ") +
                        std::to_string(job.frame_index[t]) + " unreadable: " + error;
          return image;
        },
        setup.options);
    setup.ApplyColourCheck(&engine);
    // Every frame labeled, with its progress; Ctrl+C stops it between frames.
    const int rows_t = static_cast<int>(job.frame_index.size());
    ProgressBar bar("label", !quiet);
    const ProgressReporter progress = bar.Reporter();
    engine.LabelFrames(0, rows_t - 1, [&](int t) {
      progress.Report("frames labeled", t + 1, rows_t);
      progress.ThrowIfCancelled();
    });
    bar.Break();
    // Counted, written, reported.
    report.counts = CountLabels(job, store, notes);
    store.SetReasons(engine.reasons());
    {
      // Both put in place together once both are complete.
      OutputSet outputs({out, cl.Option("xypts").value_or("")});
      store.Save(out);
      if (const auto xypts = cl.Option("xypts")) recon::WriteXyPts(*xypts, store.labels());
      outputs.Commit();
    }
    for (const auto& c : report.counts)
      report.labeled += c.labeled, report.needs_review += c.needs_review;
    report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!quiet) PrintReport(job, report, out);
    if (cl.Flag("json")) PrintJson(job, report);
    return 0;
  });
}

}  // namespace netlab::app
