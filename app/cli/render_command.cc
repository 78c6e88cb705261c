// netlab render --sim result.h5 --out DIR [--rig rig.yaml] [--frames A:B] [--scale S]
//               [--noise SIGMA] [--json] ...

#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
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
    "  --background B         black, white or textile (default black; textile: a black cloth\n"
    "                         panel with folds and weave)\n"
    "  --frame-clutter        with --background textile: the rig's structure along the\n"
    "                         frame's edges\n"
    "  --exposure S           exposure time for motion blur, s (default 0.001)\n"
    "  --blur-samples N       renders averaged over the exposure (default 3; 1: no blur)\n"
    "  --vignetting V         0..1 of the lens's cos^4 fall-off (default 0.5)\n"
    "  --calibration-views N  foil poses for calibration images (default 20; 0: none)\n"
    "  --coloring FILE        yarn colours per link (`netlab color-net`; default: six dyes "
    "cycled)\n"
    "  --seed N               noise and pose seed (default 1)\n"
    "  --camera-time-offset CAM=D[,CAM=D...]\n"
    "                         camera CAM exposes its frame k at (k + D) / fps, D in frames,\n"
    "                         -1 < D < 1 (a trigger delay its timestamps do not show); written\n"
    "                         into truth.h5 /camera_time_offset_frames\n"
    "  --lamps paper|FILE     point lamps instead of the directional light: paper, one beside\n"
    "                         each camera (the target glossy); or a file {ambient, glossy,\n"
    "                         shininess, lamps: [{position: [x, y, z], power}]}; the target\n"
    "                         casts shadows where it hides a lamp\n"
    "  --flicker HZ:DEPTH[:DUTY]\n"
    "                         the light's intensity 1 + DEPTH cos(2 pi HZ t) (mains ripple:\n"
    "                         100:0.3), or with DUTY a PWM LED on for DUTY of each period at\n"
    "                         1 - DEPTH when off; each frame gets its mean over the exposure\n"
    "  --f-number N           thin-lens depth of field at f-number N (with --focus-distance)\n"
    "  --focus-distance M     the distance in focus, m (camera depth)\n"
    "  --pixel-pitch UM       the sensor's pixel pitch at --scale 1, um (default 5.5)\n"
    "  --camera-variation SIGMA\n"
    "                         cameras that differ: white balance, gain, gamma, fixed-pattern\n"
    "                         noise and hot pixels drawn with --seed at relative spread SIGMA\n"
    "  --camera-response FILE per-camera responses (cameras: {cam0: {white_balance: [R, G, B],\n"
    "                         gain, gamma, prnu, dsnu, hot_pixels, seed}})\n"
    "  --camera-motion CAM=AMPLITUDE_MM[:HZ][,CAM=...]\n"
    "                         camera CAM's centre vibrating by AMPLITUDE_MM at HZ along a seeded\n"
    "                         direction, or without HZ jumping by it in the middle of the\n"
    "                         frames; its pose per frame is written into truth.h5\n"
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

// A number from `text` (the whole of it), or UsageError naming `option` and `what`.
double Number(const std::string& text, const std::string& option, const std::string& what) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
    throw UsageError(option + ": " + what + " must be a number, got '" + text + "'");
  return value;
}

// --flicker HZ:DEPTH[:DUTY].
recon::Flicker ParseFlicker(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream items(text);
  for (std::string part; std::getline(items, part, ':');) parts.push_back(part);
  if (parts.size() < 2 || parts.size() > 3)
    throw UsageError("--flicker expects HZ:DEPTH or HZ:DEPTH:DUTY, got '" + text + "'");
  recon::Flicker flicker;
  flicker.hz = Number(parts[0], "--flicker " + text, "the frequency HZ");
  flicker.depth = Number(parts[1], "--flicker " + text, "the depth");
  if (parts.size() == 3) flicker.duty = Number(parts[2], "--flicker " + text, "the duty cycle");
  if (!(flicker.hz > 0.0)) throw UsageError("--flicker " + text + ": the frequency must be > 0 Hz");
  if (!(flicker.depth >= 0.0 && flicker.depth <= 1.0))
    throw UsageError("--flicker " + text + ": the depth must be in [0, 1]");
  if (parts.size() == 3 && !(flicker.duty > 0.0 && flicker.duty < 1.0))
    throw UsageError("--flicker " + text + ": the duty cycle must be in (0, 1)");
  return flicker;
}

// --camera-motion CAM=AMPLITUDE_MM[:HZ][,...]: one motion per rig camera (still where not named).
std::vector<recon::CameraMotion> ParseCameraMotion(const std::string& text, const calib::Rig& rig,
                                                   uint64_t seed) {
  std::vector<recon::CameraMotion> motion(rig.cameras.size());
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos)
      throw UsageError("--camera-motion expects CAM=AMPLITUDE_MM[:HZ][,...], got '" + item + "'");
    const std::string name = item.substr(0, eq);
    const int c = rig.Find(name);
    if (c < 0) {
      std::string names;
      for (const auto& camera : rig.cameras) names += (names.empty() ? "" : ", ") + camera.name;
      throw UsageError("--camera-motion " + item + ": the rig has no camera '" + name +
                       "' (cameras: " + names + ")");
    }
    const std::string value = item.substr(eq + 1);
    const size_t colon = value.find(':');
    const double mm = Number(value.substr(0, colon), "--camera-motion " + item, "the amplitude");
    double hz = 0.0;
    if (colon != std::string::npos)
      hz = Number(value.substr(colon + 1), "--camera-motion " + item, "the frequency");
    if (!(mm > 0.0 && mm <= 1000.0))
      throw UsageError("--camera-motion " + item + ": the amplitude must be in (0, 1000] mm");
    if (colon != std::string::npos && !(hz > 0.0))
      throw UsageError("--camera-motion " + item + ": the frequency must be > 0 Hz");
    motion[c] =
        recon::DrawCameraMotion(1e-3 * mm, hz, std::numeric_limits<double>::quiet_NaN(), seed, c);
  }
  return motion;
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
    const CommandLine cl(args, {"json", "quiet", "help", "frame-clutter"},
                         {"sim",
                          "out",
                          "rig",
                          "frames",
                          "scale",
                          "noise",
                          "fps",
                          "bit-depth",
                          "bayer",
                          "background",
                          "exposure",
                          "blur-samples",
                          "vignetting",
                          "calibration-views",
                          "seed",
                          "threads",
                          "coloring",
                          "camera-time-offset",
                          "flicker",
                          "f-number",
                          "focus-distance",
                          "pixel-pitch",
                          "camera-variation",
                          "camera-response",
                          "camera-motion",
                          "lamps"});
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
    else if (background == "textile")
      job.textile_background = true;
    else if (background != "black")
      throw UsageError("--background expects black, white or textile, got '" + background + "'");
    job.background_clutter = cl.Flag("frame-clutter");
    if (job.background_clutter && !job.textile_background)
      throw UsageError("--frame-clutter goes with --background textile");

    if (const auto lamps = cl.Option("lamps")) {
      if (*lamps == "paper")
        job.paper_lamps = true;
      else
        job.lamps = recon::ReadLamps(*lamps);
    }
    if (const auto flicker = cl.Option("flicker")) job.flicker = ParseFlicker(*flicker);
    if (cl.Option("f-number") || cl.Option("focus-distance")) {
      if (!cl.Option("f-number") || !cl.Option("focus-distance"))
        throw UsageError("--f-number and --focus-distance go together");
      job.depth_of_field.f_number = cl.DoubleOption("f-number", 4.0, 0.5, 64.0);
      job.depth_of_field.focus_distance_m = cl.DoubleOption("focus-distance", 3.0, 0.05, 1e4);
      job.depth_of_field.pixel_pitch_m =
          1e-6 * cl.DoubleOption("pixel-pitch", 5.5, 0.1, 100.0) / scale;
      for (const calib::Camera& camera : job.rig.cameras) {
        const double f = camera.intrinsics.fx * job.depth_of_field.pixel_pitch_m;
        if (!(job.depth_of_field.focus_distance_m > 2.0 * f))
          throw UsageError("--focus-distance must be beyond twice the focal length (" +
                           std::to_string(f * 1e3) + " mm for " + camera.name + ")");
      }
    }
    if (cl.Option("camera-variation") && cl.Option("camera-response"))
      throw UsageError("--camera-variation and --camera-response exclude each other");
    if (cl.Option("camera-variation"))
      job.responses = recon::DrawCameraResponses(static_cast<int>(job.rig.cameras.size()),
                                                 cl.DoubleOption("camera-variation", 0.0, 0.0, 1.0),
                                                 job.sensor.seed);
    if (const auto file = cl.Option("camera-response"))
      job.responses = recon::ReadCameraResponses(*file, job.rig);
    if (const auto motion = cl.Option("camera-motion"))
      job.camera_motion = ParseCameraMotion(*motion, job.rig, job.sensor.seed);

    if (const auto offsets = cl.Option("camera-time-offset"))
      job.camera_time_offset_frames = ParseCameraOffsets(*offsets, job.rig);
    if (const auto coloring = cl.Option("coloring")) {
      job.coloring = {recon::LoadYarnColoring(*coloring)};
      job.coloring_file = *coloring;
    }
    for (const char* input : {"rig", "coloring", "camera-response", "lamps"})
      if (const auto path = cl.Option(input); path && *path != "paper")
        recon::CheckOutsideOutput(*path, std::string("--") + input, job.out_dir);
    ProgressBar bar("render", !cl.Flag("quiet"));
    const recon::RenderSummary summary = recon::RenderExperiment(job, bar.Reporter());
    bar.Break();
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
