#include "libnetsim/identification/shot_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include "common/yaml_util.h"
#include "libnetsim/sweep/sweep_runner.h"
#include "libnetsim/validation/alignment.h"

namespace netlab::netsim {
namespace {

using Clock = std::chrono::steady_clock;
using Eigen::Matrix3d;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();

// A material parameter: the thread's, shared by every shot, fitted as ln(value).
bool IsMaterial(const FitParameter& p) {
  return p.kind == FitParameter::Kind::kScenario && p.log && p.path.rfind("materials.", 0) == 0;
}

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// The alignment parameters of coordinates x: the time offset and the rigid correction.
struct Alignment6 {
  double tau = 0.0;
  Matrix3d rotation = Matrix3d::Identity();
  Vector3d translation = Vector3d::Zero();
};

// Shot `shot`'s alignment at coordinates x (its own time_offset and frame).
Alignment6 AlignmentOf(const std::vector<FitParameter>& parameters, const double* x,
                       double fixed_tau, int shot) {
  Alignment6 a;
  a.tau = fixed_tau;
  Vector3d w = Vector3d::Zero();
  for (size_t i = 0; i < parameters.size(); ++i) {
    const FitParameter& p = parameters[i];
    if (p.shot != shot) continue;
    if (p.kind == FitParameter::Kind::kTimeOffset) a.tau = x[i];
    if (p.kind != FitParameter::Kind::kFrame) continue;
    if (p.frame_axis < 3) {
      w[p.frame_axis] = x[i];
    } else {
      a.translation[p.frame_axis - 3] = x[i];
    }
  }
  a.rotation = ExpSo3(w);
  return a;
}

// The measured points and their whitening, fixed at the start so that every evaluation sums the
// same residuals with the same weights.
class Residuals {
 public:
  Residuals(const KnotTracks& measured, Comparison comparison)
      : measured_(measured), comparison_(std::move(comparison)) {}

  // Keeps the points the start's simulation reaches at every offset within tau +- margin, and
  // weighs each by Sigma_meas + sigma_sim^2 I + (interpolation error)^2 I there.
  void Fix(const KnotTracks& sim, double tau, double margin, double sim_sigma_m) {
    const SimInterpolant interp(sim, comparison_.sim_knot);
    std::vector<ComparedPoint> kept;
    Vector3d p;
    double error = 0.0;
    for (const ComparedPoint& pt : comparison_.points) {
      const double t = measured_.time[pt.frame] + tau;
      if (!interp.At(t - margin, pt.knot, &p, nullptr, nullptr) ||
          !interp.At(t + margin, pt.knot, &p, nullptr, nullptr) ||
          !interp.At(t, pt.knot, &p, nullptr, &error))
        continue;
      const Matrix3d cov =
          pt.meas_cov + Matrix3d::Identity() * (sim_sigma_m * sim_sigma_m + error * error);
      kept.push_back(pt);
      whiten_.push_back(Eigen::LLT<Matrix3d>(cov).matrixL().solve(Matrix3d::Identity()));
    }
    comparison_.points = std::move(kept);
  }

  int count() const { return 3 * static_cast<int>(comparison_.points.size()); }

  // L^-1 (p_meas - R p_sim(t + tau) - t) of every point into out[count()]; false when the
  // simulation does not reach one.
  bool Evaluate(const KnotTracks& sim, const Alignment6& a, double* out) const {
    const SimInterpolant interp(sim, comparison_.sim_knot);
    Vector3d p;
    for (size_t i = 0; i < comparison_.points.size(); ++i) {
      const ComparedPoint& pt = comparison_.points[i];
      if (!interp.At(measured_.time[pt.frame] + a.tau, pt.knot, &p, nullptr, nullptr)) return false;
      const Vector3d r =
          whiten_[i] * (measured_.Position(pt.frame, pt.knot) - a.rotation * p - a.translation);
      out[3 * i] = r.x();
      out[3 * i + 1] = r.y();
      out[3 * i + 2] = r.z();
    }
    return true;
  }

 private:
  const KnotTracks& measured_;
  Comparison comparison_;
  std::vector<Matrix3d> whiten_;
};

// Runs one shot's simulations of coordinate vectors, several at a time, remembering the
// unperturbed ones.
class Simulator {
 public:
  Simulator(std::string scenario_path, int shot, std::vector<ScenarioOverride> set,
            const std::vector<FitParameter>& parameters, const FitOptions& options)
      : path_(std::move(scenario_path)),
        shot_(shot),
        set_(std::move(set)),
        parameters_(parameters),
        options_(options) {}

  // The knot tracks of every coordinate vector (full x; only the scenario parameters matter), in
  // order; an empty pointer for a run that failed (its reason in *error).
  // Const: remembering runs and counting them changes nothing a caller sees.
  std::vector<std::shared_ptr<const KnotTracks>> Run(const std::vector<std::vector<double>>& xs,
                                                     std::string* error) const {
    std::vector<std::shared_ptr<const KnotTracks>> out(xs.size());
    std::vector<std::vector<ScenarioOverride>> runs;
    std::vector<size_t> which;
    for (size_t i = 0; i < xs.size(); ++i) {
      const std::vector<double> key = ScenarioPart(xs[i]);
      if (const auto hit = cache_.find(key); hit != cache_.end()) {
        out[i] = hit->second;
        continue;
      }
      std::vector<ScenarioOverride> set = set_;
      for (const ScenarioOverride& o : ScenarioOverrides(parameters_, xs[i], shot_))
        set.push_back(o);
      runs.push_back(std::move(set));
      which.push_back(i);
    }
    if (runs.empty()) return out;
    SweepOptions sweep;
    sweep.jobs = options_.jobs;
    sweep.on_run = [this](const SweepRun&, int, int) { ++simulations_; };
    sweep.progress = options_.progress.Silent();  // its token stops the runs
    SweepResult result;
    try {
      result = RunSweep(path_, runs, sweep);
    } catch (const Cancelled&) {
      // Not thrown through Ceres: every run fails, and the fit throws at its next poll.
      if (error) *error = "cancelled";
      return out;
    }
    if (cache_.size() > 64) cache_.clear();
    for (size_t r = 0; r < runs.size(); ++r) {
      const SweepRun& run = result.runs[r];
      if (!run.ok()) {
        if (error) *error = std::string(StatusName(run.status)) + ": " + run.error;
        continue;
      }
      auto tracks = std::make_shared<const KnotTracks>(run.Tracks());
      out[which[r]] = tracks;
      // Only the unperturbed runs are asked for again (the accepted step's Jacobian).
      if (which[r] == 0) cache_[ScenarioPart(xs[which[r]])] = tracks;
    }
    return out;
  }

  int simulations() const { return simulations_; }

 private:
  std::vector<double> ScenarioPart(const std::vector<double>& x) const {
    std::vector<double> key;
    for (size_t i = 0; i < parameters_.size(); ++i)
      if (parameters_[i].kind == FitParameter::Kind::kScenario && Moves(parameters_[i], shot_))
        key.push_back(x[i]);
    return key;
  }

  const std::string path_;
  const int shot_;
  const std::vector<ScenarioOverride> set_;  // --set and the cut duration
  const std::vector<FitParameter>& parameters_;
  const FitOptions& options_;
  mutable std::map<std::vector<double>, std::shared_ptr<const KnotTracks>> cache_;
  mutable int simulations_ = 0;
};

// The priors by parameter index: (mean, sigma) in the parameter's units.
// An anchor is the weak prior of a log parameter without one: (ln value - ln start) / ln 1000, a
// factor 1000 per standard deviation. It keeps a parameter the data cannot see near its start
// instead of drifting to 1e-70 (the cost is flat along it), and moves one the data determine by
// a negligible amount (its information is 0.02 against the data's thousands).
struct PriorTerm {
  int parameter;
  double value, sigma;  // the parameter's units; an anchor's in its coordinate (ln value)
  bool anchor = false;
};
constexpr double kAnchorSigma = 6.907755278982137;  // ln 1000

// One shot of the fit: its fixed residuals, its simulations, where its rows start.
struct Shot {
  Residuals residuals;
  Simulator simulator;
  int offset = 0;                             // first row of its residuals
  std::optional<ScenarioOverride> held_step;  // integrator.dt when it was auto (HoldStep)
};

// The whole least-squares problem as one Ceres cost: data residuals, then prior residuals.
class ShotCost : public ceres::CostFunction {
 public:
  ShotCost(const std::vector<FitParameter>& parameters, std::vector<Shot>* shots,
           std::vector<PriorTerm> priors, const FitOptions& options, double margin)
      : active_(parameters.size(), true),
        margin_(margin),
        parameters_(parameters),
        shots_(*shots),
        priors_(std::move(priors)),
        options_(options) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(parameters.size()));
    int rows = 0;
    for (Shot& shot : shots_) {
      shot.offset = rows;
      rows += shot.residuals.count();
    }
    data_rows_ = rows;
    set_num_residuals(rows + static_cast<int>(priors_.size()));
  }

  bool Evaluate(double const* const* x_blocks, double* residuals,
                double** jacobians) const override {
    const int p = static_cast<int>(parameters_.size());
    const std::vector<double> x(x_blocks[0], x_blocks[0] + p);
    // The offset's range, as a rejected step rather than a Ceres bound: a bound makes Ceres
    // search along the projected step, a Jacobian (a batch of simulations) per trial.
    for (int j = 0; j < p; ++j)
      if (parameters_[j].kind == FitParameter::Kind::kTimeOffset &&
          std::abs(x[j] - options_.score.time_offset_s) > margin_)
        return Reject("the time offset left its range");
    double* jac = jacobians != nullptr ? jacobians[0] : nullptr;
    if (jac) std::fill(jac, jac + size_t(data_rows_) * p, 0.0);
    for (size_t k = 0; k < shots_.size(); ++k)
      if (!EvaluateShot(static_cast<int>(k), x, residuals, jac)) return false;
    EvaluatePriors(x.data(), residuals + data_rows_, jac ? jac + size_t(data_rows_) * p : nullptr);
    if (jac && std::find(active_.begin(), active_.end(), false) == active_.end()) {
      last_x_ = x;
      last_jacobian_.assign(jac, jac + size_t(num_residuals()) * p);
    }
    return true;
  }

  // Which parameters the next evaluations move (the others' columns are zero, unsimulated).
  void SetActive(std::vector<bool> active) { active_ = std::move(active); }

  // The cost (data and priors, sum of squares) at each coordinate vector, every shot's
  // simulations run together; NaN where a simulation fails or does not reach a point.
  std::vector<double> CostsAt(const std::vector<std::vector<double>>& xs) const {
    std::vector<double> costs(xs.size(), 0.0);
    std::string error;
    for (size_t k = 0; k < shots_.size(); ++k) {
      const Shot& shot = shots_[k];
      const auto sims = shot.simulator.Run(xs, &error);
      std::vector<double> r(shot.residuals.count());
      for (size_t i = 0; i < xs.size(); ++i) {
        const Alignment6 a = AlignmentOf(parameters_, xs[i].data(), options_.score.time_offset_s,
                                         static_cast<int>(k));
        if (!sims[i] || !shot.residuals.Evaluate(*sims[i], a, r.data())) {
          costs[i] = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        for (double v : r) costs[i] += v * v;
      }
    }
    std::vector<double> prior(priors_.size());
    for (size_t i = 0; i < xs.size(); ++i) {
      EvaluatePriors(xs[i].data(), prior.data(), nullptr);
      for (double v : prior) costs[i] += v * v;
    }
    return costs;
  }

  // At most the simulations one Levenberg-Marquardt iteration over `active` runs: each shot's
  // trial step and a forward difference per active scenario parameter that moves it (the
  // accepted step's own run is remembered).
  long RunsPerIteration(const std::vector<bool>& active) const {
    long runs = 0;
    for (size_t k = 0; k < shots_.size(); ++k) {
      ++runs;
      for (size_t j = 0; j < parameters_.size(); ++j)
        runs += parameters_[j].kind == FitParameter::Kind::kScenario && active[j] &&
                Moves(parameters_[j], static_cast<int>(k));
    }
    return runs;
  }
  int shots() const { return static_cast<int>(shots_.size()); }

  int simulations() const {
    int n = 0;
    for (const Shot& shot : shots_) n += shot.simulator.simulations();
    return n;
  }
  int data_rows() const { return data_rows_; }

  // The Jacobian (row-major, num_residuals x p) at x when the last evaluation was there.
  bool JacobianAt(const std::vector<double>& x, std::vector<double>* jacobian) const {
    if (x != last_x_) return false;
    *jacobian = last_jacobian_;
    return true;
  }
  const std::string& last_failure() const { return failure_; }

 private:
  // Shot k's rows of the residuals (and of the Jacobian, zeroed by the caller): its unperturbed
  // run and, for a Jacobian, one forward-difference run per active scenario parameter that moves
  // it, all at once; its alignment columns by central differences of the interpolation.
  bool EvaluateShot(int k, const std::vector<double>& x, double* residuals, double* jac) const {
    const int p = static_cast<int>(parameters_.size());
    const Shot& shot = shots_[k];
    std::vector<std::vector<double>> xs = {x};
    std::vector<int> column_of_run = {-1};
    for (int j = 0; jac && j < p; ++j)
      if (parameters_[j].kind == FitParameter::Kind::kScenario && active_[j] &&
          Moves(parameters_[j], k)) {
        xs.push_back(x);
        xs.back()[j] += Step(j);
        column_of_run.push_back(j);
      }
    std::string error;
    const auto sims = shot.simulator.Run(xs, &error);
    if (!sims[0]) return Reject(error);
    const int n = shot.residuals.count();
    double* r0 = residuals + shot.offset;
    const double fixed = options_.score.time_offset_s;
    const Alignment6 a = AlignmentOf(parameters_, x.data(), fixed, k);
    if (!shot.residuals.Evaluate(*sims[0], a, r0)) return Reject("the simulation ends early");
    if (!jac) return true;
    double* rows = jac + size_t(shot.offset) * p;
    std::vector<double> plus(n), minus(n);
    for (size_t r = 1; r < xs.size(); ++r) {
      const int j = column_of_run[r];
      if (!sims[r] || !shot.residuals.Evaluate(*sims[r], a, plus.data()))
        return Reject("a finite-difference run of " + parameters_[j].name + " failed: " + error);
      for (int i = 0; i < n; ++i) rows[size_t(i) * p + j] = (plus[i] - r0[i]) / Step(j);
    }
    for (int j = 0; j < p; ++j) {
      if (parameters_[j].kind == FitParameter::Kind::kScenario || !active_[j] ||
          parameters_[j].shot != k)
        continue;
      const double h = parameters_[j].kind == FitParameter::Kind::kTimeOffset ? 1e-5 : 1e-6;
      std::vector<double> xp = x, xm = x;
      xp[j] += h;
      xm[j] -= h;
      if (!shot.residuals.Evaluate(*sims[0], AlignmentOf(parameters_, xp.data(), fixed, k),
                                   plus.data()) ||
          !shot.residuals.Evaluate(*sims[0], AlignmentOf(parameters_, xm.data(), fixed, k),
                                   minus.data()))
        return Reject("the time offset leaves the simulated span");
      for (int i = 0; i < n; ++i) rows[size_t(i) * p + j] = (plus[i] - minus[i]) / (2 * h);
    }
    return true;
  }

  double Step(int j) const {
    return parameters_[j].log ? options_.step : options_.step * parameters_[j].spread;
  }
  bool Reject(const std::string& why) const {
    failure_ = why;
    return false;
  }
  void EvaluatePriors(const double* x, double* r, double* jac) const {
    const int p = static_cast<int>(parameters_.size());
    for (size_t i = 0; i < priors_.size(); ++i) {
      const PriorTerm& prior = priors_[i];
      const FitParameter& par = parameters_[prior.parameter];
      const double value = prior.anchor ? x[prior.parameter] : par.Value(x[prior.parameter]);
      r[i] = (value - prior.value) / prior.sigma;
      if (!jac) continue;
      std::fill(jac + i * p, jac + (i + 1) * p, 0.0);
      jac[i * p + prior.parameter] = (par.log && !prior.anchor ? value : 1.0) / prior.sigma;
    }
  }

  std::vector<bool> active_;
  const double margin_;  // s, how far the time offset may move
  const std::vector<FitParameter>& parameters_;
  std::vector<Shot>& shots_;
  int data_rows_ = 0;
  const std::vector<PriorTerm> priors_;
  const FitOptions& options_;
  mutable std::vector<double> last_x_, last_jacobian_;
  mutable std::string failure_;
};

// A report of the fit (FitOptions::progress says what it holds).
void ReportFit(const FitOptions& options, int start_index, const std::string& stage, int iteration,
               double cost, int simulations, long simulations_left) {
  if (!options.progress.reports()) return;
  std::string where;
  if (options.starts > 1)
    where = "start " + std::to_string(start_index + 1) + "/" + std::to_string(options.starts);
  if (!stage.empty()) where += (where.empty() ? "" : ", ") + std::string("stage ") + stage;
  char cost_text[32];
  std::snprintf(cost_text, sizeof cost_text, "%.6g", cost);
  const std::string detail =
      (iteration >= 0 ? "iteration " + std::to_string(iteration) + ", " : std::string()) + "cost " +
      cost_text;
  options.progress.Report(where, simulations, static_cast<double>(simulations + simulations_left),
                          detail);
}

// Progress once per Levenberg-Marquardt iteration; `after` (simulations of the stages after this
// one) and the run's own iterations left bound the ETA.
class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const FitOptions& options, const ShotCost& cost, int start_index,
                   std::string stage, const std::vector<bool>& active, long after)
      : options_(options),
        cost_(cost),
        start_index_(start_index),
        stage_(std::move(stage)),
        per_iteration_(cost.RunsPerIteration(active)),
        after_(after) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (options_.progress.cancelled()) return ceres::SOLVER_ABORT;  // LevenbergMarquardt throws
    // Ceres reports a rejected step's cost; the fit stays where it was.
    if (s.iteration == 0 || s.step_is_successful) cost_now_ = 2 * s.cost;
    const long left =
        static_cast<long>(options_.max_iterations - s.iteration) * per_iteration_ + after_;
    ReportFit(options_, start_index_, stage_, s.iteration, cost_now_, cost_.simulations(), left);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const FitOptions& options_;
  const ShotCost& cost_;
  int start_index_;
  std::string stage_;
  long per_iteration_;
  long after_;
  double cost_now_ = 0.0;  // the cost where the run stands
};

// Standard deviations and covariance of an information matrix that may be singular: the
// directions it leaves free get infinite variance (judged on the matrix scaled to unit diagonal).
Eigen::MatrixXd CovarianceOf(const Eigen::MatrixXd& information, Eigen::VectorXd* sigma) {
  const int p = static_cast<int>(information.rows());
  Eigen::VectorXd d(p);
  for (int i = 0; i < p; ++i) d(i) = information(i, i) > 0 ? 1 / std::sqrt(information(i, i)) : 0;
  const Eigen::MatrixXd scaled = d.asDiagonal() * information * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd free_weight = Eigen::VectorXd::Zero(p);
  const double floor = 1e-10 * std::max(1.0, eig.eigenvalues().maxCoeff());
  for (int k = 0; k < p; ++k) {
    const Eigen::VectorXd v = eig.eigenvectors().col(k);
    if (eig.eigenvalues()(k) > floor) {
      cov += v * v.transpose() / eig.eigenvalues()(k);
    } else {
      free_weight += v.cwiseAbs2();
    }
  }
  cov = d.asDiagonal() * cov * d.asDiagonal();
  sigma->resize(p);
  for (int i = 0; i < p; ++i)
    (*sigma)(i) = d(i) == 0 || free_weight(i) > 1e-6 ? kInf : std::sqrt(cov(i, i));
  return cov;
}

// Index of each prior's parameter (priors on parameters that are not free are left out), then an
// anchor for every log parameter without a prior.
std::vector<PriorTerm> PriorTerms(const std::vector<FitParameter>& parameters,
                                  const std::vector<FitPrior>& priors) {
  std::vector<PriorTerm> terms;
  std::vector<bool> has(parameters.size(), false);
  for (const FitPrior& prior : priors) {
    if (!(prior.sigma > 0) || !std::isfinite(prior.value))
      throw InputError(prior.source + ": the prior of " + prior.name +
                       " needs a finite value and a sigma > 0");
    for (size_t i = 0; i < parameters.size(); ++i)
      if (parameters[i].name == prior.name) {
        if (parameters[i].log && !(prior.value > 0))
          throw InputError(prior.source + ": the prior of " + prior.name + " is " +
                           std::to_string(prior.value) + "; a material or drag value is > 0");
        terms.push_back({static_cast<int>(i), prior.value, prior.sigma});
        has[i] = true;
      }
  }
  for (size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].log && !has[i])
      terms.push_back(
          {static_cast<int>(i), parameters[i].Coordinate(parameters[i].start), kAnchorSigma, true});
  return terms;
}

// The measured span, shifted by the offset (and as far as the offset may move), must overlap the
// scenario's own [0, duration]: the fit extends the simulation to the measured span's end, and a
// measurement 100 s after the launch (another clock's time, or ms read as s) would have it
// simulate 100 s of flight for every trial, for hours, before any message.
void CheckTimeOverlap(const FitShotInput& in, const Scenario& scenario, const FitOptions& options,
                      double margin) {
  const KnotTracks& measured = *in.measured;
  const double offset = options.score.time_offset_s;
  const double lo = measured.time.front() + offset, hi = measured.time.back() + offset;
  if (lo - margin <= scenario.duration && hi + margin >= 0.0) return;
  std::ostringstream os;
  os << in.measured_name << ": /time spans " << measured.time.front() << " .. "
     << measured.time.back() << " s; at --time-offset " << offset << " s (+- " << margin
     << " s) that is " << lo << " .. " << hi << " s of the simulation, which " << in.scenario_path
     << " runs over 0 .. " << scenario.duration
     << " s (duration): no overlap. Give the measured file's launch as its time 0, or the "
     << "offset between them as --time-offset";
  throw InputError(os.str());
}

// The simulated span the fit needs: the measured one shifted by the offset, with room for the
// offset to move and for the interpolation's stencil. The scenario's duration is cut or extended
// to it.
double FitDuration(const Scenario& scenario, const FitOptions& options, const KnotTracks& measured,
                   double margin, std::vector<ScenarioOverride>* set) {
  const double needed =
      measured.time.back() + options.score.time_offset_s + margin + 4 * scenario.output_interval;
  char value[32];
  std::snprintf(value, sizeof value, "%.17g", needed);
  set->push_back({"duration", value});
  return needed;
}

// An automatic step (integrator.dt: auto) is held for every run of the fit. The automatic step
// follows the bending stiffness (dt ~ 1/sqrt(EI)) in jumps, since it divides the output interval
// exactly; on Net A's implicit flight each jump changed the integrator's error by about as much as
// EI's own signal, and the cost along EI jumped by 100-400 between values 10 % apart (bench_fit
// landscape). The step held is the one stable over the start's box: the start's automatic step
// times, for each log material parameter, the ratio its step falls by at x2 or /2 of its start
// (probes of one output frame). A material stiffer still may step beyond its stability limit,
// which rejects that trial step. Returns the held step, 0 when the scenario gives its own.
double HoldStep(const std::string& path, const Scenario& scenario,
                const std::vector<FitParameter>& parameters, const std::vector<double>& x0,
                int shot, std::vector<ScenarioOverride>* set) {
  if (scenario.simulation.dt > 0.0) return 0.0;
  char value[32];
  std::snprintf(value, sizeof value, "%.17g", scenario.output_interval);
  auto step_at = [&](const std::vector<double>& x) {
    std::vector<ScenarioOverride> probe = *set;
    for (const ScenarioOverride& o : ScenarioOverrides(parameters, x, shot)) probe.push_back(o);
    probe.push_back({"duration", value});
    const SweepRun run = RunOne(path, 0, probe, 1);
    if (!run.ok() || !(run.summary.dt > 0.0))
      throw std::runtime_error(path + ": the starting simulation failed: " + run.error);
    return run.summary.dt;
  };
  const double start = step_at(x0);
  double dt = start;
  for (size_t i = 0; i < parameters.size(); ++i) {
    if (!IsMaterial(parameters[i])) continue;
    for (const double factor : {2.0, 0.5}) {
      std::vector<double> x = x0;
      x[i] += std::log(factor);
      dt *= std::min(1.0, step_at(x) / start);
    }
  }
  std::snprintf(value, sizeof value, "%.17g", dt);
  set->push_back({"integrator.dt", value});
  return dt;
}

// A start spread over the box around the first: ln 2 either way for log parameters, the spread
// for the other scenario parameters; the alignment starts where it was given.
std::vector<double> DrawStart(const std::vector<FitParameter>& parameters,
                              const std::vector<double>& x0, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> x = x0;
  for (size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].kind == FitParameter::Kind::kScenario)
      x[i] += (parameters[i].log ? std::log(2.0) : parameters[i].spread) * u(*rng);
  return x;
}

// `netlab score` of the fitted simulation, the rigid correction applied to it.
ScoreSummary FinalScore(const KnotTracks& measured, KnotTracks sim, const Alignment6& a,
                        const ScoreOptions& base, const std::string& measured_name) {
  for (Vector3d& p : sim.position) p = a.rotation * p + a.translation;
  ScoreOptions options = base;
  options.alignment = Alignment::kNone;
  options.time_offset_s = a.tau;
  return Score(measured, sim, options, measured_name, "the fitted simulation").summary;
}

// The quadratic model's promise, checked where it matters: along each scenario parameter in
// `check`, the cost two sigmas either side of the estimate over the rise the Jacobian predicts,
// (2 sigma_i)^2 (J^T J)_ii. About 1 on a smooth cost; far from 1 where the cost is rough (the
// simulation's discrete events, a chaotic response), where sigma means nothing. NaN: not checked.
// Two sigmas, not one: at one the predicted rise is about 1, and the simulation's own jitter in
// the cost (a few tenths on Net A's flight) moved well-determined launch velocities' ratios to
// 0.4 and 1.6.
std::vector<std::array<double, 2>> QuadraticCheck(const ShotCost& cost,
                                                  const std::vector<double>& best, double best_cost,
                                                  const Eigen::VectorXd& sigma,
                                                  const Eigen::MatrixXd& jtj,
                                                  const std::vector<bool>& check) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::array<double, 2>> ratio(best.size(), {kNaN, kNaN});
  std::vector<std::vector<double>> xs;
  std::vector<std::pair<int, int>> which;  // (parameter, side)
  for (size_t i = 0; i < best.size(); ++i)
    if (check[i])
      for (int side = 0; side < 2; ++side) {
        xs.push_back(best);
        xs.back()[i] += (side == 0 ? -2 : 2) * sigma(i);
        which.push_back({static_cast<int>(i), side});
      }
  if (xs.empty()) return ratio;
  const std::vector<double> costs = cost.CostsAt(xs);
  for (size_t r = 0; r < xs.size(); ++r) {
    const auto [i, side] = which[r];
    const double predicted = 4 * sigma(i) * sigma(i) * jtj(i, i);
    // A failed run is a cost that is not smooth there either.
    ratio[i][side] = std::isfinite(costs[r]) ? (costs[r] - best_cost) / predicted
                                             : std::numeric_limits<double>::infinity();
  }
  return ratio;
}

// Levenberg-Marquardt from *x over the `active` parameters (the others held).
void LevenbergMarquardt(ShotCost* cost, const std::vector<bool>& active, const FitOptions& options,
                        ProgressCallback callback, std::vector<double>* x,
                        ceres::Solver::Summary* summary) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(cost, nullptr, x->data());
  std::vector<int> held;
  for (size_t i = 0; i < active.size(); ++i)
    if (!active[i]) held.push_back(static_cast<int>(i));
  if (!held.empty())
    problem.SetManifold(x->data(), new ceres::SubsetManifold(static_cast<int>(x->size()), held));
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-8;
  solver.parameter_tolerance = 1e-8;
  solver.num_threads = 1;
  solver.callbacks.push_back(&callback);
  ceres::Solve(solver, &problem, summary);
  options.progress.ThrowIfCancelled();
  if (summary->termination_type == ceres::FAILURE && summary->iterations.empty())
    throw std::runtime_error("the fit could not start: " + cost->last_failure());
}

// Each shot with its residuals fixed by the start's simulation: the points it reaches and their
// weights.
std::vector<Shot> PrepareShots(const std::vector<FitShotInput>& inputs,
                               const std::vector<FitParameter>& parameters,
                               const FitOptions& options, const std::vector<double>& x0,
                               double margin, bool fit_time, FitResult* result) {
  std::vector<Shot> shots;
  shots.reserve(inputs.size());
  for (size_t k = 0; k < inputs.size(); ++k) {
    const FitShotInput& in = inputs[k];
    if (in.measured == nullptr || in.measured->frames() < 1)
      throw std::invalid_argument(in.measured_name + ": no frame");
    std::vector<ScenarioOverride> set = options.set;
    const Scenario scenario = LoadScenario(in.scenario_path, set);
    for (std::string& note : ResolutionNotes(scenario, parameters, in.scenario_path))
      result->notes.push_back(std::move(note));
    CheckTimeOverlap(in, scenario, options, margin);
    const double duration = FitDuration(scenario, options, *in.measured, margin, &set);
    const double dt =
        HoldStep(in.scenario_path, scenario, parameters, x0, static_cast<int>(k), &set);
    std::optional<ScenarioOverride> held_step;
    if (dt > 0.0) held_step = set.back();
    if (k == 0) {
      result->duration_s = duration;
      result->dt_s = dt;
    }
    Simulator simulator(in.scenario_path, static_cast<int>(k), std::move(set), parameters, options);
    std::string error;
    const auto first = simulator.Run({x0}, &error);
    if (!first[0])
      throw std::runtime_error(in.scenario_path + ": the starting simulation failed: " + error);
    Residuals residuals(*in.measured,
                        PrepareComparison(*in.measured, *first[0], options.score, in.measured_name,
                                          "the starting simulation"));
    // The points are kept a little beyond the bounds of the offset, for its central differences.
    residuals.Fix(*first[0], options.score.time_offset_s, fit_time ? margin + 1e-3 : 0.0,
                  options.score.sim_sigma_m);
    if (residuals.count() == 0)
      throw std::invalid_argument(in.measured_name + ": no measured knot-frame within the " +
                                  "simulated span (check --time-offset)");
    shots.push_back({std::move(residuals), std::move(simulator), 0, std::move(held_step)});
  }
  return shots;
}

// The prior given for a parameter, or null.
const FitPrior* PriorOf(const FitParameter& parameter, const FitOptions& options) {
  for (const FitPrior& prior : options.priors)
    if (prior.name == parameter.name) return &prior;
  return nullptr;
}

// The scan's runs along one material parameter: its values but the one the fit stands at, and
// that one too when a prior centres the scan elsewhere (ScanCoordinates).
long ScanRunsOf(const ShotCost& cost, const FitParameter& parameter, const FitOptions& options) {
  return (2L * options.scan_steps + (PriorOf(parameter, options) ? 1 : 0)) * cost.shots();
}

// The simulations of one scan: every shot at 2 x options.scan_steps points per material parameter
// (the middle one is where the scan stands, already run), and the middle one of a prior's.
long ScanRuns(const ShotCost& cost, const std::vector<FitParameter>& parameters,
              const FitOptions& options) {
  long runs = 0;
  if (options.scan_steps <= 0) return runs;
  for (const FitParameter& par : parameters)
    if (IsMaterial(par)) runs += ScanRunsOf(cost, par, options);
  return runs;
}

// The scan between the stages: along each material parameter in turn, the cost at
// options.scan_steps values per factor 2 either way of the current one (2 x 8: steps of 9 %), or
// over its prior's reach (ScanCoordinates), simulated at once, and the parameter moved to the
// lowest. Levenberg-Marquardt follows the cost from where it is, and a stiffness's cost in a
// flight is a narrow valley: the net's bending waves come back into phase away from it. On Net A's
// flight with the explicit integrator the cost along EI rises from x0.5 to x0.77 of the truth and
// falls again to it, a basin of about +-15 % (bench_fit landscape) that a start off by 2 does not
// reach by descending. Returns the rivals: for each parameter whose scan shows another local
// minimum behind a barrier (FindScanMinima), the point at the lowest such minimum, for the last
// stage to start from too (the other parameters not yet refitted there: the scan's costs only rank
// basins).
std::vector<std::pair<int, std::vector<double>>> ScanMaterial(
    const ShotCost& cost, const std::vector<FitParameter>& parameters, const FitOptions& options,
    int start_index, const std::string& stage, long after, std::vector<double>* x) {
  std::vector<std::pair<int, std::vector<double>>> rivals;
  if (options.scan_steps <= 0) return rivals;
  const int steps = options.scan_steps, n = 2 * steps + 1;
  long left = ScanRuns(cost, parameters, options);
  for (size_t i = 0; i < parameters.size(); ++i) {
    if (!IsMaterial(parameters[i])) continue;
    left -= ScanRunsOf(cost, parameters[i], options);
    const std::vector<double> along =
        ScanCoordinates(parameters[i], PriorOf(parameters[i], options), (*x)[i], steps);
    std::vector<std::vector<double>> xs(n, *x);
    for (int k = 0; k < n; ++k) xs[k][i] = along[k];
    const std::vector<double> c = cost.CostsAt(xs);
    options.progress.ThrowIfCancelled();
    const auto [best, rival] = FindScanMinima(c, steps);
    if (rival >= 0) rivals.push_back({static_cast<int>(i), xs[rival]});
    (*x)[i] = xs[best][i];
    ReportFit(options, start_index,
              stage + " " + parameters[i].name + (rival >= 0 ? " (2 minima)" : ""), -1, c[best],
              cost.simulations(), left + after);
  }
  return rivals;
}

// Where one run of the last stage ended: a start, or a rival minimum of the scan.
struct FitEnd {
  std::vector<double> x;
  double cost = kInf;
  std::string from;  // "start 2", "start 1, from the other valley of <parameter>"
};

// Levenberg-Marquardt from each start, in stages when material parameters are free: with others,
// first the launch, the drag and the alignment with the material held; then a scan along each
// material parameter (ScanMaterial); then everything, from the scan's best and its rivals.
// The material's signal in a flight is weak; fitted from a start far off in velocity or drag, the
// stiffnesses went where they explain the wrong launch (a net of EA = 26 N and EI = 4e-7 N m^2, a
// valley of wrong minima, in the twin's Net A flight). Returns the best end (its cost in
// result->cost_final); every usable end in *ends; *valley_found when a scan found another valley,
// *rival_failed when the last stage from one ended unusable.
std::vector<double> Minimise(ShotCost* cost, const std::vector<FitParameter>& parameters,
                             const FitOptions& options, const std::vector<double>& x0,
                             FitResult* result, std::vector<FitEnd>* ends, bool* valley_found,
                             bool* rival_failed) {
  const int p = static_cast<int>(parameters.size());
  std::vector<bool> all(p, true), launch(p);
  for (int i = 0; i < p; ++i) launch[i] = !IsMaterial(parameters[i]);
  const int others = static_cast<int>(std::count(launch.begin(), launch.end(), true));
  const bool staged = others % p != 0;  // material and others free: the material held first
  const bool scanned = others < p && options.scan_steps > 0;
  const int stages = 1 + staged + scanned;
  auto stage = [&](int k, const std::string& what) {
    return stages == 1 ? std::string()
                       : std::to_string(k) + "/" + std::to_string(stages) + " " + what;
  };
  // Upper bounds of the simulations left, for the ETA: a Levenberg-Marquardt run of each stage
  // (iteration 0 is its start's Jacobian), a whole start, and what follows the last start (the
  // quadratic check: two points per scenario parameter; the Jacobian at the best end when it is
  // not the last one taken).
  const long lm_all = (options.max_iterations + 1L) * cost->RunsPerIteration(all);
  const long lm_launch =
      staged ? (options.max_iterations + 1L) * cost->RunsPerIteration(launch) : 0;
  const long scan = scanned ? ScanRuns(*cost, parameters, options) : 0;
  const long per_start = lm_launch + scan + lm_all;
  const long simulated = std::count_if(parameters.begin(), parameters.end(), [](const auto& par) {
    return par.kind == FitParameter::Kind::kScenario;
  });
  const long finish = 2 * simulated * cost->shots() + cost->RunsPerIteration(all);
  std::mt19937 rng(options.seed);
  std::vector<double> best;
  result->cost_initial = cost->CostsAt({x0})[0];  // the start's run is remembered: no simulation
  result->cost_final = kInf;
  // The last stage from x; its end kept when usable, and the best end remembered.
  // `after`: the simulations after this run (its start's other valleys, the later starts, the
  // check).
  auto last_stage = [&](std::vector<double> x, int s, const std::string& from, long after,
                        ceres::Solver::Summary* summary) -> bool {
    LevenbergMarquardt(
        cost, all, options,
        ProgressCallback(options, *cost, s,
                         stage(stages, "all") + (from.empty() || stages == 1 ? "" : ", " + from),
                         all, after),
        &x, summary);
    result->iterations += static_cast<int>(summary->iterations.size()) - 1;
    if (!summary->IsSolutionUsable()) return false;
    const std::string name = "start " + std::to_string(s + 1) + (from.empty() ? "" : ", " + from);
    ends->push_back({x, 2 * summary->final_cost, name});
    if (2 * summary->final_cost < result->cost_final) {
      result->cost_final = 2 * summary->final_cost;
      best = x;
      result->best_start = s;
      result->termination = summary->message;
    }
    return true;
  };
  for (int s = 0; s < options.starts; ++s) {
    std::vector<double> x = s == 0 ? x0 : DrawStart(parameters, x0, &rng);
    ceres::Solver::Summary summary;
    std::vector<std::pair<int, std::vector<double>>> rivals;
    const long later = (options.starts - 1 - s) * per_start + finish;
    if (staged) {
      cost->SetActive(launch);
      LevenbergMarquardt(cost, launch, options,
                         ProgressCallback(options, *cost, s, stage(1, "material held"), launch,
                                          scan + lm_all + later),
                         &x, &summary);
      result->iterations += static_cast<int>(summary.iterations.size()) - 1;
      cost->SetActive(all);
      if (summary.termination_type == ceres::FAILURE) continue;
    }
    if (scanned)
      rivals = ScanMaterial(*cost, parameters, options, s, stage(1 + staged, "scan"),
                            lm_all + later, &x);
    long valleys = static_cast<long>(rivals.size());
    last_stage(x, s, "", valleys * lm_all + later, &summary);
    for (const auto& [i, rival] : rivals) {
      *valley_found = true;
      if (!last_stage(rival, s, "from the other valley of " + parameters[i].name,
                      --valleys * lm_all + later, &summary))
        *rival_failed = true;
    }
  }
  if (best.empty()) throw std::runtime_error("the fit failed: " + cost->last_failure());
  return best;
}

// The Jacobian at x (Ceres' last one when it was taken there), row-major.
std::vector<double> JacobianAt(const ShotCost& cost, const std::vector<double>& x) {
  std::vector<double> jac;
  if (cost.JacobianAt(x, &jac)) return jac;
  std::vector<double> r(cost.num_residuals());
  jac.resize(size_t(cost.num_residuals()) * x.size());
  const double* blocks[] = {x.data()};
  double* jacobians[] = {jac.data()};
  if (!cost.Evaluate(blocks, r.data(), jacobians))
    throw std::runtime_error("the Jacobian at the fit failed: " + cost.last_failure());
  return jac;
}

// The --set lines that rerun shot `shot` as fitted: the user's own (integrator.type=explicit, a
// changed duration...) but those the fitted values replace whole (a free parameter's, or a list
// whose every item is free), then the fitted values, which come later and so win where a user's
// line set a list or a section only in part.
std::vector<ScenarioOverride> FittedSet(const std::vector<FitParameter>& parameters,
                                        const std::vector<ScenarioOverride>& set,
                                        const std::vector<double>& x, int shot) {
  // The items of a list value, read as ApplyOverride reads it; 0 if not a list.
  auto items = [](const std::string& value) {
    try {
      const YAML::Node node = YAML::Load(value);
      return node.IsSequence() ? static_cast<int>(node.size()) : 0;
    } catch (const YAML::Exception&) {
      return 0;
    }
  };
  std::vector<ScenarioOverride> out;
  for (const ScenarioOverride& o : set) {
    int free_items = 0;
    bool exact = false;
    for (const FitParameter& p : parameters) {
      if (p.kind != FitParameter::Kind::kScenario || !Moves(p, shot)) continue;
      exact |= p.path == o.path;
      free_items += p.path.rfind(o.path + ".", 0) == 0;
    }
    if (!exact && !(free_items > 0 && free_items == items(o.value))) out.push_back(o);
  }
  for (const ScenarioOverride& o : ScenarioOverrides(parameters, x, shot)) out.push_back(o);
  return out;
}

// Every shot's score at the fit, and the data's information, each shot's rows divided by the
// inflation its score finds for correlated residuals (and by its reduced chi^2 above 1).
Eigen::MatrixXd DataInformation(const std::vector<FitShotInput>& inputs,
                                const std::vector<Shot>& shots,
                                const std::vector<FitParameter>& parameters,
                                const FitOptions& options, const std::vector<double>& best,
                                const Eigen::MatrixXd& j, FitResult* result) {
  const int p = static_cast<int>(parameters.size());
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(p, p);
  for (size_t k = 0; k < shots.size(); ++k) {
    const int kk = static_cast<int>(k);
    std::string error;
    const auto sim = shots[k].simulator.Run({best}, &error);
    if (!sim[0]) throw std::runtime_error("the fitted simulation failed: " + error);
    const Alignment6 a = AlignmentOf(parameters, best.data(), options.score.time_offset_s, kk);
    const ScoreSummary score =
        FinalScore(*inputs[k].measured, *sim[0], a, options.score, inputs[k].measured_name);
    const double inflation = std::max(1.0, score.tau_int) * std::max(1.0, score.design_effect) *
                             std::max(1.0, score.mean_d2 / 3.0);
    const auto rows = j.middleRows(shots[k].offset, shots[k].residuals.count());
    information += rows.transpose() * rows / inflation;
    result->scores.push_back(score);
    result->inflations.push_back(inflation);
    result->fitted_sets.push_back(FittedSet(parameters, options.set, best, kk));
    if (shots[k].held_step) result->fitted_sets.back().push_back(*shots[k].held_step);
    result->inflation = std::max(result->inflation, inflation);
  }
  result->score = result->scores.front();
  result->fitted_set = result->fitted_sets.front();
  return information;
}

// An end counts as fitting as well as the best when its cost is within chi^2_1's 95 % quantile
// of the best's, times the data's inflation.
constexpr double kAsWell = 3.841458820694124;

// Why a material parameter whose sigma is small is not marked identified when the only doubt is
// another basin of the cost (Report).
std::string AnotherBasinNote(const FittedParameter& f) {
  char numbers[160];
  std::snprintf(numbers, sizeof numbers,
                " (%.4g +- %.3g) is not marked identified although its sigma is small: ", f.value,
                f.sigma);
  std::string where;
  if (std::isnan(f.alternative)) {
    where =
        "a last stage of the fit from the scan's other valley failed, so where that valley "
        "leads is unknown";
  } else {
    char other[160];
    std::snprintf(other, sizeof other, "%.4g there, its cost %+.3g", f.alternative,
                  f.alternative_rise);
    where = "a last stage of the fit (" + f.alternative_from + ") ended in another basin (" +
            other + ")";
  }
  return f.parameter.name + numbers + where +
         ". fit marks no material parameter identified while another basin stands, however much "
         "worse that basin fits: its scans look along one parameter at a time, and the basin the "
         "truth is in can be the one that fits worse (docs/fit.md, Several valleys). The estimate "
         "is the best end found; a bench prior (--prior) settles which basin is the thread's";
}

// Estimates, sigmas, whether each is identified (sigma below half the reference spread: the
// prior's sigma, else the parameter's spread, fit_parameters.h), for the scenario ones that
// look identified whether the cost is smooth enough for sigma to mean something, and whether
// another end of the fit fits as well.
void Report(const ShotCost& cost, const std::vector<FitParameter>& parameters,
            const std::vector<PriorTerm>& priors, const std::vector<double>& best,
            const std::vector<FitEnd>& ends, bool valley_found, bool rival_failed,
            const Eigen::VectorXd& sigma, const Eigen::VectorXd& data_sigma,
            const Eigen::MatrixXd& jtj, FitResult* result) {
  const int p = static_cast<int>(parameters.size());
  std::vector<bool> looks_identified(p), check(p);
  for (int i = 0; i < p; ++i) {
    double reference = parameters[i].spread;  // in coordinate units
    for (const PriorTerm& prior : priors)
      if (prior.parameter == i && !prior.anchor)
        reference = parameters[i].log ? prior.sigma / prior.value : prior.sigma;
    looks_identified[i] = sigma(i) < 0.5 * reference;
    check[i] = looks_identified[i] && parameters[i].kind == FitParameter::Kind::kScenario;
  }
  const auto ratio = QuadraticCheck(cost, best, result->cost_final, sigma, jtj, check);
  // Another basin: when a scan found another valley, an end of the fit with a material parameter
  // beyond 2 sigma of the estimate, however well it fits, or a last stage from such a valley that
  // failed. The scan saw one parameter at a time, and the basin the truth is in can be the one
  // that looks worse (Net A's explicit flight: from EA x2 and EI x0.5 the fit ended at EA x2 and
  // EI x0.35, smooth and within the noise, the truth's cost about 170 lower; the fit from the
  // scan's other valley of EI ended 84 above it, elsewhere). Then every material parameter is in
  // doubt, not only the one whose scan found the valley: there EA was as wrong as EI. When every
  // last stage came back to the same end, the scan's second valley was one parameter's view of a
  // single basin.
  const FitEnd* elsewhere = nullptr;
  if (valley_found) {
    std::vector<std::vector<double>> xs;
    for (const FitEnd& e : ends) xs.push_back(e.x);
    std::vector<bool> material(p);
    for (int j = 0; j < p; ++j) material[j] = IsMaterial(parameters[j]);
    const int k = EndElsewhere(xs, best, {sigma.data(), sigma.data() + p}, material);
    if (k >= 0) elsewhere = &ends[k];
  }
  const bool another_basin = elsewhere != nullptr || rival_failed;
  for (int i = 0; i < p; ++i) {
    const FitParameter& par = parameters[i];
    FittedParameter f;
    f.parameter = par;
    f.value = par.Value(best[i]);
    const double scale = par.log ? f.value : 1.0;  // d value / d coordinate
    f.sigma = sigma(i) * scale;
    f.data_sigma = data_sigma(i) * scale;
    for (const PriorTerm& prior : priors)
      if (prior.parameter == i && !prior.anchor) {
        f.has_prior = true;
        f.prior_value = prior.value;
        f.prior_sigma = prior.sigma;
      }
    f.check = ratio[i];
    // Smooth: the cost at -+2 sigma within a factor 2 of the quadratic model's rise.
    f.rough = check[i] && !(std::min(ratio[i][0], ratio[i][1]) > 0.5 &&
                            std::max(ratio[i][0], ratio[i][1]) < 2.0);
    // Another end of the fit (a start, the scan's other valley) that fits as well with this
    // parameter beyond 2 sigma of the estimate: the data do not tell the two apart. And, for a
    // material parameter, another basin (above).
    for (const FitEnd& e : ends) {
      if (e.cost - result->cost_final < kAsWell * result->inflation &&
          std::abs(e.x[i] - best[i]) > 2 * sigma(i)) {
        f.ambiguous = true;
        f.alternative = par.Value(e.x[i]);
        f.alternative_rise = e.cost - result->cost_final;
        f.alternative_from = e.from;
        break;
      }
    }
    if (!f.ambiguous && another_basin && IsMaterial(par)) {
      f.ambiguous = true;
      if (elsewhere != nullptr) {
        f.alternative = par.Value(elsewhere->x[i]);
        f.alternative_rise = elsewhere->cost - result->cost_final;
        f.alternative_from = elsewhere->from;
      }
      // Held back by the other basin alone, however much worse it fits: say so in words.
      if (looks_identified[i] && !f.rough) result->notes.push_back(AnotherBasinNote(f));
    }
    f.identified = looks_identified[i] && !f.rough && !f.ambiguous;
    f.determined_by = f.identified  ? DeterminedBy::kFlightData
                      : f.has_prior ? DeterminedBy::kPrior
                                    : DeterminedBy::kNeither;
    result->parameters.push_back(f);
  }
}

}  // namespace

int EndElsewhere(const std::vector<std::vector<double>>& ends, const std::vector<double>& best,
                 const std::vector<double>& sigma, const std::vector<bool>& material) {
  for (size_t k = 0; k < ends.size(); ++k)
    for (size_t j = 0; j < best.size(); ++j)
      if (material[j] && std::abs(ends[k][j] - best[j]) > 2 * sigma[j]) return static_cast<int>(k);
  return -1;
}

std::string DeterminedByName(DeterminedBy by) {
  switch (by) {
    case DeterminedBy::kFlightData: return "flight data";
    case DeterminedBy::kPrior: return "prior";
    case DeterminedBy::kNeither: return "neither";
  }
  return "?";
}

std::string PriorConflictNote(const FittedParameter& f, const std::string& source) {
  if (!f.has_prior || !(f.prior_sigma > 0)) return "";
  const double away = (f.value - f.prior_value) / f.prior_sigma;
  if (!(std::abs(away) > kPriorReach)) return "";
  char numbers[128];
  std::snprintf(numbers, sizeof numbers, " at %.4g, %.1f sigma from its prior (%.4g +- %.3g",
                f.value, away, f.prior_value, f.prior_sigma);
  return "the fit puts " + f.parameter.name + numbers + (source.empty() ? "" : ", " + source) +
         "): the flight and the bench disagree. A model coarser than the flight biases what it "
         "fits (docs/fit.md, Limits), or the bench did not measure this thread";
}

std::vector<double> ScanCoordinates(const FitParameter& parameter, const FitPrior* prior,
                                    double current, int steps) {
  double centre = current, half = std::log(2.0);
  if (prior != nullptr && prior->value > 0 && prior->sigma > 0) {
    centre = parameter.Coordinate(prior->value);
    half = std::min(half, kPriorReach * prior->sigma / prior->value);
  }
  std::vector<double> along;
  for (int k = -steps; k <= steps; ++k)
    along.push_back(k == 0 ? centre : centre + half * k / std::max(steps, 1));
  return along;
}

ScanMinima FindScanMinima(const std::vector<double>& costs, int current, double barrier) {
  const int n = static_cast<int>(costs.size());
  ScanMinima m;
  if (current < 0 || current >= n) return m;
  std::vector<double> c = costs;
  for (double& v : c)
    if (!std::isfinite(v)) v = kInf;  // a failed run: no minimum there
  m.best = current;
  for (int k = 0; k < n; ++k)
    if (c[k] < c[m.best]) m.best = k;
  for (int k = 0; k < n; ++k) {
    const bool minimum =
        std::isfinite(c[k]) && (k == 0 || c[k] < c[k - 1]) && (k == n - 1 || c[k] < c[k + 1]);
    if (!minimum || k == m.best) continue;
    const auto [lo, hi] = std::minmax(k, m.best);
    const double top = *std::max_element(c.begin() + lo, c.begin() + hi + 1);
    if (top - std::max(c[k], c[m.best]) >= barrier && (m.rival < 0 || c[k] < c[m.rival]))
      m.rival = k;
  }
  return m;
}

std::vector<std::string> ResolutionNotes(const Scenario& scenario,
                                         const std::vector<FitParameter>& parameters,
                                         const std::string& name) {
  std::vector<std::string> notes;
  for (const FitParameter& par : parameters) {
    // materials.<material>.bend_stiffness
    const std::string key = ".bend_stiffness";
    if (!IsMaterial(par) || !par.path.ends_with(key)) continue;
    const size_t first = std::string("materials.").size();
    const std::string material = par.path.substr(first, par.path.size() - first - key.size());
    for (size_t n = 0; n < scenario.nets.size(); ++n) {
      const NetSpec& net = scenario.nets[n];
      if (scenario.materials[net.material].name != material) continue;
      const double segment = net.mesh / net.segments_per_link;
      if (segment <= kBendingSegment * 1.001) continue;
      char size[64];
      std::snprintf(size, sizeof size, "%.3g cm segments (%d per link)", segment * 100,
                    net.segments_per_link);
      // The step matters as much as the links: the implicit step damps the bending response
      // at any resolution (docs/simulator.md, "Accuracy as the response to a parameter").
      const std::string step =
          scenario.simulation.integrator == IntegratorType::kImplicit
              ? " The implicit step hides most of EI's effect whatever the links (0.15 of "
                "those 1.23 mm at 2.5 cm segments, 0.75 of the 1.46 mm at 1.25 cm): fit EI with "
                "--set integrator.type=explicit."
              : "";
      notes.push_back(
          "net '" + net.name + "' of " + name + " has " + size +
          ", coarser than EI's bending in a flight: the fitted " + par.name +
          " is this model's, not the thread's (Net A's first 1 s of flight, explicit step: EI x4 "
          "moves the knots 1.23 mm RMS at 2.5 cm segments, 1.46 mm at 1.25 cm; "
          "docs/simulator.md)." +
          step + " To fit the thread's, refine the links: --set nets." + std::to_string(n) +
          ".segments_per_link=" +
          std::to_string(static_cast<int>(std::ceil(net.mesh / kBendingSegment - 1e-9))) +
          ", with the bench's values as a prior (--prior) to pick the valley");
    }
  }
  return notes;
}

FitResult FitShot(const std::string& scenario_path, const KnotTracks& measured,
                  const std::vector<FitParameter>& parameters, const FitOptions& options,
                  const std::string& measured_name) {
  return FitShots({{scenario_path, &measured, measured_name}}, parameters, options);
}

// FitShots, before its check for a cancel.
static FitResult RunFit(const std::vector<FitShotInput>& inputs,
                        const std::vector<FitParameter>& parameters, const FitOptions& options) {
  const auto start = Clock::now();
  if (inputs.empty()) throw std::invalid_argument("fit: no shot");
  if (options.starts < 1 || options.max_iterations < 1 || !(options.step > 0))
    throw std::invalid_argument("fit options: starts, max_iterations and step must be positive");
  for (const FitParameter& par : parameters)
    if (par.shot >= static_cast<int>(inputs.size()))
      throw std::invalid_argument("fit: " + par.name + " belongs to a shot that is not given");
  const int p = static_cast<int>(parameters.size());
  bool fit_time = false;
  for (const FitParameter& par : parameters)
    fit_time |= par.kind == FitParameter::Kind::kTimeOffset;
  // How far the time offset may move: --max-time-offset, at most 50 ms and a tenth of the
  // shortest measured span. The points the simulation does not reach at every offset within it
  // are left out, so a wide margin would leave a short shot nothing (16 frames span 84 ms).
  double span = kInf;
  for (const FitShotInput& in : inputs)
    if (in.measured != nullptr && in.measured->frames() > 0)
      span = std::min(span, in.measured->time.back() - in.measured->time.front());
  const double margin =
      fit_time ? std::min({options.score.max_time_offset_s, 0.05, 0.1 * span}) : 0.0;
  const std::vector<PriorTerm> priors = PriorTerms(parameters, options.priors);
  std::vector<double> x0(p);
  for (int i = 0; i < p; ++i) x0[i] = parameters[i].Coordinate(parameters[i].start);

  FitResult result;
  std::vector<Shot> shots =
      PrepareShots(inputs, parameters, options, x0, margin, fit_time, &result);
  ShotCost cost(parameters, &shots, priors, options, margin);
  result.residuals = cost.data_rows();
  std::vector<FitEnd> ends;
  bool valley_found = false, rival_failed = false;
  const std::vector<double> best =
      Minimise(&cost, parameters, options, x0, &result, &ends, &valley_found, &rival_failed);

  // The covariance: the data's information (inflated per shot) plus the priors'.
  const std::vector<double> jac = JacobianAt(cost, best);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(
      jac.data(), cost.num_residuals(), p);
  const Eigen::MatrixXd data_information =
      DataInformation(inputs, shots, parameters, options, best, j, &result);
  const auto prior_rows = j.bottomRows(priors.size());
  Eigen::VectorXd sigma, data_sigma;
  result.covariance = CovarianceOf(data_information + prior_rows.transpose() * prior_rows, &sigma);
  CovarianceOf(data_information, &data_sigma);
  result.correlation = Eigen::MatrixXd::Identity(p, p);
  for (int r = 0; r < p; ++r)
    for (int c = 0; c < p; ++c)
      if (r != c && std::isfinite(sigma(r)) && std::isfinite(sigma(c)) && sigma(r) * sigma(c) > 0)
        result.correlation(r, c) = result.covariance(r, c) / (sigma(r) * sigma(c));
      else if (r != c)
        result.correlation(r, c) = std::numeric_limits<double>::quiet_NaN();

  Report(cost, parameters, priors, best, ends, valley_found, rival_failed, sigma, data_sigma,
         j.transpose() * j, &result);
  for (const FittedParameter& f : result.parameters)
    if (const FitPrior* prior = PriorOf(f.parameter, options)) {
      const std::string note = PriorConflictNote(f, prior->source);
      if (!note.empty()) result.notes.push_back(note);
    }
  result.ends = static_cast<int>(ends.size());
  result.simulations = cost.simulations();
  result.wall_s = Seconds(start);
  return result;
}

FitResult FitShots(const std::vector<FitShotInput>& inputs,
                   const std::vector<FitParameter>& parameters, const FitOptions& options) {
  try {
    FitResult result = RunFit(inputs, parameters, options);
    options.progress.ThrowIfCancelled();  // a result reached while cancelling is not the fit's
    return result;
  } catch (const Cancelled&) {
    throw;
  } catch (...) {
    options.progress.ThrowIfCancelled();  // runs that failed because they were cancelled
    throw;
  }
}

}  // namespace netlab::netsim
