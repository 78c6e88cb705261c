#pragma once
// sweep.h5: every run of a sweep in one file, written by one process (MPI rank 0) as the runs come
// back, to "<path>.partial", renamed into place by Commit (an existing file is untouched until
// then, and stays so when the sweep fails).
//
// Layout (HDF5; every dataset of numbers has a "units" attribute, "1" where it has none):
//   /scenario                    string   the scenario file as read; the runs change it by
//                                         /fixed and one --set per parameter
//   /fixed                       string   the --set overrides of every run, one per line
//   /parameters/from, /to        [P] float64  each --vary's a and b (the scenario's units)
//   /parameters/count            [P] int32    n
//                                (attribute "paths": the dotted paths, one per line)
//   /runs/values                 [R,P] float64  each run's parameter values; run i is the grid
//                                point of the first parameter varying slowest
//   /runs/status                 [R] int32   0 ok, 1 blew up, 2 bad value, 3 failed
//   /runs/errors                 string   one line per run: why it failed ("" when ok)
//   /runs/overrides              string   one line per run: its --set arguments
//   /runs/max_area               [R] float64 m^2  (sweep_runner.h: SweepOutputs; NaN for a run
//   /runs/max_area_time          [R] float64 s     that failed)
//   /runs/max_penetration        [R] float64 m
//   /runs/centroid_drift         [R] float64 m
//   /runs/sim_time               [R] float64 s    simulated time reached
//   /runs/dt                     [R] float64 s    the step used
//   /runs/steps                  [R] int64
//   /runs/wall_time              [R] float64 s    wall-clock time of the run
//   /runs/rank                   [R] int32        the MPI rank that ran it
//   /tracks/<i>/time             [T] float64 s    run i's output frames, every decimate-th
//   /tracks/<i>/knots/position   [T,K,3] float64 m  (the frames up to a blow-up; none when the
//                                scenario could not be built); attributes "overrides", "status",
//                                "error"
//   /knots/grid                  [K,2] int32  (row, col), /knots/net [K] int32: the knots of the
//                                tracks, as the first run that built has them
//   /sensitivity/<output>        [P] float64  d ln(output)/d ln(parameter) at the grid's centre
//                                (sweep_sensitivity.h), NaN where undefined
// Root attributes: "format" = "netlab-sweep", "version" = "1", "source" = "netlab sweep",
// "scenario_path", "decimate", "jobs", "ranks", "wall_s" (the last four as text).

#include <memory>
#include <string>
#include <vector>

#include "libnetsim/sweep/sweep_grid.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "libnetsim/sweep/sweep_sensitivity.h"

namespace netlab::netsim {

inline constexpr char kSweepFileFormat[] = "netlab-sweep";

struct SweepFileHeader {
  std::string scenario_path;
  std::string scenario_text;
  std::vector<ScenarioOverride> fixed;
  std::vector<SweepParameter> parameters;
  std::vector<SweepPoint> grid;  // the runs' parameter values, by index
  int decimate = 1;
};

class SweepFileWriter {
 public:
  // Creates "<path>.partial". std::runtime_error naming it when it cannot.
  SweepFileWriter(const std::string& path, const SweepFileHeader& header);
  ~SweepFileWriter();
  SweepFileWriter(const SweepFileWriter&) = delete;
  SweepFileWriter& operator=(const SweepFileWriter&) = delete;

  // Writes run `run.index`'s tracks now and keeps its row of the /runs tables for Commit.
  void AddRun(const SweepRun& run);
  // Writes the /runs tables and the sensitivities, closes the file and renames it to `path`.
  void Commit(const SweepResult& result, const std::vector<std::vector<Sensitivity>>& sensitivity);
  const std::string& partial_path() const { return partial_path_; }

 private:
  struct Handles;
  std::string path_, partial_path_;
  SweepFileHeader header_;
  std::vector<SweepRun> rows_;  // the runs without their tracks
  bool grid_written_ = false;
  std::unique_ptr<Handles> handles_;
};

}  // namespace netlab::netsim
