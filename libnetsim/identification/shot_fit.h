#pragma once
// Identification of a shot's parameters from its measured knot tracks: the engine of `netlab fit`
// (docs/fit.md).
//
// Unknowns: the free parameters (fit_parameters.h). Residuals: every measured knot-frame that
// `netlab score` compares, whitened by its covariance (Sigma_meas + sigma_sim^2 I + the cubic
// interpolation's error^2, held at the start's values):
//   e_tk = L_tk^-1 (p_meas(t, k) - Exp(w) p_sim(t + time_offset, k) - t_frame)
// plus one residual (value - prior) / sigma_prior per parameter with a prior. Minimised with
// Ceres' Levenberg-Marquardt; the Jacobian's columns of scenario parameters by forward finite
// differences of whole simulations, run in parallel on the sweep pool (libnetsim/sweep); those of
// time_offset and frame by central differences of the interpolation (no simulation).
//
// The uncertainty: the covariance (J^T J)^-1 at the fit, with the data's information divided by
// the inflation `netlab score` finds for correlated residuals (integrated autocorrelation time x
// within-frame design effect) and by the reduced chi^2 when above 1 (a model that cannot fit
// the data within its noise), each shot's rows by its own. Weak anchors keep scale parameters no
// data or prior can see near their start; material parameters are held while the launch is
// fitted first, then each is scanned over a factor 2 either way (or over its prior's reach,
// ScanCoordinates) before everything is fitted. A parameter that looks identified is checked:
// the cost at -+ 2 sigma must rise within 2x of the Jacobian's prediction, or the cost is rough
// there and sigma means nothing.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/progress.h"
#include "common/tracks/track_file.h"
#include "libnetsim/identification/fit_parameters.h"
#include "libnetsim/scenario/scenario.h"
#include "libnetsim/validation/score.h"

namespace netlab::netsim {

// A prior on one parameter (from `netlab characterize`): a residual (value - mean) / sigma.
struct FitPrior {
  std::string name;  // the parameter's name (a dotted path)
  double value = 0.0, sigma = 0.0;
  std::string source;  // where it came from, for the report
};

struct FitOptions {
  std::vector<ScenarioOverride> set;  // applied to the scenario before the parameters
  ScoreOptions score;                 // meas_sigma_m, sim_sigma_m, time_offset_s (start or
                                      // fixed), max_time_offset_s
  std::vector<FitPrior> priors;
  int jobs = 0;             // simulations at a time (0: the machine's cores)
  int max_iterations = 25;  // Levenberg-Marquardt iterations per start
  int starts = 1;           // > 1: also from starts-1 points spread over the start's box
  // Forward-difference step of a scenario parameter: of ln(value) for log parameters, of the
  // spread (fit_parameters.h) times this for the others.
  double step = 1e-3;
  uint32_t seed = 1;  // the extra starts' draws
  // Between the stages, each material parameter is scanned over a factor 2 either way of where the
  // first stage left it (or over its prior's reach, ScanCoordinates), this many values either
  // way (0: no scan).
  int scan_steps = 8;
  // A report per Levenberg-Marquardt iteration and per scanned parameter, on the calling thread:
  // stage "start 2/3, stage 1/3 material held" (the start when starts > 1; the stage "1/3
  // material held", "2/3 scan <parameter>", "3/3 all", without the first when only material
  // parameters are free, none when no material parameter is), done the simulations so far,
  // total at most the simulations in all (every Levenberg-Marquardt run to max_iterations, the
  // scan, the last stage from each other valley found so far, the final check), detail
  // "iteration 4, cost 812.3" (the cost, %.6g, the sum of squared whitened residuals where the
  // fit stands; no iteration in the scan's reports). Its token stops the simulations under way:
  // the fit throws Cancelled.
  ProgressReporter progress;
};

// What settled a fitted parameter: the flight data (identified), its prior, or neither.
enum class DeterminedBy { kFlightData, kPrior, kNeither };
std::string DeterminedByName(DeterminedBy by);  // "flight data" | "prior" | "neither"

struct FittedParameter {
  FitParameter parameter;
  double value = 0.0;       // the estimate
  double sigma = 0.0;       // its standard uncertainty (inf: the data and priors leave it free)
  double data_sigma = 0.0;  // what the flight data alone says (inf: nothing)
  bool has_prior = false;
  double prior_value = 0.0, prior_sigma = 0.0;
  // The cost at value -+ 2 sigma over the rise the Jacobian predicts (about 1 on a smooth cost);
  // NaN where not checked (parameters that do not look identified, time_offset and frame).
  std::array<double, 2> check = {std::numeric_limits<double>::quiet_NaN(),
                                 std::numeric_limits<double>::quiet_NaN()};
  bool rough = false;  // checked, and the cost is not within 2x of the quadratic model
  // The cost has more than one valley along it: another end of the fit (a start, or the scan's
  // other valley) fits as well (its cost within 3.84 x the inflation of the best's) with this
  // parameter more than 2 sigma away; or, for a material parameter, a scan found another valley
  // and the fit from there ended in another basin (EndElsewhere), however much worse (it may
  // have ended worse only because the other parameters were not yet right), or failed. The
  // estimate is the lowest end found, not identified by the flight; a prior decides. The other
  // end's value, how much higher its cost ended, and where it started (NaN and empty when that
  // fit failed).
  bool ambiguous = false;
  double alternative = std::numeric_limits<double>::quiet_NaN();
  double alternative_rise = std::numeric_limits<double>::quiet_NaN();  // its cost above the best's
  std::string alternative_from;
  // sigma < half the reference spread (the prior's sigma, or spread), the cost not rough and no
  // other end as good
  bool identified = false;
  DeterminedBy determined_by = DeterminedBy::kNeither;
};

struct FitResult {
  std::vector<FittedParameter> parameters;
  Eigen::MatrixXd covariance;  // of the fitted coordinates (ln(value) for log parameters)
  Eigen::MatrixXd correlation;
  double cost_initial = 0.0, cost_final = 0.0;  // sum of squared whitened residuals + priors
  int residuals = 0;                            // data residuals (3 per knot-frame)
  double inflation = 1.0;  // what the data's information was divided by (the largest shot's)
  int iterations = 0;
  int simulations = 0;
  int best_start = 0;
  int ends = 0;  // runs of the last stage that ended usable (starts, and the scan's rivals)
  std::string termination;  // Ceres' report
  double wall_s = 0.0;
  double duration_s = 0.0;  // the simulated span each run was cut to
  double dt_s = 0.0;        // the automatic step held for every run (the start's); 0: the
                            // scenario's own dt
  ScoreSummary score;       // `netlab score` of the fitted simulation (the first shot's)
  // The --set lines that reproduce the fit (first shot): the user's own but those naming a free
  // parameter, the fitted parameters, then the held step (integrator.dt) when the scenario's was
  // auto.
  std::vector<ScenarioOverride> fitted_set;
  // Per shot, in order: the score, the inflation, the --set lines.
  std::vector<ScoreSummary> scores;
  std::vector<double> inflations;
  std::vector<std::vector<ScenarioOverride>> fitted_sets;
  // What the user should know about the fit beyond the numbers (ResolutionNotes,
  // PriorConflictNote).
  std::vector<std::string> notes;
};

// One measured shot and the scenario that simulates it.
struct FitShotInput {
  std::string scenario_path;
  const KnotTracks* measured = nullptr;
  std::string measured_name = "measured";
};

// Fits `parameters` of the scenario in `scenario_path` to `measured`. Throws InputError (bad
// scenario, parameters or priors), std::invalid_argument (the tracks, as `netlab score` checks
// them) or std::runtime_error when the starting simulation fails.
FitResult FitShot(const std::string& scenario_path, const KnotTracks& measured,
                  const std::vector<FitParameter>& parameters, const FitOptions& options,
                  const std::string& measured_name = "measured");

// Several shots at once (fit_parameters.h: the material and drag shared, the rest per shot): the
// residuals of every shot, each weighed and inflated as one shot's.
FitResult FitShots(const std::vector<FitShotInput>& shots,
                   const std::vector<FitParameter>& parameters, const FitOptions& options);

// Notes for a free bending stiffness whose net is too coarse to show it: a link's segments
// longer than kBendingSegment, where a flight shows only part of EI's effect on the knots, so the
// fitted EI is that resolution's, not the thread's (docs/benchmarks.md, "Bending waves"); under
// the implicit step the note adds that the step hides most of EI's effect at any resolution
// (docs/simulator.md). `name` names the scenario in the note.
inline constexpr double kBendingSegment = 0.0125;  // m
std::vector<std::string> ResolutionNotes(const Scenario& scenario,
                                         const std::vector<FitParameter>& parameters,
                                         const std::string& name);

// The scan's reading of one profile of costs along a parameter (NaN or inf: a failed run): the
// lowest (the one at `current` unless another is lower), and the lowest other local minimum
// behind a barrier, a rise of at least `barrier` above both between them (-1: none). The default,
// a chi^2 rise of 9, is 3 sigma in one parameter: the simulation's jitter in the cost seldom
// makes a rival, and one it makes costs a run of the last stage, not a wrong answer.
struct ScanMinima {
  int best = -1, rival = -1;
};
ScanMinima FindScanMinima(const std::vector<double>& costs, int current, double barrier = 9.0);

// When a scan found another valley, the fit's last stage ran from it too; the first of the ends
// (coordinates) that lies in another basin than `best`: a material parameter (`material`) more
// than 2 sigma (`sigma`, of the coordinates) from the estimate. -1 when every end came back to the
// estimate's basin. One found makes every material parameter ambiguous (FittedParameter).
int EndElsewhere(const std::vector<std::vector<double>>& ends, const std::vector<double>& best,
                 const std::vector<double>& sigma, const std::vector<bool>& material);

// Where the scan between the stages looks along a material parameter: 2 steps + 1 coordinates
// (ln value), ascending, the middle one the centre. Without a prior, a factor 2 either way of
// `current`, the coordinate the fit stands at. With one, the prior's reach: its value +-3 sigma
// (3 sigma / value in ln value), or a factor 2 either way of it when that is narrower. A valley
// beyond the prior's reach is not a rival: the bench puts the parameter there with odds below
// 0.3 % (docs/benchmarks.md, "Parameter identification").
inline constexpr double kPriorReach = 3.0;
std::vector<double> ScanCoordinates(const FitParameter& parameter, const FitPrior* prior,
                                    double current, int steps);

// A note when the fit ends beyond its prior's reach (more than kPriorReach prior sigma from the
// prior's value): the flight and the bench disagree. Empty when it does not, or has no prior.
// `source` names the prior (its file).
std::string PriorConflictNote(const FittedParameter& fitted, const std::string& source);

}  // namespace netlab::netsim
