#pragma once
// The simulation's own spread, Sigma_sim, from an ensemble: runs of the same model that differ
// only in what the model cannot know (the step, the links' resolution, the launch within its
// measured uncertainty). Each member is interpolated (linearly) at the scored simulation's frame
// times, so the spread is taken after the time alignment the score applies to the simulation,
// and the per knot-frame sample covariance S of the members (divisor M - 1) is taken as the spread
// of one run about the ensemble's mean. The measured flight and the scored run are each one such
// outcome, independent, so their difference has covariance 2 S; as r^T S^-1 r of M - 1 degrees
// of freedom averages 3 (M - 1) / (M - 5) (Hotelling), 2 S (M - 1) / (M - 5) is what is added to
// the simulation's own /knots/covariance (2 S for M <= 5: too few runs; 10 or more advised).
// `netlab score --sim-ensemble` (docs/score.md).

#include <string>
#include <vector>

#include "common/tracks/track_file.h"

namespace netlab::netsim {

struct EnsembleMember {
  std::string name;  // for messages: "ens.h5:/tracks/3" or a file path
  KnotTracks tracks;
};

// The runs of an ensemble: a `netlab sweep` file (its runs that finished, status ok), or a comma
// list of simulation files. Throws InputError naming the file for a file that is neither.
std::vector<EnsembleMember> ReadEnsemble(const std::string& spec);

// `sim` with /knots/covariance replaced by its own (zero when absent) plus the members' spread.
// Throws InputError naming the member and what differs: fewer than 2 members, a member of another
// net (its grid), a member that does not cover the simulation's time to within one of its frames
// (a frame beyond a member's span takes the others' spread).
// The largest per-axis spread is returned in `max_sigma_m` when given.
KnotTracks AddEnsembleCovariance(const KnotTracks& sim, const std::string& sim_name,
                                 const std::vector<EnsembleMember>& members,
                                 double* max_sigma_m = nullptr);

}  // namespace netlab::netsim
