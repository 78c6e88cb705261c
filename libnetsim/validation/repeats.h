#pragma once
// Repeated shots of one case scored together: `netlab score --measured a.h5,b.h5,c.h5`
// (docs/score.md, "Repeats"). Each shot is scored on its own by Score (its own time offset and,
// when asked, its own rigid alignment); then
//
// - the pooled test: Fisher's combination of the shots' own tests. The shots are independent,
//   so under "the simulation is right" their p-values are independent and uniform, and
//   F = -2 sum_i ln p_i ~ chi^2(2 S) over S shots; p = P(chi^2(2 S) >= F). A shot the model
//   misses rejects the pool however well the others fit (a sum of the shots' scaled chi^2 weighs
//   each by its correlation inflation, and let a shot of uncorrelated noise with too large
//   covariances outvote two the model missed: repeats_test). The pooled mean d2 is
//   sum_i sum d2_i / sum_i N_i, dof = sum_i nu_i; the critical mean d2 is the pooled mean d2 at
//   which p reaches the significance when every shot's sum d2 is scaled alike;
// - the spread between the repeats, the experiment's reproducibility: at the first shot's frames,
//   simulated time s = t + tau_0; every shot's measured knot at s (its own measured time s -
//   tau_i, with tau_i its fitted offset moved to where the shot lies closest to the first shot,
//   so that a model whose error grows over the flight does not set the shots apart; interpolated
//   linearly between its two measured frames around it, both informative), carried into the
//   simulation's frame by its own rigid alignment (x = R_i^T (x_meas - t_i)). Where n >= 2 shots
//   have the knot, their mean x_bar; the spread of a set of knot-frames is sqrt(sum |x_i - x_bar|^2
//   / sum (n - 1)): the RMS distance (3-D) of one shot from the mean of infinitely many, unbiased
//   in the count of shots. Interpolating between two frames with weights 1 - f and f averages their
//   noise: the variance it removes, f (1 - f) tr(C_a + C_b) by the stated covariances (3
//   meas_sigma^2 each without), is added back ((n - 1) / n of it, as the sum above takes), so
//   measurement noise of sigma per axis alone gives sqrt(3) sigma whatever fraction of a frame the
//   shots' offsets differ by. Given per phase (the first shot's phases), per knot class, and over
//   all.

#include <array>
#include <string>
#include <vector>

#include "common/tracks/track_file.h"
#include "libnetsim/validation/score.h"

namespace netlab::netsim {

// The spread of a set of knot-frames (a phase, a knot class, all).
struct SpreadRow {
  std::string name;
  int points = 0;      // knot-frames where 2 or more shots have the knot
  double rms_m = 0.0;  // the spread, m (NaN when points == 0)
  // Beside it, the model's error over the same phase or class: the RMS of every shot's
  // informative points there, m (NaN when none).
  double error_rms_m = 0.0;
  double start_s = 0.0;  // phases: the simulated time span [start_s, end_s)
  double end_s = 0.0;
};

struct RepeatsSummary {
  std::vector<std::string> names;  // the measured files, in the order given
  // The pooled test over all shots.
  int points = 0;               // knot-frames compared, all shots
  double rms_m = 0.0;           // RMS error over every shot's informative points, m
  double mean_d2 = 0.0;         // sum of all d2 / points
  double dof = 0.0;             // sum of the shots' nu
  double effective_points = 0;  // sum of the shots' N / c
  double scaled_d2 = 0.0;       // sum of the shots' sum d2 / c
  double effective_dof = 0.0;   // sum of the shots' nu / c
  double p_value = 1.0;
  double critical_mean_d2 = 0.0;
  double margin = 0.0;  // critical_mean_d2 - mean_d2 (negative: rejected)
  Verdict verdict = Verdict::kInconsistent;
  // The spread between the shots.
  SpreadRow spread;                           // over every knot-frame
  std::vector<SpreadRow> spread_per_phase;    // ejection, spreading, opened, contact
  std::array<SpreadRow, 3> spread_per_class;  // kKnotClassNames order
  // Each shot's clock against the first shot's as the spread aligns them, s (t_first = t_i +
  // offset at the same moment of the flight; 0 for the first shot).
  std::vector<double> spread_time_offset_s;
};

struct RepeatsResult {
  std::vector<ScoreResult> shots;  // one per measured file, as Score gives it
  RepeatsSummary summary;
  // The first shot's result with the test's fields (mean_d2, dof, effective_points, p_value,
  // critical_mean_d2, margin, verdict, covariance_too_large) replaced by the pooled ones: what
  // score.h5's root, the JSON's top level and the report's verdict show.
  ScoreResult combined;
};

// Refuses repeats of different nets: every shot must list the first shot's knots (net, row, col)
// in the same order. Throws InputError naming both files and the first knot that differs.
void CheckSameNet(const std::vector<const KnotTracks*>& measured,
                  const std::vector<std::string>& names);

// Scores every shot against `sim` and pools them. Throws as Score does (naming the shot's file,
// e.g. a shot whose time does not overlap the simulation) and as CheckSameNet.
RepeatsResult ScoreRepeats(const std::vector<const KnotTracks*>& measured,
                           const std::vector<std::string>& names, const KnotTracks& sim,
                           const ScoreOptions& options, const std::string& sim_name = "simulation");

// The pooled test and the spread of already scored shots (their measured tracks beside them).
RepeatsSummary PoolRepeats(const std::vector<const KnotTracks*>& measured,
                           const std::vector<std::string>& names,
                           const std::vector<ScoreResult>& shots, const ScoreOptions& options);

}  // namespace netlab::netsim
