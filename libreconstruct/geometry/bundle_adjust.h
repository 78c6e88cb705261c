#pragma once
// 3D knot tracks from 2D labels over a whole sequence: triangulation of every knot in every
// frame (triangulation.h), then optionally a bundle adjustment with Ceres.
//
// Adjustment modes:
//   kNone    per-point triangulation only (linear + nonlinear refinement, outliers).
//   kPoints  the points, with the switchable priors below, the cameras as calibrated.
//   kRig     first the cameras' extrinsics over the sequence (intrinsics fixed; rig_refinement.h):
//            the cameras are bolted to one frame, so each keeps one pose for the whole sequence;
//            the gauge is fixed explicitly by holding the reference camera (the rig's first) and
//            the distance from it to the second camera (the scale); refined on up to `rig_frames`
//            frames spread over the sequence, then every point is triangulated again with the
//            new rig. The new rig is adopted only if the sequence determines it (camera centres
//            and rotations to the given standard deviations): a small or flat net at one place
//            trades a camera's position against its turn, and such a rig would spoil every point.
//
// Priors (kPoints / kRig; each switchable, each reported by how far it moved the points):
//   link length   |p_a - p_b| = link_length_m, sigma link_sigma_m, for adjacent knots in a frame
//                 (the thread barely stretches);
//   smoothness    p[t-1] - 2 p[t] + p[t+1] = 0, sigma smoothness_sigma_m, for each knot in
//                 consecutive frames (bounded acceleration: sigma ~ a dt^2).
// The link prior couples the knots of a frame only and is solved frame by frame; smoothness
// couples one knot's frames only and is solved knot by knot; with both, the two are alternated
// (block coordinate descent, until a sweep moves the points less than prior_tolerance_m RMS or
// after prior_sweeps), each holding the other's neighbours at their current values.
//
// Uncertainty: sigma^2 (J^T J)^-1 per point, J the inlier reprojection Jacobian, sigma the given
// pixel noise or the one estimated from all residuals (sum r^2 / (2 n_obs - 3 n_points)). With
// priors, their terms at the point are added with its neighbours held fixed: the conditional
// covariance, a slight underestimate of the marginal one.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "common/progress.h"
#include "libreconstruct/geometry/triangulation.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::recon {

enum class Adjustment { kNone, kPoints, kRig };

// "none", "points", "rig"; false (and *mode untouched) otherwise.
bool ParseAdjustment(const std::string& name, Adjustment* mode);

struct SequenceOptions {
  // Per-point triangulation. With auto_threshold its outlier threshold and Huber scale follow
  // the labelling noise: outlier_sigmas x sigma (at least min_threshold_px) and 2 sigma, sigma
  // being sigma_px when given, else estimated robustly (median residual) from a first pass with
  // the fixed threshold. A fixed 4 px let a 26 px mislabel in a far camera pass at 0.3 px noise:
  // the point moved 2.5 cm along the near pair's depth and every view stayed within 4 px.
  TriangulationOptions triangulation;
  bool auto_threshold = true;
  double outlier_sigmas = 5.0;
  double min_threshold_px = 0.5;
  Adjustment adjustment = Adjustment::kPoints;
  double sigma_px = 0.0;       // labelling noise for the covariances; 0: estimated
  double link_length_m = 0.0;  // > 0: link-length prior on
  double link_sigma_m = 0.002;
  double smoothness_sigma_m = 0.0;  // > 0: smoothness prior on
  int prior_sweeps = 4;             // at most; with both priors on
  double prior_tolerance_m = 2e-5;  // a sweep moving the points less than this (RMS) ends them
  int rig_frames = 200;
  // kRig: the adjusted rig is adopted only when the sequence determines every camera this well
  // (standard deviations); otherwise the calibrated rig is kept (rig_adjusted false).
  double rig_max_center_sigma_mm = 2.0;
  double rig_max_rotation_sigma_deg = 0.02;
  int threads = 2;
  // Labels in state "needs review" are left out unless this is set.
  bool use_unreviewed = false;
  // A triangulated point whose largest standard deviation (the square root of its covariance's
  // largest eigenvalue) exceeds the bound is degenerate: its rays meet too close to parallel (or
  // anti-parallel) to place it. It is kept out of the valid points and reported with the reason.
  // The bound is max_sigma_m when > 0, else degenerate_sigma_factor x the median over the
  // sequence's points.
  double max_sigma_m = 0.0;
  double degenerate_sigma_factor = 10.0;
  // Per rig camera: its sub-frame clock offset in frames (its frame t is exposed at frame time
  // t + offset). Empty, or all zero: the cameras are taken as simultaneous. Otherwise every
  // label of a camera with a non-zero offset is moved to the frame time along its own 2D track
  // (CameraOffsets, camera_offsets.h) before triangulation.
  std::vector<double> camera_offset_frames;
  // Stages "knot-frames triangulated", "rig stages" (of 2), "smoothness prior" and "link prior"
  // (no count), "sweeps of both priors", from the calling thread or the workers (the callback
  // must be thread-safe); a cancel stops the workers between chunks and throws Cancelled.
  ProgressReporter progress;
};

struct ObservationOutlier {
  int frame = 0;             // frame number (labels' frame_index)
  int knot = 0;              // row * cols + col
  int camera = 0;            // index into the rig
  double residual_px = 0.0;  // NaN where the point was not triangulated at all
};

// A triangulated point left out as degenerate (SequenceOptions::max_sigma_m).
struct DegeneratePoint {
  int frame = 0;         // frame number (labels' frame_index)
  int knot = 0;          // row * cols + col
  double sigma_m = 0.0;  // its largest standard deviation, m
  // The angle (0..180 deg) at which its two best-crossing rays meet at the point: near 0 the
  // cameras look along one line, near 180 they face each other across it.
  double ray_angle_deg = 0.0;
  std::string reason;  // one sentence: the cameras, the angle, sigma against the bound
};

struct SequenceResult {
  int rows = 0, cols = 0;
  std::vector<int> frame_index;             // [T]
  std::vector<Eigen::Vector3d> position;    // [T*K] m, world frame
  std::vector<uint8_t> valid;               // [T*K]
  std::vector<Eigen::Matrix3d> covariance;  // [T*K] m^2
  std::vector<double> rms_px;  // [T*K] RMS inlier reprojection residual, NaN if invalid
  std::vector<ObservationOutlier> outliers;
  // Degenerate points: valid 0, their position and covariance kept (degenerate[i] = 1).
  std::vector<uint8_t> degenerate;  // [T*K]
  std::vector<DegeneratePoint> degenerate_points;
  double max_sigma_m = 0.0;     // the bound used
  std::string max_sigma_from;   // "given" or "10 x the median sigma (0.43 mm)"
  double median_sigma_m = 0.0;  // over the points before the degenerate were taken out
  // Labels of a camera with a clock offset that could not be moved to the frame time (no label
  // of the knot in a neighbouring frame of that camera): left out.
  int64_t offset_unshifted = 0;
  calib::Rig rig;  // as given, or refined (kRig)

  int64_t candidates = 0;    // knot-frames with two or more views
  int64_t triangulated = 0;  // of those, valid (degenerate points not counted)
  int64_t two_view = 0;      // of those, from exactly two views: a mislabel along the epipolar
                             // line cannot be seen in them (the smoothness prior can)
  int64_t single_view = 0;   // knot-frames with exactly one view (left out)
  int64_t unreviewed_skipped = 0;
  // Labels placed from the other cameras' (LabelSource::kProjected): they repeat those views,
  // and are left out.
  int64_t projected_skipped = 0;
  double reprojection_rms_px = 0.0;  // over every inlier observation
  double sigma_px = 0.0;             // used for the covariances
  bool sigma_estimated = false;
  double outlier_threshold_px = 0.0;  // the threshold the triangulation used
  double robust_sigma_px = 0.0;       // the first pass's robust noise estimate (auto threshold)
  // How far each prior moved the points (RMS and max over valid points, m); 0 when off.
  double link_shift_rms_m = 0.0, link_shift_max_m = 0.0;
  double smoothness_shift_rms_m = 0.0, smoothness_shift_max_m = 0.0;
  // Smoothness prior: two-view points at odds with their track, left out (their views are in
  // `outliers`), and points seen three or more times that the prior pulls beyond the outlier
  // threshold from their labels (kept; the prior may be too stiff for the motion).
  int64_t track_outliers = 0, prior_disagreements = 0;
  // Both priors: sweeps of the block coordinate descent and the RMS change of the last one.
  int prior_sweeps_done = 0;
  double prior_sweep_change_rms_m = 0.0;
  // kRig: the cameras' change (per camera: rotation deg, centre mm) and the RMS before / after
  // on the frames used.
  std::vector<double> rig_rotation_change_deg, rig_center_change_mm;
  std::vector<double> rig_rotation_sigma_deg, rig_center_sigma_mm;  // their uncertainty
  bool rig_adjusted = false;  // the adjusted rig was adopted (well determined)
  double rig_rms_before_px = 0.0, rig_rms_after_px = 0.0;
  int rig_frames_used = 0;
  double triangulate_s = 0.0, adjust_s = 0.0;
};

// The per-point triangulation options for labels of `sigma_px` px of noise, as auto_threshold
// sets them: options.triangulation with the outlier threshold outlier_sigmas x sigma (at least
// min_threshold_px) and the Huber scale 2 sigma (at least 0.4 min_threshold_px).
TriangulationOptions TriangulationForNoise(const SequenceOptions& options, double sigma_px);

// Throws netlab::InputError when the labels use a camera the rig lacks (naming it).
SequenceResult ReconstructSequence(const calib::Rig& rig, const LabelSet& labels,
                                   const SequenceOptions& options);

// What the user of a reconstruction should know and may act on, one sentence each (none when
// all is well): the estimated labelling noise is more than a quarter of the outlier threshold
// (good labels are being rejected); points of three or more views are pulled beyond the
// threshold by the smoothness prior (prior_disagreements); fewer than 90 % of the knot-frames
// seen twice or more were triangulated. The sentences name `netlab triangulate`'s options
// (--outlier-px, --smooth-sigma).
std::vector<std::string> SequenceWarnings(const SequenceResult& result);

}  // namespace netlab::recon
