// netlab triangulate --rig rig.yaml --labels LABELS --knots ROWSxCOLS --fps F --out tracks.h5
//                    [--csv PREFIX] [--ba none|points|rig] [--experiment FILE]
//                    [--estimate-offsets] [--apply-offsets] [--json]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
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
#include "common/tracks/track_file.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/geometry/camera_motion.h"
#include "libreconstruct/geometry/camera_offsets.h"
#include "libreconstruct/geometry/track_export.h"
#include "libreconstruct/labels/label_set.h"
#include "libreconstruct/recording/experiment.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab triangulate --rig rig.yaml --labels LABELS --knots ROWSxCOLS --fps F\n"
    "                          --out tracks.h5 [--csv PREFIX] [--ba none|points|rig]\n"
    "                          [--experiment FILE] [--estimate-offsets] [--apply-offsets]\n"
    "                          [--json]\n\n"
    "Triangulates every labeled knot in every frame from the cameras that labeled it, with\n"
    "outlier rejection, optional bundle adjustment and priors, and writes 3D knot tracks with\n"
    "their covariance (docs/triangulation.md).\n\n"
    "options:\n"
    "  --rig FILE          the calibrated cameras (netlab calibrate)\n"
    "  --labels FILE       labels.h5 (the labeling tools), or a DLTdv8-style xypts.csv whose\n"
    "                      camera C is the rig's C-th camera and point P knot P-1 in row-major\n"
    "                      order (OpenCV pixels: origin at the centre of the top-left pixel)\n"
    "  --knots ROWSxCOLS   the net's knots, e.g. 11x11\n"
    "  --fps F             frame rate: /time = frame / F unless --experiment has timestamps\n"
    "  --experiment FILE   the recording (experiment.yaml): /time of each frame is the mean of\n"
    "                      its cameras' timestamps, their spread in /frame_time_spread_s\n"
    "                      (checked: every labeled frame listed, increasing, the cameras within\n"
    "                      one frame of each other)\n"
    "  --out FILE          the knot-track file (HDF5, the layout the simulator writes, plus\n"
    "                      /knots/covariance, /knots/reprojection_error_px and /outliers)\n"
    "  --csv PREFIX        also write PREFIXxyzpts.csv and PREFIXxyzres.csv (DLTdv8 style)\n"
    "  --ba MODE           none: triangulation only; points (default): Ceres over the sequence\n"
    "                      with the priors below; rig: first the cameras' extrinsics (one pose\n"
    "                      each for the sequence; camera 1 and its distance to camera 2 held)\n"
    "  --outlier-px P      an observation this far from its point's projection is an outlier\n"
    "                      (default: 5x the labelling noise, --sigma-px or estimated from a\n"
    "                      first pass at 4 px; keep a fixed one above ~4x the noise)\n"
    "  --sigma-px S        labelling noise for the covariances (default: from the residuals)\n"
    "  --link-length M     link-length prior: adjacent knots M apart (off unless given)\n"
    "  --link-sigma M      its standard deviation (default 0.002)\n"
    "  --smooth-sigma M    smoothness prior: p[t-1] - 2p[t] + p[t+1] = 0 with this standard\n"
    "                      deviation, m (off unless given; ~ acceleration x frame time^2)\n"
    "  --rig-frames N      frames used to adjust the rig (default 200, spread over the sequence);\n"
    "                      the adjusted rig is used only if they determine every camera to\n"
    "                      --rig-max-sigma-mm (default 2) and --rig-max-sigma-deg (0.02)\n"
    "  --use-unreviewed    also use labels still marked for review (default: accepted only)\n"
    "  --max-sigma-mm S    a point whose largest sigma exceeds S mm is degenerate (its rays meet\n"
    "                      too close to parallel or head-on): kept out of the valid points,\n"
    "                      flagged with its reason in /knots/degenerate and /degenerate\n"
    "                      (default: 10x the sequence's median sigma)\n"
    "  --estimate-offsets  estimate each camera's sub-frame clock offset against the rig's first\n"
    "                      camera from the knots' motion, with its sigma (not determined when\n"
    "                      the sigma exceeds 0.05 frames: said so, no value)\n"
    "  --apply-offsets     estimate them and move each camera's labels to the frame time along\n"
    "                      their own track before triangulating\n"
    "  --truth FILE        knot tracks to compare with (e.g. the simulation that was rendered):\n"
    "                      every number in the truth's frame, the tracks moved onto it by the\n"
    "                      best rigid motion (a calibrated rig has its own world frame); the\n"
    "                      degenerate points apart\n"
    "  --threads N         worker threads (default 2)\n"
    "  --quiet             no progress or summary on stderr\n"
    "  --json              print one JSON summary object on stdout as the last output:\n"
    "                      frames, points (knots per frame), triangulated (knot-frames),\n"
    "                      degenerate_points, reprojection_rms_px, outliers, wall_s, with\n"
    "                      offsets camera_offsets_frames and camera_offsets_sigma_frames, and\n"
    "                      more\n\n"
    "exit status: 0 done, 1 bad input, 2 usage error.\n";

// The command line, checked.
struct TriangulateArgs {
  int rows = 0, cols = 0;
  std::string rig_path, labels_path, out;
  double fps = 0.0;
  std::string ba;                              // as given: none, points or rig
  std::optional<std::string> csv, truth_path;  // --csv PREFIX, --truth FILE
  std::optional<std::string> experiment_path;  // --experiment FILE
  bool quiet = false, json = false;
  bool estimate_offsets = false, apply_offsets = false;
  recon::SequenceOptions options;  // without progress
};

// Every option but --help, in the order they are checked (the first bad one is reported).
TriangulateArgs ParseArgs(const CommandLine& cl) {
  TriangulateArgs a;
  a.quiet = cl.Flag("quiet");
  a.json = cl.Flag("json");
  cl.Knots("knots", &a.rows, &a.cols);
  a.rig_path = cl.Required("rig");
  a.labels_path = cl.Required("labels");
  a.out = cl.Required("out");
  a.fps = cl.DoubleOption("fps", 0.0, 1e-6, 1e7);
  if (!cl.Option("fps")) throw UsageError("--fps is required");
  a.csv = cl.Option("csv");
  a.truth_path = cl.Option("truth");
  a.experiment_path = cl.Option("experiment");
  a.apply_offsets = cl.Flag("apply-offsets");
  a.estimate_offsets = cl.Flag("estimate-offsets") || a.apply_offsets;
  recon::SequenceOptions& options = a.options;
  a.ba = cl.Option("ba").value_or("points");
  if (!recon::ParseAdjustment(a.ba, &options.adjustment))
    throw UsageError("--ba expects none, points or rig, got '" + a.ba + "'");
  options.triangulation.outlier_threshold_px = cl.DoubleOption("outlier-px", 4.0, 0.01, 1e4);
  options.auto_threshold = !cl.Option("outlier-px");
  // 0 stands for "estimate" or "off" inside; a value the user gives must be a real one (a
  // --smooth-sigma 0 silently meant no prior at all).
  options.sigma_px = cl.DoubleOption("sigma-px", 0.0, 1e-6, 1e3);
  options.link_length_m = cl.DoubleOption("link-length", 0.0, 1e-6, 100.0);
  options.link_sigma_m = cl.DoubleOption("link-sigma", 0.002, 1e-9, 100.0);
  options.smoothness_sigma_m = cl.DoubleOption("smooth-sigma", 0.0, 1e-9, 100.0);
  options.rig_frames = cl.IntOption("rig-frames", 200, 1, 1000000);
  options.rig_max_center_sigma_mm = cl.DoubleOption("rig-max-sigma-mm", 2.0, 1e-9, 1e6);
  options.rig_max_rotation_sigma_deg = cl.DoubleOption("rig-max-sigma-deg", 0.02, 1e-9, 360.0);
  options.threads = cl.IntOption("threads", 2, 1, 256);
  options.use_unreviewed = cl.Flag("use-unreviewed");
  options.max_sigma_m = cl.DoubleOption("max-sigma-mm", 0.0, 1e-6, 1e9) * 1e-3;
  if (options.adjustment == recon::Adjustment::kNone &&
      (options.link_length_m > 0 || options.smoothness_sigma_m > 0))
    throw UsageError("the priors (--link-length, --smooth-sigma) need --ba points or rig");
  return a;
}

// The truth must be the labels' net over the labels' frames: a 6 x 6 truth against 11 x 11 labels
// matched the first 36 knots by (row, col) and reported "353 mm RMS" instead of refusing.
void CheckTruthMatches(const KnotTracks& truth, const TriangulateArgs& a,
                       const recon::LabelSet& labels, const std::vector<double>& times) {
  int rows = 0, cols = 0;
  for (const auto& [row, col] : truth.grid) {
    rows = std::max(rows, row + 1);
    cols = std::max(cols, col + 1);
  }
  if (rows != a.rows || cols != a.cols)
    throw InputError("--truth " + *a.truth_path + ": a " + std::to_string(rows) + "x" +
                     std::to_string(cols) + " net, the labels (--knots) are " +
                     std::to_string(a.rows) + "x" + std::to_string(a.cols));
  if (labels.frames() == 0 || truth.time.empty()) return;
  const double first = times.front(), last = times.back();
  if (last < truth.time.front() - 0.5 / a.fps || first > truth.time.back() + 0.5 / a.fps) {
    std::ostringstream os;
    os << "--truth " << *a.truth_path << ": covers " << truth.time.front() << ".."
       << truth.time.back() << " s, the labels' frames " << labels.frame_index.front() << ".."
       << labels.frame_index.back() << " are " << first << ".." << last << " s ("
       << (a.experiment_path ? "the cameras' timestamps" : "at --fps " + std::to_string(a.fps))
       << "): no frame in common";
    throw InputError(os.str());
  }
}

// The frames' times: from the recording's timestamps (--experiment) where it has them, else
// frame / --fps.
recon::FrameTimes FrameTimesOf(const TriangulateArgs& a, const calib::Rig& rig,
                               const recon::LabelSet& labels) {
  std::vector<std::string> names;
  std::vector<std::map<int, double>> timestamps(rig.cameras.size());
  std::vector<std::string> where(rig.cameras.size());
  for (const auto& c : rig.cameras) names.push_back(c.name);
  if (a.experiment_path) {
    const recon::Experiment experiment = recon::LoadExperiment(*a.experiment_path);
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      const int e = experiment.Find(rig.cameras[c].name);
      if (e < 0 || experiment.cameras[e].timestamps.empty()) continue;
      where[c] = experiment.cameras[e].timestamps;
      timestamps[c] = recon::ReadTimestamps(where[c]);
      if (timestamps[c].empty())
        throw InputError(where[c] + ": camera " + rig.cameras[c].name +
                         "'s timestamps file lists no frame");
    }
  }
  return recon::FrameTimesFromTimestamps(labels.frame_index, a.fps, names, timestamps, where);
}

// What one run produced, for the summary on stderr and the JSON on stdout.
struct Outcome {
  int frames = 0;
  recon::SequenceResult result;
  std::optional<recon::TruthComparison> truth;   // with --truth
  std::optional<recon::OffsetEstimate> offsets;  // with --estimate-offsets
  bool result_offsets_applied = false;           // --apply-offsets
  recon::FrameTimes times;
  std::string csv_pts, csv_res;             // with --csv
  std::vector<recon::CameraMotion> motion;  // the cameras that moved during the shot
  std::vector<std::string> warnings;
  double wall_s = 0.0;
};

// The knot-track file, and with --csv the DLTdv8-style files (their paths into `outcome`).
// All are put in place together once every one is complete (a failure leaves each as it was).
void WriteOutputs(const TriangulateArgs& a, const KnotTracks& tracks, Outcome* outcome) {
  if (a.csv) {
    outcome->csv_pts = *a.csv + "xyzpts.csv";
    outcome->csv_res = *a.csv + "xyzres.csv";
  }
  OutputSet outputs({a.out, outcome->csv_pts, outcome->csv_res});
  WriteKnotTracks(a.out, tracks);
  if (a.csv) {
    recon::WriteXyzPts(outcome->csv_pts, tracks, a.rows, a.cols);
    recon::WriteXyzRes(outcome->csv_res, tracks, a.rows, a.cols);
  }
  outputs.Commit();
}

// The rig adjustment's lines of the summary: the verdict, then per camera its change.
void PrintRigSummary(const recon::SequenceResult& r) {
  std::fprintf(stderr, "rig %s on %d frames (RMS %.3f -> %.3f px)\n",
               r.rig_adjusted ? "adjusted"
                              : "NOT adjusted: the sequence does not determine it; the "
                                "calibrated rig was kept",
               r.rig_frames_used, r.rig_rms_before_px, r.rig_rms_after_px);
  for (size_t c = 1; c < r.rig_center_change_mm.size(); ++c)
    std::fprintf(stderr, "  %s: %s %.3f mm (sigma %.3f), %.4f deg (sigma %.4f)\n",
                 r.rig.cameras[c].name.c_str(), r.rig_adjusted ? "moved" : "would move",
                 r.rig_center_change_mm[c], r.rig_center_sigma_mm[c], r.rig_rotation_change_deg[c],
                 r.rig_rotation_sigma_deg[c]);
}

// The degenerate points: how many, the bound and whence, the first few with their reasons.
void PrintDegenerate(const TriangulateArgs& a, const recon::SequenceResult& r) {
  const size_t n = r.degenerate_points.size();
  std::fprintf(stderr,
               "%zu degenerate point%s left out: largest sigma over %.3f mm (%s; median %.3f "
               "mm)%s\n",
               n, n == 1 ? "" : "s", r.max_sigma_m * 1e3, r.max_sigma_from.c_str(),
               r.median_sigma_m * 1e3, n > 0 ? ":" : "");
  constexpr size_t kShown = 5;
  for (size_t i = 0; i < std::min(n, kShown); ++i) {
    const recon::DegeneratePoint& d = r.degenerate_points[i];
    std::fprintf(stderr, "  frame %d, knot (%d,%d): %s\n", d.frame, d.knot / a.cols,
                 d.knot % a.cols, d.reason.c_str());
  }
  if (n > kShown) std::fprintf(stderr, "  and %zu more (/degenerate/reason)\n", n - kShown);
}

// Where the times come from, and each camera's clock offset when estimated.
void PrintClocks(const Outcome& o) {
  if (!o.times.cameras.empty()) {
    const double spread = *std::max_element(o.times.spread_s.begin(), o.times.spread_s.end());
    std::string names;
    for (const std::string& c : o.times.cameras) names += (names.empty() ? "" : ", ") + c;
    std::fprintf(stderr, "times from the timestamps of %s (mean per frame; spread up to %.4f ms)\n",
                 names.c_str(), spread * 1e3);
  }
  if (!o.offsets) return;
  std::fprintf(stderr, "camera clock offsets against %s (frames; %s):\n",
               o.offsets->cameras.front().camera.c_str(),
               o.result_offsets_applied ? "applied: each camera's labels moved to the frame time"
                                        : "not applied (--apply-offsets)");
  for (const recon::CameraOffset& c : o.offsets->cameras) {
    if (c.determined)
      std::fprintf(stderr, "  %s: %+.4f +- %.4f%s\n", c.camera.c_str(), c.offset_frames,
                   c.sigma_frames, c.why.empty() ? "" : ("  (" + c.why + ")").c_str());
    else
      std::fprintf(stderr, "  %s: not determined (%s)\n", c.camera.c_str(), c.why.c_str());
  }
}

// The comparison with the truth, in the truth's frame.
void PrintTruth(const recon::TruthComparison& t) {
  if (!t.aligned) {
    std::fprintf(stderr,
                 "against the truth: %lld valid points the truth has, fewer than the three "
                 "that fit its frame: no comparison\n",
                 static_cast<long long>(t.points));
    return;
  }
  std::fprintf(stderr,
               "against the truth, in its frame (the tracks moved %.4f deg and %.3f mm onto "
               "it): %.3f mm RMS (max %.3f mm) over %lld valid points, mean d2 %.2f\n",
               t.rotation_deg, t.translation_m * 1e3, t.rms_m * 1e3, t.max_m * 1e3,
               static_cast<long long>(t.points), t.mean_mahalanobis2);
  if (t.degenerate_points > 0)
    std::fprintf(stderr, "  the %lld degenerate points: %.1f mm RMS (max %.1f mm)\n",
                 static_cast<long long>(t.degenerate_points), t.degenerate_rms_m * 1e3,
                 t.degenerate_max_m * 1e3);
}

// The summary on stderr: counts, each prior's and the rig's effect, the truth, the warnings.
void PrintSummary(const TriangulateArgs& a, const Outcome& o) {
  const recon::SequenceResult& r = o.result;
  const long long degenerate = static_cast<long long>(r.degenerate_points.size());
  const long long untriangulated = r.candidates - r.triangulated - degenerate;
  std::fprintf(stderr,
               "%d frames x %d knots: %lld knot-frames triangulated of %lld seen twice or "
               "more (%lld not: see /outliers; %lld degenerate: see /degenerate), %lld seen "
               "once; reprojection RMS %.3f px; %zu outlier observations (threshold %.2f px); "
               "sigma %.3f px%s; --ba %s; %.1f s\n",
               o.frames, a.rows * a.cols, static_cast<long long>(r.triangulated),
               static_cast<long long>(r.candidates), untriangulated, degenerate,
               static_cast<long long>(r.single_view), r.reprojection_rms_px, r.outliers.size(),
               r.outlier_threshold_px, r.sigma_px, r.sigma_estimated ? " (estimated)" : "",
               a.ba.c_str(), o.wall_s);
  PrintDegenerate(a, r);
  PrintClocks(o);
  if (a.options.link_length_m > 0)
    std::fprintf(stderr, "link-length prior moved the points %.3f mm RMS (max %.3f mm)\n",
                 r.link_shift_rms_m * 1e3, r.link_shift_max_m * 1e3);
  if (a.options.smoothness_sigma_m > 0)
    std::fprintf(stderr,
                 "smoothness prior moved the points %.3f mm RMS (max %.3f mm); %lld two-view "
                 "points at odds with their tracks left out\n",
                 r.smoothness_shift_rms_m * 1e3, r.smoothness_shift_max_m * 1e3,
                 static_cast<long long>(r.track_outliers));
  if (a.options.adjustment == recon::Adjustment::kRig) PrintRigSummary(r);
  if (o.truth) PrintTruth(*o.truth);
  for (const std::string& w : o.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  std::fprintf(stderr, "written %s%s%s\n", a.out.c_str(),
               o.csv_pts.empty() ? "" : (", " + o.csv_pts + ", " + o.csv_res).c_str(), "");
}

void JsonArray(JsonWriter* json, const std::string& key, const std::vector<double>& values) {
  json->Key(key).BeginArray();
  for (double v : values) json->Number(v);
  json->EndArray();
}

// The times' source and, when estimated, the cameras' clock offsets (null where not determined).
void PrintJsonClocks(const Outcome& o, JsonWriter* json) {
  json->Key("time_from").String(o.times.cameras.empty() ? "fps" : "timestamps");
  double spread = 0.0;
  for (double v : o.times.spread_s) spread = std::max(spread, v);
  json->Key("frame_time_spread_max_s").Number(spread);
  if (!o.offsets) return;
  json->Key("camera_offsets_frames").BeginObject();
  for (const recon::CameraOffset& c : o.offsets->cameras) {
    json->Key(c.camera);
    if (c.determined)
      json->Number(c.offset_frames);
    else
      json->Null();
  }
  json->EndObject();
  json->Key("camera_offsets_sigma_frames").BeginObject();
  for (const recon::CameraOffset& c : o.offsets->cameras)
    json->Key(c.camera).Number(c.sigma_frames);
  json->EndObject();
  json->Key("camera_offsets_undetermined").BeginObject();
  for (const recon::CameraOffset& c : o.offsets->cameras)
    if (!c.determined) json->Key(c.camera).String(c.why);
  json->EndObject();
  json->Key("camera_offsets_applied").Bool(o.result_offsets_applied);
}

// The JSON summary on stdout (the contract: tests/app/cli/triangulate_command_test.cc).
void PrintJson(const TriangulateArgs& a, const Outcome& o) {
  const recon::SequenceResult& r = o.result;
  JsonWriter json;
  json.BeginObject();
  // Counts and residuals.
  json.Key("frames").Int(o.frames);
  json.Key("points").Int(a.rows * a.cols);
  json.Key("triangulated").Int(r.triangulated);
  json.Key("candidates").Int(r.candidates);
  json.Key("two_view").Int(r.two_view);
  json.Key("untriangulated")
      .Int(r.candidates - r.triangulated - static_cast<int64_t>(r.degenerate_points.size()));
  json.Key("degenerate_points").Int(static_cast<int64_t>(r.degenerate_points.size()));
  json.Key("max_sigma_m").Number(r.max_sigma_m);
  json.Key("max_sigma_from").String(r.max_sigma_from);
  json.Key("median_sigma_m").Number(r.median_sigma_m);
  json.Key("single_view").Int(r.single_view);
  json.Key("unreviewed_skipped").Int(r.unreviewed_skipped);
  json.Key("projected_skipped").Int(r.projected_skipped);
  json.Key("reprojection_rms_px").Number(r.reprojection_rms_px);
  json.Key("outliers").Int(static_cast<int64_t>(r.outliers.size()));
  json.Key("sigma_px").Number(r.sigma_px);
  json.Key("sigma_estimated").Bool(r.sigma_estimated);
  json.Key("outlier_threshold_px").Number(r.outlier_threshold_px);
  json.Key("ba").String(a.ba);
  // Each prior and the rig, when on.
  if (a.options.link_length_m > 0) {
    json.Key("link_prior_shift_rms_m").Number(r.link_shift_rms_m);
    json.Key("link_prior_shift_max_m").Number(r.link_shift_max_m);
  }
  if (a.options.smoothness_sigma_m > 0) {
    json.Key("track_outliers").Int(r.track_outliers);
    json.Key("prior_disagreements").Int(r.prior_disagreements);
    json.Key("smoothness_prior_shift_rms_m").Number(r.smoothness_shift_rms_m);
    json.Key("smoothness_prior_shift_max_m").Number(r.smoothness_shift_max_m);
  }
  if (a.options.adjustment == recon::Adjustment::kRig) {
    json.Key("rig_adjusted").Bool(r.rig_adjusted);
    json.Key("rig_frames").Int(r.rig_frames_used);
    json.Key("rig_rms_before_px").Number(r.rig_rms_before_px);
    json.Key("rig_rms_after_px").Number(r.rig_rms_after_px);
    JsonArray(&json, "rig_center_change_mm", r.rig_center_change_mm);
    JsonArray(&json, "rig_rotation_change_deg", r.rig_rotation_change_deg);
    JsonArray(&json, "rig_center_sigma_mm", r.rig_center_sigma_mm);
    JsonArray(&json, "rig_rotation_sigma_deg", r.rig_rotation_sigma_deg);
  }
  // The truth, the warnings, the times.
  PrintJsonClocks(o, &json);
  if (o.truth) {
    // In the truth's frame (NaN, i.e. null, with fewer than three points);
    // truth_aligned_rms_m is truth_rms_m.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const bool aligned = o.truth->aligned;
    json.Key("truth_points").Int(o.truth->points);
    json.Key("truth_rms_m").Number(aligned ? o.truth->rms_m : nan);
    json.Key("truth_max_m").Number(aligned ? o.truth->max_m : nan);
    json.Key("truth_aligned_rms_m").Number(aligned ? o.truth->rms_m : nan);
    json.Key("truth_mean_mahalanobis2").Number(aligned ? o.truth->mean_mahalanobis2 : nan);
    json.Key("truth_alignment_rotation_deg").Number(aligned ? o.truth->rotation_deg : nan);
    json.Key("truth_alignment_translation_m").Number(aligned ? o.truth->translation_m : nan);
    json.Key("truth_degenerate_points").Int(o.truth->degenerate_points);
    json.Key("truth_degenerate_rms_m").Number(aligned ? o.truth->degenerate_rms_m : nan);
    json.Key("truth_degenerate_max_m").Number(aligned ? o.truth->degenerate_max_m : nan);
  }
  // The cameras that moved during the shot: the frames, the largest departure.
  json.Key("moved_cameras").BeginArray();
  for (const recon::CameraMotion& m : o.motion) {
    if (m.moved.empty()) continue;
    json.BeginObject();
    json.Key("camera").String(m.camera);
    json.Key("frames").BeginArray();
    for (const auto& [first, last] : m.moved) json.BeginArray().Int(first).Int(last).EndArray();
    json.EndArray();
    json.Key("largest_departure_px").Number(m.largest_departure_px);
    json.Key("largest_departure_frame").Int(m.largest_departure_frame);
    json.EndObject();
  }
  json.EndArray();
  json.Key("warnings").BeginArray();
  for (const std::string& w : o.warnings) json.String(w);
  json.EndArray();
  json.Key("triangulate_s").Number(r.triangulate_s);
  json.Key("adjust_s").Number(r.adjust_s);
  json.Key("wall_s").Number(o.wall_s);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunTriangulate(const std::vector<std::string>& args) {
  return RunGuarded("triangulate", [&] {
    const CommandLine cl(
        args, {"json", "quiet", "help", "use-unreviewed", "estimate-offsets", "apply-offsets"},
        {"rig", "labels", "knots", "fps", "out", "csv", "ba", "outlier-px", "sigma-px",
         "link-length", "link-sigma", "smooth-sigma", "rig-frames", "truth", "threads",
         "rig-max-sigma-mm", "rig-max-sigma-deg", "max-sigma-mm", "experiment"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    const auto start = std::chrono::steady_clock::now();
    TriangulateArgs a = ParseArgs(cl);
    // Before any work: no output over an input or another output, every output's folder there.
    CheckOutputPaths({{"--rig", a.rig_path},
                      {"--labels", a.labels_path},
                      {"--truth", a.truth_path.value_or("")},
                      {"--experiment", a.experiment_path.value_or("")}},
                     {{"--out", a.out},
                      {"--csv", a.csv ? *a.csv + "xyzpts.csv" : ""},
                      {"--csv", a.csv ? *a.csv + "xyzres.csv" : ""}});

    // The inputs: rig, labels (of the rig's cameras), the truth.
    const calib::Rig rig = calib::ReadRig(a.rig_path);
    std::vector<std::string> names;
    for (const auto& c : rig.cameras) names.push_back(c.name);
    const recon::LabelSet labels = recon::ReadLabelsAny(a.labels_path, a.rows, a.cols, names);
    std::string rig_names;
    for (const std::string& name : names) rig_names += (rig_names.empty() ? "" : ", ") + name;
    for (const std::string& camera : labels.cameras)
      if (std::find(names.begin(), names.end(), camera) == names.end())
        throw InputError(a.labels_path + ": labels of camera '" + camera + "', which the --rig " +
                         a.rig_path + " does not have (it has " + std::to_string(names.size()) +
                         ": " + rig_names + "): give the rig the labels were made with");
    Outcome o;
    o.times = FrameTimesOf(a, rig, labels);
    std::optional<KnotTracks> truth;
    if (a.truth_path) {
      truth = ReadKnotTracks(*a.truth_path);
      CheckTruthMatches(*truth, a, labels, o.times.time_s);
    }

    // The reconstruction, with its progress on stderr.
    ProgressBar bar("triangulate", !a.quiet);
    a.options.progress = bar.Reporter();
    o.frames = labels.frames();
    if (a.estimate_offsets) {
      o.offsets = recon::EstimateCameraOffsets(rig, labels, a.options);
      if (a.apply_offsets) {
        a.options.camera_offset_frames = o.offsets->Applicable();
        o.result_offsets_applied = true;
      }
    }
    o.result = recon::ReconstructSequence(rig, labels, a.options);
    bar.Break();
    if (o.result.candidates == 0)
      throw InputError(a.labels_path + ": no knot is labeled in two cameras in any of its " +
                       std::to_string(labels.frames()) + " frames: nothing to triangulate" +
                       (a.options.use_unreviewed ? ""
                                                 : " (labels still marked for review are left "
                                                   "out without --use-unreviewed)"));
    if (o.result.triangulated == 0)
      throw InputError(a.labels_path + ": none of the " + std::to_string(o.result.candidates) +
                       " knot-frames labeled in two or more cameras could be triangulated (every "
                       "one rejected as an outlier: do the labels belong to this --rig?)");

    // The tracks written, compared with the truth, reported.
    KnotTracks tracks = recon::TracksFromSequence(o.result, o.times.time_s, "netlab triangulate");
    if (!o.times.cameras.empty()) tracks.frame_time_spread_s = o.times.spread_s;
    if (o.offsets) {
      for (const recon::CameraOffset& c : o.offsets->cameras) {
        tracks.camera_offset_frames.push_back(
            c.determined ? c.offset_frames : std::numeric_limits<double>::quiet_NaN());
        tracks.camera_offset_sigma_frames.push_back(c.sigma_frames);
      }
      tracks.camera_offsets_applied = o.result_offsets_applied;
    }
    WriteOutputs(a, tracks, &o);
    if (truth) o.truth = recon::CompareWithTruth(tracks, *truth);
    o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    o.motion = recon::DetectCameraMotion(rig, labels, a.options);
    o.warnings = recon::SequenceWarnings(o.result);
    for (const std::string& w : recon::CameraMotionSentences(o.motion)) o.warnings.push_back(w);
    if (o.offsets && o.result_offsets_applied)
      for (const recon::CameraOffset& c : o.offsets->cameras)
        if (!c.determined && c.why != "no labels of this camera")
          o.warnings.push_back("the clock offset of " + c.camera +
                               " is not determined; its labels were taken at the frame time");
    if (o.result.offset_unshifted > 0)
      o.warnings.push_back(std::to_string(o.result.offset_unshifted) +
                           " labels of cameras with a clock offset have no label of their knot "
                           "in a neighbouring frame to move them by: left out");
    if (!a.quiet) PrintSummary(a, o);
    if (a.json) PrintJson(a, o);
    return 0;
  });
}

}  // namespace netlab::app
