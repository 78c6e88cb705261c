#pragma once
// score.h5: what `netlab score` found, for plots and further analysis (docs/score.md lists every
// dataset). Every dataset has a "units" attribute; masked knot-frames are NaN.
//
//   /time                          [T]       s     measured time of each row
//   /residual                      [T,K,3]   m     measured - simulated, measured frame
//   /d2                            [T,K]     1     Mahalanobis distance squared
//   /compared                      [T,K]     1     1 where residual and d2 are defined
//   /informative                   [T,K]     1     1 where compared and its sigma within the
//                                                  bound: the points the errors in m are over
//   /knots/grid                    [K,2]           (row, col)
//   /knots/class                   [K]             0 corner, 1 edge, 2 inner
//   /knots/rms_m, max_m, mean_d2, points   [K]     per knot
//   /per_class/{rms_m,max_m,mean_d2,points} [3]    corner, edge, inner (attribute "names")
//   /per_phase/{rms_m,max_m,mean_d2,points,start_s,end_s} [4]  (attribute "names")
//   /error_vs_time/rms_m           [T,3]     m     RMS per class and frame
//   /global/corner_area_{measured,simulated}        [T]    m^2
//   /global/centroid_{measured,simulated}           [T,3]  m
//   /global/corner_distance_{measured,simulated}    [T,6]  m  (corners 01 12 23 30 02 13)
//   /d2_histogram/{edges [B+1], counts [B], expected [B]}  chi^2_3 expectation
//   /alignment/{time_offset_s, time_offset_sigma_s [1], rotation [3,3], translation [3],
//               covariance [6,6] (rotation vector rad, translation m)}  meas_from_sim
//   /summary/<field>               [1]       the --json fields, units as attributes
// Root attributes: format = "netlab-score", version = "1", verdict, alignment, notes.
//
// With repeats (several measured files, repeats.h) everything above is the first shot's, except
// the test (root attribute verdict; /summary/{mean_d2, dof, effective_points, p_value,
// critical_mean_d2, margin, verdict}), which is pooled; and
//   /repeats                       attribute names: the measured files, one a line
//   /repeats/pooled/{points, rms_m, mean_d2, dof, effective_points, p_value, critical_mean_d2,
//                    margin} [1]   attribute verdict
//   /repeats/shots/{time_offset_s, time_offset_sigma_s, spread_time_offset_s, mean_d2, dof,
//                   p_value, rms_m, max_m, points} [S]    one row per shot; attributes names,
//                   verdicts (spread_time_offset_s: its clock against the first shot's, as the
//                   spread aligns them)
//   /repeats/shot_<i>/{per_class/*, per_phase/*}   shot i's tables, as /per_class, /per_phase
//   /repeats/shot_<i>/alignment/{time_offset_s, time_offset_sigma_s [1], rotation, translation}
//                                  attributes name, verdict
//   /repeats/spread/{rms_m, points} [1]            the spread between the shots, all knot-frames
//   /repeats/spread/per_phase/{rms_m, points, start_s, end_s} [4]  (simulated time)
//   /repeats/spread/per_class/{rms_m, points} [3]  corner, edge, inner (attribute "names")

#include <string>

#include "libnetsim/validation/score.h"

namespace netlab::netsim {

inline constexpr char kScoreFileFormat[] = "netlab-score";

struct RepeatsResult;

// Writes `result` to `path` via "<path>.partial" and a rename. Throws std::runtime_error.
void WriteScore(const std::string& path, const ScoreResult& result);
// The same with the /repeats group of `repeats` (none when null); `result` is repeats->combined.
void WriteScore(const std::string& path, const ScoreResult& result, const RepeatsResult* repeats);

}  // namespace netlab::netsim
