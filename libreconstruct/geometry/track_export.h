#pragma once
// Knot tracks out of a sequence reconstruction: in the layout of the knot-track file
// (common/tracks/track_file.h), compared with true tracks, and exported as DLTdv8-style CSV:
//
//   xyzpts.csv  a header row, then one row per frame of the tracks: columns pt{P}_X, pt{P}_Y,
//               pt{P}_Z for P = 1..K (knot (row, col) of a rows x cols net is P = row*cols+col+1;
//               the tracks' knots are matched by their grid coordinates), metres in the world
//               frame, "NaN" where the knot is not valid.
//   xyzres.csv  the same rows; columns pt{P}_dltres: the knot's RMS reprojection residual in px
//               (/knots/reprojection_error_px), "NaN" where not valid or unknown.
//
// Values are written with 17 significant digits so that reading gives back the same doubles.
// Files are written through "<path>.partial" and a rename.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "common/tracks/track_file.h"
#include "libreconstruct/geometry/bundle_adjust.h"

namespace netlab::recon {

// The reconstruction as knot tracks: time[t] the time of frame row t (s; frame_index / fps, or
// the cameras' timestamps), the knots of the rows x cols net in row-major order, positions,
// validity, covariances, RMS reprojection residuals, the outlier observations, the degenerate
// points and the rig's camera names, the given source.
KnotTracks TracksFromSequence(const SequenceResult& result, const std::vector<double>& time_s,
                              const std::string& source);
// The same with time = frame_index / fps.
KnotTracks TracksFromSequence(const SequenceResult& result, double fps, const std::string& source);

// Reconstructed tracks against true ones (e.g. the simulation that was rendered), every number in
// the truth's frame: the tracks are first moved by the best rigid motion onto the truth (a rig
// calibrated from a foil or markers has its own world frame), fitted to the valid points.
struct TruthComparison {
  int64_t points = 0;              // valid knot-frames the truth has a position for
  bool aligned = false;            // three points or more: the motion was fitted, the numbers below
                                   // are set (all 0 otherwise)
  double rms_m = 0.0;              // RMS 3D error over the valid points, m
  double max_m = 0.0;              // largest 3D error, m
  double mean_mahalanobis2 = 0.0;  // mean e' C^-1 e, C the point's covariance turned into the
                                   // truth's frame: 3 when the covariances are right
  // The motion (truth_from_tracks): how far the tracks' frame is from the truth's.
  double rotation_deg = 0.0, translation_m = 0.0;
  // The degenerate points (/knots/degenerate) the truth has a position for, through the same
  // motion: their RMS and largest error, m.
  int64_t degenerate_points = 0;
  double degenerate_rms_m = 0.0, degenerate_max_m = 0.0;
};

// Compares every valid point of `tracks` (which must carry covariances) with the truth's knot at
// the same grid position, linearly interpolated to the point's time; points outside the truth's
// time span, or where it lacks the knot or a valid position, are left out. The rigid motion is
// Umeyama's (no scale) over the valid points; the degenerate points are compared apart.
TruthComparison CompareWithTruth(const KnotTracks& tracks, const KnotTracks& truth);

void WriteXyzPts(const std::string& path, const KnotTracks& tracks, int rows, int cols);
void WriteXyzRes(const std::string& path, const KnotTracks& tracks, int rows, int cols);

// Reads xyzpts.csv back: positions[t][P - 1] (NaN where "NaN"). Throws netlab::InputError naming
// the file, line and column on malformed input.
std::vector<std::vector<Eigen::Vector3d>> ReadXyzPts(const std::string& path);
// Reads xyzres.csv back: residual[t][P - 1].
std::vector<std::vector<double>> ReadXyzRes(const std::string& path);

}  // namespace netlab::recon
