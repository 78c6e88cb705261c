#pragma once
// Runs a scenario from t = 0 to its duration, writing output frames at every output_interval to a
// knot-track file (track_file.h), and summarises the run. The engine behind `netlab simulate`.

#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/progress.h"
#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {

struct RunOptions {
  std::string out_path;  // knot-track HDF5 file; empty: write nothing
  // Stage "steps" (done and total counted in integrator steps), about every 2 % of the run, on
  // the calling thread; its token is polled at every step: a cancelled run throws Cancelled and
  // leaves no
  // "<out_path>.partial".
  ProgressReporter progress;
  // Called at every output frame (the frames the file gets) with the time (s) and the knots'
  // positions (m, in Model::knots order), e.g. to keep the tracks in memory; may be empty.
  std::function<void(double time, const std::vector<Vector3d>& knots)> on_frame;
  // on_frame keeps every keep_every-th frame's knots in memory (0: none): the run is refused
  // before its first step when they would not fit (as is a file larger than its disk's space).
  int keep_every = 0;
  // Called once the scenario is built, before the first step (the knots' grid and nets); may be
  // empty.
  std::function<void(const BuiltScenario& built)> on_built;
};

struct RunSummary {
  std::string scenario;
  bool stable = true;              // false when the run stopped on a NaN or blow-up
  std::string error;               // why it stopped (empty when stable)
  std::string integrator;          // "explicit" | "verlet" | "implicit"
  double dt = 0.0;                 // s, the step used
  double dt_limit = 0.0;           // s, estimated stability limit
  double max_inertia_scale = 1.0;  // largest rotational inertia scaling factor
  long steps = 0;
  // Steps the implicit integrator split, for the tension (otherwise the same as steps), and the
  // largest split.
  long substeps = 0;
  int max_substeps = 1;
  int nodes = 0;
  int segments = 0;
  int knots = 0;
  int frames = 0;         // output frames written
  double sim_time = 0.0;  // s, simulated time reached
  double wall_s = 0.0;    // s, wall-clock time of the stepping (and output)
  double segment_steps_per_s = 0.0;
  double real_time_factor = 0.0;   // sim_time / wall_s
  double max_penetration = 0.0;    // m, deepest contact penetration
  std::string max_penetration_at;  // where it happened ("" when no contact)
  double contact_start_s = std::numeric_limits<double>::quiet_NaN();  // first contact; NaN: none
  std::vector<std::pair<std::string, Vector3d>> probes;               // positions at the end, m
  Energy energy;                                                      // at the end
  std::vector<std::string> active;                                    // forces in use
  std::string output;                                                 // file written ("" if none)

  // A few human-readable lines.
  std::string BriefReport() const;
};

// Throws InputError for scenarios that cannot be built, std::runtime_error when the output
// cannot be written and Cancelled when options.progress's token is set. A blow-up is not an
// exception: it is reported in the summary (stable false), and the frames written so far stay in
// "<out_path>.partial".
RunSummary RunScenario(const Scenario& scenario, const RunOptions& options);

}  // namespace netlab::netsim
