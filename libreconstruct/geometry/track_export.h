#pragma once
// DLTdv8-style CSV export of knot tracks (the knot-track file, libnetsim/tracks/track_file.h):
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

#include <string>
#include <vector>

#include <Eigen/Core>

#include "libnetsim/tracks/track_file.h"

namespace netlab::recon {

void WriteXyzPts(const std::string& path, const netsim::KnotTracks& tracks, int rows, int cols);
void WriteXyzRes(const std::string& path, const netsim::KnotTracks& tracks, int rows, int cols);

// Reads xyzpts.csv back: positions[t][P - 1] (NaN where "NaN"). Throws netlab::InputError naming
// the file, line and column on malformed input.
std::vector<std::vector<Eigen::Vector3d>> ReadXyzPts(const std::string& path);
// Reads xyzres.csv back: residual[t][P - 1].
std::vector<std::vector<double>> ReadXyzRes(const std::string& path);

}  // namespace netlab::recon
