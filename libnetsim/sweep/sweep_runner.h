#pragma once
// Runs many variants of one scenario: a list of override sets in, one SweepRun per set out. The
// engine of `netlab sweep`, and of the finite-difference runs of `netlab fit`.
//
// The runs go to a pool of `jobs` threads in this process (each run builds its own simulation;
// nothing is shared but the scenario file) and, when the process is one rank of an MPI launch
// (`mpirun -np N netlab sweep ...`, sweep_mpi.h), over the ranks: rank 0 hands out run indices
// one at a time to whichever rank asks (dynamic: a slow region of the grid does not leave the other
// ranks idle), the ranks send each finished run back, and rank 0 alone returns them and calls the
// callbacks. All MPI calls are on the calling thread; the pool's threads never touch MPI or HDF5.
//
// A run that fails is part of the result, never an exception: a blow-up (kBlewUp, the frames up
// to it kept), a value the scenario rejects (kBadValue: the InputError's message) or anything else
// that threw (kFailed). Every run of a given override set gives the same bits whatever the pool,
// the rank or the order: it is `netlab simulate --set ...` of that set.

#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/tracks/track_file.h"
#include "libnetsim/scenario/run_scenario.h"
#include "libnetsim/scenario/scenario_override.h"

namespace netlab::netsim {

class MpiSession;

// The outputs a sweep reports per run (the report plots each against each parameter).
struct SweepOutputs {
  // m^2: the largest area of net 0's corner polygon (knots (0,0), (0,C-1), (R-1,C-1), (R-1,0);
  // half the norm of the diagonals' cross product, as `netlab score` computes it) over the output
  // frames: how far the net opened. NaN when the scenario has no net.
  double max_area_m2 = std::numeric_limits<double>::quiet_NaN();
  double max_area_time_s = std::numeric_limits<double>::quiet_NaN();  // s, when it was largest
  double max_penetration_m = 0.0;  // m, the deepest contact penetration (0: no contact)
  // m: how far the centroid of all knots moved from the first output frame to the last.
  double centroid_drift_m = std::numeric_limits<double>::quiet_NaN();
};

// The outputs by name, in the order of the file's and the report's tables.
struct SweepOutputInfo {
  const char* name;   // key in sweep.h5 (/runs/<name>) and in the JSON
  const char* title;  // for people
  const char* units;
  double SweepOutputs::*field;
};
inline constexpr std::array<SweepOutputInfo, 4> kSweepOutputs = {{
    {"max_area", "largest opening area (corner polygon)", "m^2", &SweepOutputs::max_area_m2},
    {"max_area_time", "time of the largest opening", "s", &SweepOutputs::max_area_time_s},
    {"max_penetration", "deepest contact penetration", "m", &SweepOutputs::max_penetration_m},
    {"centroid_drift", "drift of the knots' centroid", "m", &SweepOutputs::centroid_drift_m},
}};

struct SweepRun {
  enum class Status { kOk = 0, kBlewUp = 1, kBadValue = 2, kFailed = 3 };

  int index = 0;                            // into the list of override sets
  std::vector<ScenarioOverride> overrides;  // the set it ran
  Status status = Status::kOk;
  std::string error;     // why it failed; empty when kOk
  RunSummary summary;    // as `netlab simulate` reports it (default when
                         // the scenario could not be built)
  SweepOutputs outputs;  // from every output frame
  // The knot tracks: every `decimate`-th output frame from the first (up to a blow-up).
  std::vector<double> time;              // [T], s
  std::vector<Vector3d> knots;           // [T*K], frame-major, m
  std::vector<std::array<int, 2>> grid;  // [K], (row, col) of each knot in its net
  std::vector<int> net;                  // [K], the knot's net
  int rank = 0;                          // MPI rank that ran it (0 without MPI)

  bool ok() const { return status == Status::kOk; }
  // The kept knot tracks as a track file in memory (every knot valid, no covariance).
  KnotTracks Tracks() const;
};

// "ok", "blew up", "bad value", "failed".
const char* StatusName(SweepRun::Status status);

struct SweepOptions {
  // Threads of this process's pool; 0: the machine's cores (std::thread::hardware_concurrency),
  // or 1 per rank under MPI with more than one rank (one rank per core is mpirun's job).
  int jobs = 0;
  // Keep every decimate-th output frame of each run's knot tracks (>= 1). The outputs are always
  // computed from every frame.
  int decimate = 1;
  // Keep the tracks in the returned runs; false: they are only seen by on_run (memory:
  // frames x knots x 24 bytes a run).
  bool keep_tracks = true;
  // MPI: spread the runs over the ranks of this session; null: this process alone.
  const MpiSession* mpi = nullptr;
  // Called on the calling thread (rank 0), in order of completion, as each run ends; done counts
  // the runs ended so far (this one included).
  std::function<void(const SweepRun& run, int done, int total)> on_run;
  // Stage "runs", reported on the calling thread about every 0.2 s: the runs done, counting the
  // parts of this process's runs under way (e.g. 3.4 of 12). Its token stops the sweep within a
  // second (every run under way polls it): RunSweep throws Cancelled.
  ProgressReporter progress;
};

struct SweepResult {
  bool root = true;            // false on MPI ranks other than 0: `runs` is empty there
  std::vector<SweepRun> runs;  // by index (rank 0)
  int jobs = 1;                // threads per process
  int ranks = 1;               // MPI ranks (1 without MPI)
  double wall_s = 0.0;         // s, from the first run started to the last one back
  int failed() const;
  double RunsPerHour() const { return wall_s > 0 ? runs.size() * 3600.0 / wall_s : 0.0; }
};

// Runs `scenario_path` once per override set (LoadScenario(path, set), then RunScenario without
// an output file). Every failed run is in the result; throws only what a callback throws (the
// threads then finish the runs they have and take no more) or std::invalid_argument for options
// out of range. Under MPI every rank of the session must call it with the same arguments; a rank
// that dies ends the launch (mpirun's doing).
SweepResult RunSweep(const std::string& scenario_path,
                     const std::vector<std::vector<ScenarioOverride>>& runs,
                     const SweepOptions& options);

// One run, on the calling thread: what the pool runs (exposed for tests and `fit`).
// `progress`: RunScenario's (stage "steps"); a cancel throws Cancelled.
SweepRun RunOne(const std::string& scenario_path, int index,
                const std::vector<ScenarioOverride>& overrides, int decimate,
                const ProgressReporter& progress = {});

}  // namespace netlab::netsim
