// netlab render --sim result.h5 --out DIR [--rig rig.yaml] [--frames A:B] [--scale S]
//               [--noise SIGMA] [--json] ...

#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "app/command_line/command_line.h"
#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "libreconstruct/twin/synthetic_experiment.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab render --sim RESULT.h5 --out DIR [--rig rig.yaml] [--frames A:B] [--scale S]\n"
    "                     [--noise SIGMA] [--json] [options]\n\n"
    "Films a simulated shot (`netlab simulate` output) with a virtual copy of the camera rig\n"
    "(docs/render.md): DIR/experiment.yaml with one raw Bayer frame sequence and timestamps per\n"
    "camera (read it with `netlab ingest`), DIR/truth.h5 (true knot tracks, true pixels and\n"
    "visibility per camera and frame, the rig), DIR/rig_true.yaml, and calibration images of the\n"
    "double-sided checker foil in DIR/calibration/<camera>/ with DIR/calibration/foil.yaml.\n\n"
    "options:\n"
    "  --sim FILE             simulation result (needs /nodes and /scenario)\n"
    "  --out DIR              output folder, written as DIR.partial and put in place of DIR\n"
    "                         when complete (a failing run leaves an existing DIR as it was)\n"
    "  --rig FILE             rig file (default: the paper's rig, two facing stereo pairs)\n"
    "  --frames A:B           camera frames A to B inclusive, frame k at time k / fps\n"
    "                         (default: every frame the simulation covers)\n"
    "  --scale S              image scale, 0 < S <= 1 (0.25: 512 x 512 for fast tests)\n"
    "  --noise SIGMA          sensor noise, grey levels of 8 bits (default 2)\n"
    "  --fps F                camera frame rate (default 179)\n"
    "  --bit-depth N          8, 10, 12 or 16 (default 8; deeper in 16-bit PGM)\n"
    "  --bayer P              RGGB, BGGR, GRBG, GBRG or none (default RGGB)\n"
    "  --background B         black or white (default black)\n"
    "  --exposure S           exposure time for motion blur, s (default 0.001)\n"
    "  --blur-samples N       renders averaged over the exposure (default 3; 1: no blur)\n"
    "  --vignetting V         0..1 of the lens's cos^4 fall-off (default 0.5)\n"
    "  --calibration-views N  foil poses for calibration images (default 20; 0: none)\n"
    "  --coloring FILE        yarn colours per link (`netlab color-net`; default: six dyes cycled)\n"
    "  --seed N               noise and pose seed (default 1)\n"
    "  --camera-time-offset CAM=D[,CAM=D...]\n"
    "                         camera CAM exposes its frame k at (k + D) / fps, D in frames,\n"
    "                         -1 < D < 1 (a trigger delay its timestamps do not show); written\n"
    "                         into truth.h5 /camera_time_offset_frames\n"
    "  --threads N            rendering threads (default 2)\n"
    "  --json                 print one JSON summary object on stdout as the last output\n"
    "  --quiet                no progress on stderr\n\n"
    "exit status: 0 rendered, 1 bad input (named), 2 usage error.\n";

// --camera-time-offset CAM=D[,CAM=D...]: one offset per rig camera (0 where not named).
std::vector<double> ParseCameraOffsets(const std::string& text, const calib::Rig& rig) {
  std::vector<double> offsets(rig.cameras.size(), 0.0);
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    const size_t eq = item.find('=');
    const std::string name = item.substr(0, eq);
    const int c = eq == std::string::npos ? -1 : rig.Find(name);
    if (eq == std::string::npos)
      throw UsageError("--camera-time-offset expects CAM=FRAMES[,CAM=FRAMES...], got '" + item +
                       "'");
    if (c < 0) {
      std::string names;
      for (const auto& camera : rig.cameras) names += (names.empty() ? "" : ", ") + camera.name;
      throw UsageError("--camera-time-offset " + item + ": the rig has no camera '" + name +
                       "' (cameras: " + names + ")");
    }
    const std::string value = item.substr(eq + 1);
    size_t used = 0;
    double d = 0.0;
    try {
      d = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size() || !std::isfinite(d) || !(std::abs(d) < 1.0))
      throw UsageError("--camera-time-offset " + item +
                       ": the offset must be a number of frames with -1 < D < 1");
    offsets[c] = d;
  }
  return offsets;
}

void PrintJson(const recon::RenderSummary& s, const std::string& out) {
  JsonWriter json;
  json.BeginObject();
  json.Key("out").String(out);
  json.Key("frames").Int(s.frames);
  json.Key("cameras").Int(s.cameras);
  json.Key("knots").Int(s.knots);
  json.Key("knots_visible").BeginObject();
  for (size_t c = 0; c < s.camera_names.size(); ++c) {
    json.Key(s.camera_names[c]).BeginObject();
    json.Key("mean").Number(s.knots_visible_mean[c]);
    json.Key("min").Int(s.knots_visible_min[c]);
    json.EndObject();
  }
  json.EndObject();
  json.Key("calibration_images").Int(s.calibration_images);
  json.Key("render_s").Number(s.render_s);
  json.Key("wall_s").Number(s.wall_s);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunRender(const std::vector<std::string>& args) {
  return RunGuarded("render", [&] {
    const CommandLine cl(args, {"json", "quiet", "help"},
                         {"sim", "out", "rig", "frames", "scale", "noise", "fps", "bit-depth",
                          "bayer", "background", "exposure", "blur-samples", "vignetting",
                          "calibration-views", "seed", "threads", "coloring",
                          "camera-time-offset"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    recon::RenderJob job;
    job.simulation = cl.Required("sim");
    job.out_dir = cl.Required("out");
    const double scale = cl.DoubleOption("scale", 1.0, 1e-3, 1.0);
    if (const auto rig = cl.Option("rig"))
      job.rig = recon::ScaleRig(calib::ReadRig(*rig), scale);
    else
      job.rig = calib::PaperRig(scale);
    cl.FrameRange("frames", &job.first_frame, &job.last_frame);
    job.fps = cl.DoubleOption("fps", 179.0, 1e-3, 1e6);
    job.exposure_s = cl.DoubleOption("exposure", 1e-3, 0.0, 1.0);
    job.blur_samples = cl.IntOption("blur-samples", 3, 1, 64);
    job.calibration_views = cl.IntOption("calibration-views", 20, 0, 1000);
    job.threads = cl.IntOption("threads", 2, 1, 64);
    job.sensor.noise_sigma = cl.DoubleOption("noise", 2.0, 0.0, 255.0);
    job.sensor.vignetting = cl.DoubleOption("vignetting", 0.5, 0.0, 1.0);
    job.sensor.bit_depth = cl.IntOption("bit-depth", 8, 8, 16);
    if (job.sensor.bit_depth != 8 && job.sensor.bit_depth != 10 && job.sensor.bit_depth != 12 &&
        job.sensor.bit_depth != 16)
      throw UsageError("--bit-depth expects 8, 10, 12 or 16");
    job.sensor.seed = static_cast<uint64_t>(cl.IntOption("seed", 1, 0, 1 << 30));
    if (const auto bayer = cl.Option("bayer"))
      if (!recon::ParseBayerPattern(*bayer, &job.sensor.bayer))
        throw UsageError("--bayer expects RGGB, BGGR, GRBG, GBRG or none, got '" + *bayer + "'");
    const std::string background = cl.Option("background").value_or("black");
    if (background == "white")
      job.background = recon::Colour(1.f, 1.f, 1.f);
    else if (background != "black")
      throw UsageError("--background expects black or white, got '" + background + "'");

    if (const auto offsets = cl.Option("camera-time-offset"))
      job.camera_time_offset_frames = ParseCameraOffsets(*offsets, job.rig);
    if (const auto coloring = cl.Option("coloring")) {
      job.coloring = {recon::LoadYarnColoring(*coloring)};
      job.coloring_file = *coloring;
    }
    for (const char* input : {"rig", "coloring"})
      if (const auto path = cl.Option(input))
        recon::CheckOutsideOutput(*path, std::string("--") + input, job.out_dir);
    ProgressBar bar("rendering", !cl.Flag("quiet"));
    const recon::RenderSummary summary =
        recon::RenderExperiment(job, [&](int done, int total) { bar.Update(done, total); });
    if (!cl.Flag("quiet")) {
      std::fprintf(stderr, "rendered %d frames x %d cameras (%d knots) into %s in %.1f s\n",
                   summary.frames, summary.cameras, summary.knots, job.out_dir.c_str(),
                   summary.wall_s);
      for (size_t c = 0; c < summary.camera_names.size(); ++c)
        std::fprintf(stderr, "  %s: %.1f knots visible per frame (min %d)\n",
                     summary.camera_names[c].c_str(), summary.knots_visible_mean[c],
                     summary.knots_visible_min[c]);
    }
    if (cl.Flag("json")) PrintJson(summary, job.out_dir);
    return 0;
  });
}

}  // namespace netlab::app
