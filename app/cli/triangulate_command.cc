// netlab triangulate --rig rig.yaml --labels LABELS --knots ROWSxCOLS --fps F --out tracks.h5
//                    [--csv PREFIX] [--ba none|points|rig] [--json]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <mutex>

#include <Eigen/Geometry>

#include "app/cli/command_line.h"
#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "calibration/rig.h"
#include "libnetsim/tracks/track_file.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/geometry/track_export.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab triangulate --rig rig.yaml --labels LABELS --knots ROWSxCOLS --fps F\n"
    "                          --out tracks.h5 [--csv PREFIX] [--ba none|points|rig] [--json]\n\n"
    "Triangulates every labeled knot in every frame from the cameras that labeled it, with\n"
    "outlier rejection, optional bundle adjustment and priors, and writes 3D knot tracks with\n"
    "their covariance (docs/triangulation.md).\n\n"
    "options:\n"
    "  --rig FILE          the calibrated cameras (netlab calibrate)\n"
    "  --labels FILE       labels.h5 (the labeling tools), or a DLTdv8-style xypts.csv whose\n"
    "                      camera C is the rig's C-th camera and point P knot P-1 in row-major\n"
    "                      order (OpenCV pixels: origin at the centre of the top-left pixel)\n"
    "  --knots ROWSxCOLS   the net's knots, e.g. 11x11\n"
    "  --fps F             frame rate: /time = frame / F\n"
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
    "  --truth FILE        knot tracks to compare with (e.g. the simulation that was rendered):\n"
    "                      RMS error as is, and after the best rigid motion (a calibrated rig\n"
    "                      has its own world frame)\n"
    "  --threads N         worker threads (default 2)\n"
    "  --quiet             no progress or summary on stderr\n"
    "  --json              print one JSON summary object on stdout as the last output:\n"
    "                      frames, points (knots per frame), triangulated (knot-frames),\n"
    "                      reprojection_rms_px, outliers, wall_s and more\n\n"
    "exit status: 0 done, 1 bad input, 2 usage error.\n";

// Linear interpolation of the truth's knot `k` at time t; false outside its time span.
bool TruthAt(const netsim::KnotTracks& truth, int k, double t, Eigen::Vector3d* p) {
  const auto& time = truth.time;
  if (time.empty() || t < time.front() - 1e-9 || t > time.back() + 1e-9) return false;
  const size_t hi = std::min<size_t>(
      time.size() - 1, std::lower_bound(time.begin(), time.end(), t) - time.begin());
  const size_t lo = hi > 0 ? hi - 1 : 0;
  if (!truth.Valid(static_cast<int>(lo), k) || !truth.Valid(static_cast<int>(hi), k)) return false;
  const double span = time[hi] - time[lo];
  const double w = span > 0 ? std::clamp((t - time[lo]) / span, 0.0, 1.0) : 0.0;
  *p = (1 - w) * truth.Position(static_cast<int>(lo), k) + w * truth.Position(static_cast<int>(hi), k);
  return true;
}

}  // namespace

int RunTriangulate(const std::vector<std::string>& args) {
  try {
    const CommandLine cl(args, {"json", "quiet", "help", "use-unreviewed"},
                         {"rig", "labels", "knots", "fps", "out", "csv", "ba", "outlier-px",
                          "sigma-px", "link-length", "link-sigma", "smooth-sigma", "rig-frames",
                          "truth", "threads", "rig-max-sigma-mm", "rig-max-sigma-deg"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    const auto start = std::chrono::steady_clock::now();
    const bool quiet = cl.Flag("quiet");
    int rows = 0, cols = 0;
    cl.Knots("knots", &rows, &cols);
    const std::string rig_path = cl.Required("rig"), labels_path = cl.Required("labels");
    const std::string out = cl.Required("out");
    const double fps = cl.DoubleOption("fps", 0.0, 1e-6, 1e7);
    if (!cl.Option("fps")) throw UsageError("--fps is required");
    recon::SequenceOptions options;
    const std::string ba = cl.Option("ba").value_or("points");
    if (!recon::ParseAdjustment(ba, &options.adjustment))
      throw UsageError("--ba expects none, points or rig, got '" + ba + "'");
    options.triangulation.outlier_threshold_px = cl.DoubleOption("outlier-px", 4.0, 0.01, 1e4);
    options.auto_threshold = !cl.Option("outlier-px");
    options.sigma_px = cl.DoubleOption("sigma-px", 0.0, 0.0, 1e3);
    options.link_length_m = cl.DoubleOption("link-length", 0.0, 0.0, 100.0);
    options.link_sigma_m = cl.DoubleOption("link-sigma", 0.002, 1e-9, 100.0);
    options.smoothness_sigma_m = cl.DoubleOption("smooth-sigma", 0.0, 0.0, 100.0);
    options.rig_frames = cl.IntOption("rig-frames", 200, 1, 1000000);
    options.rig_max_center_sigma_mm = cl.DoubleOption("rig-max-sigma-mm", 2.0, 0.0, 1e6);
    options.rig_max_rotation_sigma_deg = cl.DoubleOption("rig-max-sigma-deg", 0.02, 0.0, 360.0);
    options.threads = cl.IntOption("threads", 2, 1, 256);
    options.use_unreviewed = cl.Flag("use-unreviewed");
    if (options.adjustment == recon::Adjustment::kNone &&
        (options.link_length_m > 0 || options.smoothness_sigma_m > 0))
      throw UsageError("the priors (--link-length, --smooth-sigma) need --ba points or rig");

    const calib::Rig rig = calib::ReadRig(rig_path);
    std::vector<std::string> names;
    for (const auto& c : rig.cameras) names.push_back(c.name);
    const recon::LabelSet labels = recon::ReadLabelsAny(labels_path, rows, cols, names);
    std::optional<netsim::KnotTracks> truth;
    if (const auto truth_path = cl.Option("truth")) truth = netsim::ReadKnotTracks(*truth_path);

    std::mutex progress_mutex;
    std::string last_stage;
    int last_decile = -1;
    options.progress = [&](const std::string& stage, double fraction) {
      if (quiet) return;
      const std::lock_guard<std::mutex> lock(progress_mutex);
      const int decile = static_cast<int>(fraction * 10);
      if (stage == last_stage && decile == last_decile) return;
      last_stage = stage;
      last_decile = decile;
      std::fprintf(stderr, "%s %3d%%\n", stage.c_str(), decile * 10);
    };
    const recon::SequenceResult r = recon::ReconstructSequence(rig, labels, options);

    netsim::KnotTracks tracks;
    tracks.source = "netlab triangulate";
    for (int f : r.frame_index) tracks.time.push_back(f / fps);
    tracks.frame_index = r.frame_index;
    for (int row = 0; row < rows; ++row)
      for (int col = 0; col < cols; ++col) tracks.grid.push_back({row, col});
    tracks.position = r.position;
    tracks.valid = r.valid;
    tracks.covariance = r.covariance;
    tracks.reprojection_error_px = r.rms_px;
    tracks.camera_names = names;
    for (const auto& o : r.outliers)
      tracks.outliers.push_back({o.frame, o.knot, o.camera, o.residual_px});
    netsim::WriteKnotTracks(out, tracks);
    std::string csv_pts, csv_res;
    if (const auto prefix = cl.Option("csv")) {
      csv_pts = *prefix + "xyzpts.csv";
      csv_res = *prefix + "xyzres.csv";
      recon::WriteXyzPts(csv_pts, tracks, rows, cols);
      recon::WriteXyzRes(csv_res, tracks, rows, cols);
    }

    // Against the truth: 3D error and whether it agrees with the reported covariance.
    double truth_ss = 0.0, truth_max = 0.0, mahalanobis = 0.0, aligned_rms = 0.0;
    int64_t truth_n = 0;
    std::vector<Eigen::Vector3d> measured_points, true_points;
    if (truth) {
      for (int t = 0; t < tracks.frames(); ++t)
        for (int k = 0; k < tracks.knots(); ++k) {
          if (!tracks.Valid(t, k)) continue;
          const int tk = truth->FindKnot(tracks.grid[k][0], tracks.grid[k][1]);
          Eigen::Vector3d p;
          if (tk < 0 || !TruthAt(*truth, tk, tracks.time[t], &p)) continue;
          const Eigen::Vector3d e = tracks.Position(t, k) - p;
          measured_points.push_back(tracks.Position(t, k));
          true_points.push_back(p);
          truth_ss += e.squaredNorm();
          truth_max = std::max(truth_max, e.norm());
          const Eigen::Matrix3d& cov = tracks.covariance[static_cast<size_t>(t) * tracks.knots() + k];
          mahalanobis += e.dot(cov.ldlt().solve(e));
          ++truth_n;
        }
    }
    const double truth_rms = truth_n > 0 ? std::sqrt(truth_ss / truth_n) : 0.0;
    // A rig calibrated from a foil or markers has its own world frame; the shape of the tracks
    // is compared after the best rigid motion onto the truth (Umeyama, no scale).
    if (truth_n >= 3) {
      const Eigen::Map<const Eigen::Matrix3Xd> measured(measured_points[0].data(), 3, truth_n);
      const Eigen::Map<const Eigen::Matrix3Xd> truth_xyz(true_points[0].data(), 3, truth_n);
      const Eigen::Matrix4d m = Eigen::umeyama(measured, truth_xyz, false);
      const Eigen::Matrix3Xd moved =
          (m.topLeftCorner<3, 3>() * measured).colwise() + m.topRightCorner<3, 1>();
      aligned_rms = std::sqrt((moved - truth_xyz).colwise().squaredNorm().mean());
    }
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int64_t untriangulated = r.candidates - r.triangulated;
    std::vector<std::string> warnings;
    if (r.sigma_estimated && 4.0 * r.sigma_px > r.outlier_threshold_px)
      warnings.push_back("the labelling noise (" + std::to_string(r.sigma_px) +
                         " px) is more than a quarter of --outlier-px: good labels are being "
                         "rejected; raise --outlier-px to ~5x the noise");
    if (r.prior_disagreements > 0)
      warnings.push_back(std::to_string(r.prior_disagreements) +
                         " points seen by three or more cameras are pulled beyond the outlier "
                         "threshold by the smoothness prior: --smooth-sigma may be too small for "
                         "this motion");
    if (r.candidates > 0 && r.triangulated < 0.9 * r.candidates)
      warnings.push_back(std::to_string(untriangulated) + " of " + std::to_string(r.candidates) +
                         " knot-frames seen twice or more were not triangulated (see /outliers)");
    if (!quiet) {
      std::fprintf(stderr,
                   "%d frames x %d knots: %lld knot-frames triangulated of %lld seen twice or "
                   "more (%lld not: see /outliers), %lld seen once; reprojection RMS %.3f px; "
                   "%zu outlier observations (threshold %.2f px); sigma %.3f px%s; --ba %s; "
                   "%.1f s\n",
                   labels.frames(), rows * cols, static_cast<long long>(r.triangulated),
                   static_cast<long long>(r.candidates), static_cast<long long>(untriangulated),
                   static_cast<long long>(r.single_view), r.reprojection_rms_px, r.outliers.size(),
                   r.outlier_threshold_px, r.sigma_px, r.sigma_estimated ? " (estimated)" : "", ba.c_str(), wall_s);
      if (options.link_length_m > 0)
        std::fprintf(stderr, "link-length prior moved the points %.3f mm RMS (max %.3f mm)\n",
                     r.link_shift_rms_m * 1e3, r.link_shift_max_m * 1e3);
      if (options.smoothness_sigma_m > 0)
        std::fprintf(stderr,
                     "smoothness prior moved the points %.3f mm RMS (max %.3f mm); %lld two-view "
                     "points at odds with their tracks left out\n",
                     r.smoothness_shift_rms_m * 1e3, r.smoothness_shift_max_m * 1e3,
                     static_cast<long long>(r.track_outliers));
      if (options.adjustment == recon::Adjustment::kRig) {
        std::fprintf(stderr, "rig %s on %d frames (RMS %.3f -> %.3f px)\n",
                     r.rig_adjusted ? "adjusted"
                                    : "NOT adjusted: the sequence does not determine it; the "
                                      "calibrated rig was kept",
                     r.rig_frames_used, r.rig_rms_before_px, r.rig_rms_after_px);
        for (size_t c = 1; c < r.rig_center_change_mm.size(); ++c)
          std::fprintf(stderr, "  %s: %s %.3f mm (sigma %.3f), %.4f deg (sigma %.4f)\n",
                       rig.cameras[c].name.c_str(), r.rig_adjusted ? "moved" : "would move",
                       r.rig_center_change_mm[c], r.rig_center_sigma_mm[c],
                       r.rig_rotation_change_deg[c], r.rig_rotation_sigma_deg[c]);
      }
      if (truth)
        std::fprintf(stderr,
                     "against the truth: %.3f mm RMS (max %.3f mm) over %lld points; %.3f mm "
                     "RMS after the best rigid motion (for a rig in its own world frame)\n",
                     truth_rms * 1e3, truth_max * 1e3, static_cast<long long>(truth_n),
                     aligned_rms * 1e3);
      for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
      std::fprintf(stderr, "written %s%s%s\n", out.c_str(),
                   csv_pts.empty() ? "" : (", " + csv_pts + ", " + csv_res).c_str(), "");
    }
    if (cl.Flag("json")) {
      JsonWriter json;
      json.BeginObject();
      json.Key("frames").Int(labels.frames());
      json.Key("points").Int(rows * cols);
      json.Key("triangulated").Int(r.triangulated);
      json.Key("candidates").Int(r.candidates);
      json.Key("two_view").Int(r.two_view);
      json.Key("untriangulated").Int(untriangulated);
      json.Key("single_view").Int(r.single_view);
      json.Key("unreviewed_skipped").Int(r.unreviewed_skipped);
      json.Key("reprojection_rms_px").Number(r.reprojection_rms_px);
      json.Key("outliers").Int(static_cast<int64_t>(r.outliers.size()));
      json.Key("sigma_px").Number(r.sigma_px);
      json.Key("sigma_estimated").Bool(r.sigma_estimated);
      json.Key("outlier_threshold_px").Number(r.outlier_threshold_px);
      json.Key("ba").String(ba);
      if (options.link_length_m > 0) {
        json.Key("link_prior_shift_rms_m").Number(r.link_shift_rms_m);
        json.Key("link_prior_shift_max_m").Number(r.link_shift_max_m);
      }
      if (options.smoothness_sigma_m > 0) {
        json.Key("track_outliers").Int(r.track_outliers);
        json.Key("prior_disagreements").Int(r.prior_disagreements);
        json.Key("smoothness_prior_shift_rms_m").Number(r.smoothness_shift_rms_m);
        json.Key("smoothness_prior_shift_max_m").Number(r.smoothness_shift_max_m);
      }
      if (options.adjustment == recon::Adjustment::kRig) {
        json.Key("rig_adjusted").Bool(r.rig_adjusted);
        json.Key("rig_frames").Int(r.rig_frames_used);
        json.Key("rig_rms_before_px").Number(r.rig_rms_before_px);
        json.Key("rig_rms_after_px").Number(r.rig_rms_after_px);
        json.Key("rig_center_change_mm").BeginArray();
        for (double v : r.rig_center_change_mm) json.Number(v);
        json.EndArray();
        json.Key("rig_rotation_change_deg").BeginArray();
        for (double v : r.rig_rotation_change_deg) json.Number(v);
        json.EndArray();
        json.Key("rig_center_sigma_mm").BeginArray();
        for (double v : r.rig_center_sigma_mm) json.Number(v);
        json.EndArray();
        json.Key("rig_rotation_sigma_deg").BeginArray();
        for (double v : r.rig_rotation_sigma_deg) json.Number(v);
        json.EndArray();
      }
      if (truth) {
        json.Key("truth_points").Int(truth_n);
        json.Key("truth_rms_m").Number(truth_rms);
        json.Key("truth_max_m").Number(truth_max);
        json.Key("truth_aligned_rms_m").Number(aligned_rms);
        json.Key("truth_mean_mahalanobis2").Number(truth_n > 0 ? mahalanobis / truth_n : 0.0);
      }
      json.Key("warnings").BeginArray();
      for (const std::string& w : warnings) json.String(w);
      json.EndArray();
      json.Key("triangulate_s").Number(r.triangulate_s);
      json.Key("adjust_s").Number(r.adjust_s);
      json.Key("wall_s").Number(wall_s);
      json.EndObject();
      std::cout << json.str() << std::endl;
    }
    return 0;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "netlab triangulate: %s\n(see netlab triangulate --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "netlab triangulate: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace netlab::app
