#pragma once
// The simulation room without a window: simulations (a scenario run with `netlab simulate`'s
// engine on a worker, or a knot-track file loaded), each scored against the measured tracks with
// `netlab score`'s engine (netsim::Score, docs/score.md), and the simulated net as each camera
// sees it: the simulated knots aligned in time and space as the score aligns them, projected
// through the rig into the camera's image over the recorded frame.
//
// The alignment of a simulation: t_sim = t_measured + tau and x_world = R x_sim + t (the score's
// fitted time offset and rigid motion; tau = 0 and the identity before it is scored). The
// simulated knots at t_sim are the score's cubic (4-point Lagrange) interpolant of the stored
// frames; a link is drawn straight between its knots' images.
//
//   SimulationPresenter simulation(&session, &reconstruction);
//   simulation.Add(SimulationPresenter::Simulate(SimulationPresenter::MakeSimulationJob(
//       "net_a.yaml", {"drag.drag_coefficient=1.0"}, "sim.h5"), cancel));
//   simulation.SetScore(SimulationPresenter::RunScore(simulation.MakeScoreJob(0)));
//   simulation.Verdict(0);                    // "consistent: ..."
//   simulation.InCamera(0, camera, t);        // the simulated net in that view

#include <Eigen/Core>
#include <QString>
#include <atomic>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/progress.h"
#include "common/tracks/track_file.h"
#include "libnetsim/identification/shot_fit.h"
#include "libnetsim/scenario/scenario_override.h"
#include "libnetsim/validation/score.h"

namespace netlab::gui {

class ReconstructionPresenter;
class Session;

// A scenario to run: the file, `--set`'s dotted overrides, the output file, `--duration`.
struct SimulationJob {
  std::string scenario_path;
  std::vector<netsim::ScenarioOverride> overrides;
  std::string out_path;
  double duration_s = 0.0;  // 0: the scenario's
};
// A simulation, run or loaded.
struct SimulationRun {
  std::string path;  // the knot-track file
  std::optional<KnotTracks> tracks;
  std::string error;  // why there are no tracks
  bool cancelled = false;
  double wall_s = 0.0;
};
// A score to compute (copied: it runs on a worker) and its answer.
struct ScoreJob {
  int index = 0;  // the simulation's
  KnotTracks measured, sim;
  netsim::ScoreOptions options;
  std::string measured_name, sim_name;
};
struct ScoreRun {
  int index = 0;
  std::optional<netsim::ScoreResult> result;
  std::string error;
};

// A fit to run (`netlab fit`'s engine, netsim::FitShot) and its answer.
struct FitJob {
  std::string scenario_path;
  std::vector<netsim::FitParameter> parameters;
  KnotTracks measured;
  netsim::FitOptions options;
};
struct FitRun {
  std::string scenario_path;
  std::optional<netsim::FitResult> result;
  std::string error;
  bool cancelled = false;
  // The start's score: the scenario with its overrides simulated and scored against the same
  // tracks with the fit's score options (nullopt: not scored, the reason in start_error).
  std::optional<netsim::ScoreSummary> start_score;
  std::string start_error;
};

// A simulation in the room.
struct Simulation {
  std::string name;  // the file's name
  std::string path;
  KnotTracks tracks;
  std::optional<netsim::ScoreResult> score;
  std::string score_error;
  std::string score_path, report_path;  // written with the score ("" until then)
};

// One camera's view of a simulation at one frame: the simulated knots (the labels' knot index,
// (row, col) row-major) and links as image pixels; knots behind the camera left out.
struct SimulatedView {
  double sim_time_s = 0.0;
  std::vector<int> knots;
  std::vector<Eigen::Vector2d> px;  // [knots.size()]
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> links;
  // The pixel of a knot (nullopt: not drawn).
  std::optional<Eigen::Vector2d> Find(int knot) const;
};

class SimulationPresenter {
 public:
  // Both must outlive the presenter; the measured tracks are `reconstruction`'s.
  SimulationPresenter(const Session* session, const ReconstructionPresenter* reconstruction);

  // ---- Simulations.
  // `overrides` as `netlab simulate --set` takes them (PATH=VALUE); InputError naming the one
  // that cannot be read.
  static SimulationJob MakeSimulationJob(const std::string& scenario_path,
                                         const std::vector<std::string>& overrides,
                                         const std::string& out_path, double duration_s = 0.0);
  // Runs the scenario (any thread), writing out_path as netlab simulate does, reporting as
  // RunScenario does. A cancel of the reporter's token stops it within a step: the answer says
  // cancelled and no file is left. A scenario that cannot be built, or a run that blows up,
  // answers the reason.
  static SimulationRun Simulate(const SimulationJob& job, const ProgressReporter& progress = {});
  // The scenario's main keys (duration, integrator, drag, gravity, materials, nets, bodies) as
  // (`--set`'s dotted path, value) rows, lists of numbers as one value. InputError naming the
  // file when it cannot be read.
  static std::vector<std::pair<std::string, std::string>> ScenarioKeys(const std::string& path);
  // Why the scenario with these overrides (PATH=VALUE) cannot be simulated, as netlab simulate
  // says it ("" : it can).
  static std::string CheckScenario(const std::string& path,
                                   const std::vector<std::string>& overrides);
  // Reads a knot-track file (a netlab simulate result); the error names the file.
  static SimulationRun Load(const std::string& path);
  // Adds a run with tracks (GUI thread); returns its index (-1: none added, no tracks).
  int Add(SimulationRun run);
  int simulations() const { return static_cast<int>(simulations_.size()); }
  // Names simulation i's file in the project file's `simulations` (once). std::runtime_error
  // naming the project when it cannot be written.
  void AddToProject(int i) const;
  // The project's tracks and simulations read (those not yet here); the reasons of the files
  // that cannot be read, one line each.
  std::vector<std::string> OpenFromProject(ReconstructionPresenter* reconstruction);
  const Simulation& simulation(int i) const { return simulations_[i]; }

  // ---- Scores. The measured tracks are the reconstruction's (null: not triangulated yet).
  const KnotTracks* measured() const;
  // std::logic_error without measured tracks. `alignment` as --align.
  ScoreJob MakeScoreJob(int i,
                        netsim::Alignment alignment = netsim::Alignment::kTimeAndRigid) const;
  static ScoreRun RunScore(const ScoreJob& job);  // any thread
  // The answer (GUI thread). With `folder` non-empty, score_NAME.h5 and score_NAME.html are
  // written there as netlab score --out --report writes them (their paths kept) and named in
  // the project file's `scores`.
  void SetScore(ScoreRun run, const std::string& folder = "");
  // The verdict in words: "consistent: ..." / "inconsistent: ...", the numbers behind it and
  // the RMS; "not scored yet" or the reason it could not be.
  QString Verdict(int i) const;

  // ---- The simulated net over the footage.
  // The time of frame row t (s): the measured tracks' time of its frame, else frame / fps.
  double FrameTime(int t) const;
  // The alignment used to draw simulation i: the score's, else none.
  double time_offset_s(int i) const;
  // Knot positions of simulation i at simulated time `time_s`, in the rig's world frame (the
  // score's rigid motion applied), indexed by the labels' knot (NaN where the simulation has no
  // such knot, or outside its time).
  std::vector<Eigen::Vector3d> KnotsAt(int i, double time_s) const;
  // Simulation i in store camera c at frame row t.
  SimulatedView InCamera(int i, int c, int t) const;
  // The pixel distance between the label of `knot` in (c, t) and its simulated knot (nullopt:
  // no label or not drawn).
  std::optional<double> LabelDistancePx(int i, int c, int t, int knot) const;
  // The simulation the person looks at (the simulation room's selection; -1: none).
  void SetShown(int i) { shown_ = i; }
  int shown() const { return shown_; }
  // Each knot's RMS error (mm) in the shown simulation's score, row-major over the project's
  // grid (NaN: not compared), and what it is in words; empty when it is not scored. Until the
  // shown simulation is scored here (and before the room shows one: the simulation of
  // SavedScoreSimulation()), the score file the project names for it, read once (its
  // /knots/grid and /knots/rms_m): the Net grid has the saved colours as soon as the project is
  // open. A saved file that cannot be read gives none, its reason in `source`.
  std::vector<double> ShownKnotErrorsMm(QString* source) const;
  // The simulation (absolute path) whose saved score colours the Net grid before the room shows
  // one: the first of the project's simulations with a score file ("" : none).
  std::string SavedScoreSimulation() const;
  // The alignment of that saved score, as --align names it ("" : none, or unreadable): the room
  // scores the simulation again with it, to the same colours.
  std::string SavedScoreAlignment() const;
  // The score's 3D residual |measured - simulated| at (t, knot), m (nullopt: not compared).
  std::optional<double> ResidualM(int i, int t, int knot) const;

  // ---- Fit: the free parameters (`netlab fit --free`: comma-separated dotted paths of the
  // scenario, time_offset) of the scenario after `overrides`, against the measured tracks, with
  // `netlab fit`'s defaults (the time offset searched within 0.05 s). InputError naming a bad
  // entry; std::logic_error without measured tracks.
  FitJob MakeFitJob(const std::string& scenario_path, const std::vector<std::string>& overrides,
                    const std::string& free) const;
  // Any thread, reporting as FitShot does (FitOptions::progress); a cancel of the reporter's
  // token stops the fit's simulations under way (the answer says cancelled). After the fit, the
  // start (the scenario with its overrides) simulated once and scored, for FitText.
  static FitRun Fit(const FitJob& job, const ProgressReporter& progress = {});
  // The answer (GUI thread). A fit with a result and `folder` non-empty is written there as
  // fit_SCENARIO.yaml, the file netlab fit --out writes (its `measured` the project's tracks),
  // and named in the project file's `fits`; fit_path() is the file ("" : none).
  void SetFit(FitRun run, const std::string& folder = "");
  const FitRun* fit() const { return fit_ ? &*fit_ : nullptr; }
  const std::string& fit_path() const { return fit_path_; }
  // The fitted values with sigma and whether the flight data, a prior or neither determined
  // each; the cost from start to end; the fitted model's score beside the start's (FitRun's
  // start_score). Without a fit run here, the project's last fit file read (FitFileText).
  QString FitText() const;
  // A fit.yaml's values with sigma and who determined each, its cost and the fitted model's
  // score; the reason when the file cannot be read.
  static QString FitFileText(const std::string& path);
  // One line of a fit's progress `elapsed_s` into the fit: stage, iteration, cost, simulations,
  // time and ETA.
  static QString ProgressText(const Progress& p, double elapsed_s);

  std::weak_ptr<const int> lifetime() const { return alive_; }

 private:
  // A saved score file's per-knot errors, mm, row-major (read once per file).
  struct SavedErrors {
    std::string score_path;
    std::vector<double> mm;
    std::string alignment;  // the root attribute
    std::string error;      // why the file could not be read
  };
  const SavedErrors& ReadSavedErrors(const std::string& score_path) const;
  mutable std::optional<SavedErrors> saved_errors_;
  std::optional<FitRun> fit_;
  std::string fit_path_;
  int shown_ = -1;
  const Session* session_;
  const ReconstructionPresenter* reconstruction_;
  std::deque<Simulation> simulations_;  // a deque: an added one moves no score a chart shows
  std::shared_ptr<const int> alive_ = std::make_shared<const int>(0);
};

}  // namespace netlab::gui
