#pragma once
// Scoring a simulation against measured knot tracks: the paper's validation step (sec. 4.1,
// "weighted sum of squared distances between simulated and measured trajectories of all the
// knots"), made a statistical test. The engine behind `netlab score` (docs/score.md).
//
// For every knot k and measured frame t with a valid measurement:
//   r_tk  = p_meas(t, k) - meas_from_sim * p_sim(t + tau, k)                   [m, measured frame]
//   d2_tk = r_tk^T (Sigma_meas + R Sigma_sim R^T + sigma_interp^2 I)^-1 r_tk   [1]
// p_sim(t + tau) is the cubic (4-point Lagrange) interpolant of the stored simulation frames at the
// measured time shifted by the fitted offset tau (the shot's launch is not the simulation's
// t = 0); sigma_interp its estimated error (from the 4th divided difference, h^4 |p''''| / 24
// scale). meas_from_sim is a rigid transform (x_in_meas = R x_in_sim + t), identity unless fitted.
// Missing measurements (valid = 0) are masked, never filled. Sigma_sim is the simulation's own
// uncertainty (a dt/discretisation study, /knots/covariance of the simulation file, or an
// isotropic sigma); zero when none is given, and the summary says so.
//
// Consistency: under the hypothesis "the simulation is right and Sigma is the measurement's
// uncertainty", sum d2 ~ chi^2(nu), nu = 3 N - p (N knot-frames, p fitted parameters: 1 for the
// time offset, 6 for the rigid transform). Measured errors are correlated in time (smoothing
// priors, the same camera poses in every frame) and across the knots of a frame, so the variance
// of sum d2 is inflated by the integrated autocorrelation time of the d2 series (Sokal's automatic
// window) times the within-frame design effect; the scaled chi^2 of that inflation c
// (sum d2 / c ~ chi^2(nu / c), Satterthwaite) gives the p-value, i.e. an effective sample size
// N / c. The verdict is "consistent" when p >= significance.
//
// Errors in millimetres (RMS, maximum, per knot, class, phase and frame, the corner polygon and
// the centroid) are over the informative points only: a measured point whose own standard
// deviation (the square root of its covariance's largest eigenvalue) exceeds a bound (given, or
// 10 x the median over the compared points) says nothing about the model in millimetres; d2
// weighs it by its covariance, so it stays in the test. Points the triangulation flagged
// degenerate (/knots/degenerate) are not measured: masked, and counted apart. Beside the RMS, a
// covariance-weighted RMS (each point weighed by 1 / its mean variance) for tracks whose points
// differ strongly in sigma.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/tracks/track_file.h"

namespace netlab::netsim {

enum class Alignment { kNone, kTime, kRigid, kTimeAndRigid };
// "none" | "time" | "rigid" | "time+rigid"; false for anything else.
bool ParseAlignment(const std::string& text, Alignment* alignment);
std::string AlignmentName(Alignment alignment);
// Whether an alignment fits the time offset (time, time+rigid) or the rigid motion (rigid,
// time+rigid).
bool FitsTime(Alignment alignment);
bool FitsRigid(Alignment alignment);

// The consistency test's answer: consistent when its p-value is at least the significance.
enum class Verdict { kConsistent, kInconsistent };
std::string VerdictName(Verdict verdict);  // "consistent" | "inconsistent"

// Where the contact phase's start came from: the given time of first contact, the simulation's
// own first contact with the target, or nowhere (no contact phase).
enum class ContactFrom { kNone, kGiven, kSimulation };
std::string ContactFromName(ContactFrom from);  // "none" | "given" | "simulation"

enum class KnotClass { kCorner = 0, kEdge = 1, kInner = 2 };  // 2, 3, 4 links
inline constexpr const char* kKnotClassNames[3] = {"corner", "edge", "inner"};

struct ScoreOptions {
  Alignment alignment = Alignment::kTime;
  // s. t_sim = t_meas + time_offset_s: the fixed offset when the time is not fitted, the centre
  // of the search otherwise.
  double time_offset_s = 0.0;
  // s. The fitted offset is searched in time_offset_s +- this (36 frames at 179 fps: a launch
  // trigger is known to a few frames).
  double max_time_offset_s = 0.2;
  // Isotropic standard deviation of the simulation's positions, m, used when the simulation file
  // has no /knots/covariance (a dt/discretisation study: docs/benchmarks.md). 0: Sigma_sim = 0.
  double sim_sigma_m = 0.0;
  // Isotropic measurement standard deviation, m, used only when the measured file has no
  // /knots/covariance. 0: such a file is an error (there is nothing to weight by).
  double meas_sigma_m = 0.0;
  // Test level: the verdict is "inconsistent" when the p-value is below it.
  double significance = 0.01;
  // s, simulated time of first contact with the target (starts the "contact" phase); NaN: the
  // simulation's own first contact (netlab simulate stores it), or no contact phase without one.
  double contact_time_s = std::numeric_limits<double>::quiet_NaN();
  // The simulation's output is "too sparse" when its interpolation error (RMS) exceeds this
  // fraction of the measurement's RMS standard deviation.
  double max_interpolation_fraction = 0.1;
  // m: a compared point whose largest measurement sigma exceeds this is left out of the errors
  // in millimetres (not of d2). 0: informative_sigma_factor x the median over compared points.
  double max_sigma_m = 0.0;
  double informative_sigma_factor = 10.0;

  bool IsValid(std::string* error) const;
};

// One row of the per-knot, per-class or per-phase tables.
struct ScoreRow {
  std::string name;
  int points = 0;        // knot-frames compared
  int left_out = 0;      // of those, not informative: out of rms_m and max_m (not of mean_d2)
  double rms_m = 0.0;    // RMS of |r| over the informative points, m (NaN when none)
  double max_m = 0.0;    // largest |r| of those, m
  double mean_d2 = 0.0;  // mean d2 (expected 3 when consistent)
  double start_s = 0.0;  // phases: measured time span [start_s, end_s)
  double end_s = 0.0;
  // Phases: the two parts of the expected |r|, sqrt of the mean trace of each covariance over the
  // compared points, m: the simulation's (Sigma_sim, an ensemble's spread) and the measurement's.
  double sigma_sim_m = 0.0;
  double sigma_meas_m = 0.0;
};

struct ScoreSummary {
  // Sizes.
  int frames = 0;  // measured frames with at least one compared knot
  int knots = 0;
  int points = 0;      // knot-frames compared
  int masked = 0;      // measured knot-frames not compared (invalid, or outside the simulation)
  int degenerate = 0;  // of the masked, flagged degenerate by the triangulation
  // The informative points: the compared ones whose largest sigma is within the bound.
  int left_out = 0;                   // compared points beyond it: in d2, not in the errors below
  double sigma_bound_m = 0.0;         // the bound
  std::string sigma_bound_from;       // "given", or "10 x the median sigma (0.12 mm)"
  double median_sigma_m = 0.0;        // over the compared points
  double left_out_max_sigma_m = 0.0;  // the largest sigma left out (0: none)
  double left_out_max_error_m = 0.0;  // the largest error left out (0: none)
  // Errors over the informative points, measured frame.
  double rms_m = 0.0;
  double rms_percent_of_side = 0.0;  // of the net's side (largest corner-to-corner edge at t0)
  double max_m = 0.0;
  double side_m = 0.0;
  // sqrt(sum w |r|^2 / sum w), w = 3 / trace of the point's total covariance, over every
  // compared point; and the spread of the informative points' sigma (90th / 10th percentile):
  // above 2 the weighted RMS is given beside the RMS in the headline.
  double weighted_rms_m = 0.0;
  double sigma_spread = 1.0;
  // One sentence: the RMS and maximum, over how many points, how many were left out and why.
  std::string headline;
  // The consistency test.
  double mean_d2 = 0.0;
  double dof = 0.0;             // nu = 3 N - p
  int fitted_parameters = 0;    // p
  double tau_int = 1.0;         // integrated autocorrelation time of d2, frames
  double design_effect = 1.0;   // within-frame inflation
  double effective_points = 0;  // N / (tau_int * design_effect)
  double p_value = 1.0;
  double critical_mean_d2 = 0;  // mean d2 above which the verdict is kInconsistent
  double margin = 0.0;          // critical_mean_d2 - mean_d2 (negative: rejected)
  Verdict verdict = Verdict::kInconsistent;
  bool covariance_too_large = false;  // lower tail also below significance: Sigma looks inflated
  // The time alignment.
  Alignment alignment = Alignment::kTime;
  double time_offset_s = 0.0;
  double time_offset_sigma_s = 0.0;  // 0 when not fitted
  // The space alignment, meas_from_sim (identity unless fitted).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // m
  // Covariance of (rotation vector [rad], translation [m]) of a left perturbation, 6x6.
  Eigen::Matrix<double, 6, 6> rigid_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  // The simulation's sampling.
  double sim_interval_s = 0.0;
  double meas_interval_s = 0.0;
  double interpolation_rms_m = 0.0;  // estimated error of the cubic interpolation
  bool sim_too_sparse = false;
  std::string sim_uncertainty;  // "zero", "isotropic 0.5 mm", "from /knots/covariance"
  int ensemble_members = 0;     // runs whose spread is Sigma_sim (0: no ensemble)
  // Skill against a naive baseline: every knot in straight-line flight from its simulated
  // position and velocity at the first compared time (no forces: the corner masses' ballistic
  // flight in microgravity). 1 - sum d2 / sum d2_baseline; 1 perfect, 0 no better, < 0 worse.
  double skill = 0.0;
  double baseline_rms_m = 0.0;
  // Tables.
  std::array<ScoreRow, 3> per_class;  // kKnotClassNames order
  std::vector<ScoreRow> per_knot;     // [K], name "(row,col)"
  std::vector<ScoreRow> per_phase;    // ejection, spreading, opened, contact
  // Global measures (measured vs simulated).
  // Simulated time the contact phase starts at (NaN: no contact phase), and whence: kGiven
  // (ScoreOptions::contact_time_s), kSimulation (its first contact, /contact_start) or kNone.
  double contact_time_s = std::numeric_limits<double>::quiet_NaN();
  ContactFrom contact_from = ContactFrom::kNone;
  double max_area_measured_m2 = 0.0, max_area_time_measured_s = 0.0;  // NaN: never measured
  double max_area_simulated_m2 = 0.0, max_area_time_simulated_s = 0.0;
  std::vector<std::string> notes;  // what a reader must know (Sigma_sim zero, sparse output...)
  // The files the score was written to (score.h5, the HTML report; empty: none), for the JSON.
  std::string output_path, report_path;
  double wall_s = 0.0;

  // The text summary, a few lines (its fields and words: summary_fields.h).
  std::string BriefReport() const;
};

// Everything per frame and knot, for score.h5 and the report. Arrays are frame-major [T*K] over
// the measured frames; masked entries are NaN.
struct ScoreResult {
  ScoreSummary summary;
  std::vector<double> time;               // [T] measured time, s
  std::vector<std::array<int, 2>> grid;   // [K]
  std::vector<int> knot_class;            // [K] KnotClass
  std::vector<Eigen::Vector3d> residual;  // [T*K] m, measured frame
  std::vector<double> d2;                 // [T*K]
  std::vector<uint8_t> compared;          // [T*K] 1 where r and d2 are defined
  std::vector<uint8_t> informative;       // [T*K] 1 where compared and within the sigma bound
  std::vector<double> sim_var, meas_var;  // [T*K] m^2, trace of Sigma_sim / Sigma_meas (NaN: not
                                          // compared)
  std::vector<std::array<double, 3>> rms_per_class;   // [T] m, NaN where a class has no point
  std::vector<double> area_measured, area_simulated;  // [T] corner polygon, m^2 (NaN: a corner
                                                      // is missing)
  std::vector<Eigen::Vector3d> centroid_measured, centroid_simulated;  // [T] over compared knots
  std::vector<std::array<double, 6>> corner_distance_measured;         // [T] 01 12 23 30 02 13, m
  std::vector<std::array<double, 6>> corner_distance_simulated;
  // d2 histogram: bin edges [B+1], counts [B], chi^2_3 expected counts [B].
  std::vector<double> d2_edges, d2_counts, d2_expected;
};

// One measured knot-frame that can be compared, with its checked covariance.
struct ComparedPoint {
  int frame, knot;
  Eigen::Matrix3d meas_cov;  // m^2
};

// What Score compares, checked as Score checks it: the measured points (valid, finite, their
// covariance symmetric positive definite or the isotropic meas_sigma_m) and the simulation's index
// of every measured knot. `netlab fit` weighs its residuals by the same. Throws as Score does.
struct Comparison {
  std::vector<ComparedPoint> points;
  std::vector<int> sim_knot;  // [K measured]
  int masked = 0;             // measured knot-frames not valid
};
Comparison PrepareComparison(const KnotTracks& measured, const KnotTracks& sim,
                             const ScoreOptions& options,
                             const std::string& measured_name = "measured",
                             const std::string& sim_name = "simulation");

// Scores `sim` against `measured`. The file names are for error messages. Throws
// std::invalid_argument naming the file, dataset, frame and knot on bad input: different nets
// (grid mismatch), no overlap in time, NaN, a covariance that is not symmetric positive definite.
ScoreResult Score(const KnotTracks& measured, const KnotTracks& sim, const ScoreOptions& options,
                  const std::string& measured_name = "measured",
                  const std::string& sim_name = "simulation");

// Upper regularized incomplete gamma Q(a, x) and the chi^2 quantile: P(chi2_nu >= x) = Q(nu/2,
// x/2). Exposed for tests.
double UpperGammaQ(double a, double x);
double Chi2Quantile(double p, double nu);  // x with P(chi2_nu <= x) = p

}  // namespace netlab::netsim
