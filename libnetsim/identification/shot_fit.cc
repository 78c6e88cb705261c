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
#include <random>
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

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// The alignment parameters of coordinates x: the time offset and the rigid correction.
struct Alignment6 {
  double tau = 0.0;
  Matrix3d rotation = Matrix3d::Identity();
  Vector3d translation = Vector3d::Zero();
};

Alignment6 AlignmentOf(const std::vector<FitParameter>& parameters, const double* x,
                       double fixed_tau) {
  Alignment6 a;
  a.tau = fixed_tau;
  Vector3d w = Vector3d::Zero();
  for (size_t i = 0; i < parameters.size(); ++i) {
    const FitParameter& p = parameters[i];
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

// Runs simulations of scenario-parameter vectors, several at a time, remembering the last few.
class Simulator {
 public:
  Simulator(const std::string& scenario_path, const std::vector<FitParameter>& parameters,
            const FitOptions& options)
      : path_(scenario_path), parameters_(parameters), options_(options) {}

  // The knot tracks of every coordinate vector (full x; only the scenario parameters matter), in
  // order; an empty pointer for a run that failed (its reason in *error).
  std::vector<std::shared_ptr<const KnotTracks>> Run(const std::vector<std::vector<double>>& xs,
                                                     std::string* error) {
    std::vector<std::shared_ptr<const KnotTracks>> out(xs.size());
    std::vector<std::vector<ScenarioOverride>> runs;
    std::vector<size_t> which;
    for (size_t i = 0; i < xs.size(); ++i) {
      const std::vector<double> key = ScenarioPart(xs[i]);
      if (const auto hit = cache_.find(key); hit != cache_.end()) {
        out[i] = hit->second;
        continue;
      }
      std::vector<ScenarioOverride> set = options_.set;
      for (const ScenarioOverride& o : ScenarioOverrides(parameters_, xs[i])) set.push_back(o);
      runs.push_back(std::move(set));
      which.push_back(i);
    }
    if (runs.empty()) return out;
    SweepOptions sweep;
    sweep.jobs = options_.jobs;
    sweep.on_run = [this](const SweepRun&, int, int) { ++simulations_; };
    SweepResult result = RunSweep(path_, runs, sweep);
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
      if (parameters_[i].kind == FitParameter::Kind::kScenario) key.push_back(x[i]);
    return key;
  }

  const std::string& path_;
  const std::vector<FitParameter>& parameters_;
  const FitOptions& options_;
  std::map<std::vector<double>, std::shared_ptr<const KnotTracks>> cache_;
  int simulations_ = 0;
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


// The whole least-squares problem as one Ceres cost: data residuals, then prior residuals.
class ShotCost : public ceres::CostFunction {
 public:
  ShotCost(const std::vector<FitParameter>& parameters, const Residuals& residuals,
           Simulator* simulator, std::vector<PriorTerm> priors, const FitOptions& options,
           double margin)
      : active_(parameters.size(), true),
        margin_(margin),
        parameters_(parameters),
        residuals_(residuals),
        simulator_(simulator),
        priors_(std::move(priors)),
        options_(options) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(parameters.size()));
    set_num_residuals(residuals.count() + static_cast<int>(priors_.size()));
  }

  bool Evaluate(double const* const* x_blocks, double* residuals,
                double** jacobians) const override {
    const int p = static_cast<int>(parameters_.size());
    const std::vector<double> x(x_blocks[0], x_blocks[0] + p);
    // The offset's range, as a rejected step rather than a Ceres bound: a bound makes Ceres
    // search along the projected step, a Jacobian (a batch of simulations) per trial.
    const double tau = AlignmentOf(parameters_, x.data(), options_.score.time_offset_s).tau;
    if (std::abs(tau - options_.score.time_offset_s) > margin_)
      return Reject("the time offset left its range");
    const bool jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    std::vector<std::vector<double>> xs = {x};
    std::vector<int> column_of_run = {-1};
    if (jacobian)
      for (int j = 0; j < p; ++j)
        if (parameters_[j].kind == FitParameter::Kind::kScenario && active_[j]) {
          xs.push_back(x);
          xs.back()[j] += Step(j);
          column_of_run.push_back(j);
        }
    std::string error;
    const auto sims = simulator_->Run(xs, &error);
    if (!sims[0]) return Reject(error);
    const int n = residuals_.count();
    const Alignment6 a = AlignmentOf(parameters_, x.data(), options_.score.time_offset_s);
    if (!residuals_.Evaluate(*sims[0], a, residuals)) return Reject("the simulation ends early");
    EvaluatePriors(x.data(), residuals + n, jacobian ? jacobians[0] + size_t(n) * p : nullptr);
    if (!jacobian) return true;
    double* jac = jacobians[0];
    for (int j = 0; j < p; ++j)
      if (!active_[j])
        for (int i = 0; i < n; ++i) jac[size_t(i) * p + j] = 0.0;
    std::vector<double> plus(n), minus(n);
    for (size_t r = 1; r < xs.size(); ++r) {
      const int j = column_of_run[r];
      if (!sims[r] || !residuals_.Evaluate(*sims[r], a, plus.data()))
        return Reject("a finite-difference run of " + parameters_[j].name + " failed: " + error);
      for (int i = 0; i < n; ++i) jac[size_t(i) * p + j] = (plus[i] - residuals[i]) / Step(j);
    }
    for (int j = 0; j < p; ++j) {
      if (parameters_[j].kind == FitParameter::Kind::kScenario || !active_[j]) continue;
      // Alignment columns: central differences of the interpolation, no simulation.
      const double h = parameters_[j].kind == FitParameter::Kind::kTimeOffset ? 1e-5 : 1e-6;
      std::vector<double> xp = x, xm = x;
      xp[j] += h;
      xm[j] -= h;
      const double fixed = options_.score.time_offset_s;
      if (!residuals_.Evaluate(*sims[0], AlignmentOf(parameters_, xp.data(), fixed), plus.data()) ||
          !residuals_.Evaluate(*sims[0], AlignmentOf(parameters_, xm.data(), fixed), minus.data()))
        return Reject("the time offset leaves the simulated span");
      for (int i = 0; i < n; ++i) jac[size_t(i) * p + j] = (plus[i] - minus[i]) / (2 * h);
    }
    if (std::find(active_.begin(), active_.end(), false) == active_.end()) {
      last_x_ = x;
      last_jacobian_.assign(jac, jac + size_t(num_residuals()) * p);
    }
    return true;
  }

  // Which parameters the next evaluations move (the others' columns are zero, unsimulated).
  void SetActive(std::vector<bool> active) { active_ = std::move(active); }

  // The cost (data and priors, sum of squares) at x from its simulation; NaN when the simulation
  // does not reach a point.
  double CostWith(const std::vector<double>& x, const KnotTracks& sim) const {
    std::vector<double> r(num_residuals());
    const Alignment6 a = AlignmentOf(parameters_, x.data(), options_.score.time_offset_s);
    if (!residuals_.Evaluate(sim, a, r.data())) return std::numeric_limits<double>::quiet_NaN();
    EvaluatePriors(x.data(), r.data() + residuals_.count(), nullptr);
    double sum = 0.0;
    for (double v : r) sum += v * v;
    return sum;
  }

  // The Jacobian (row-major, num_residuals x p) at x when the last evaluation was there.
  bool JacobianAt(const std::vector<double>& x, std::vector<double>* jacobian) const {
    if (x != last_x_) return false;
    *jacobian = last_jacobian_;
    return true;
  }
  const std::string& last_failure() const { return failure_; }

 private:
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
  const Residuals& residuals_;
  Simulator* simulator_;
  const std::vector<PriorTerm> priors_;
  const FitOptions& options_;
  mutable std::vector<double> last_x_, last_jacobian_;
  mutable std::string failure_;
};

// Progress once per Levenberg-Marquardt iteration.
class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const FitOptions& options, const Simulator& simulator, Clock::time_point start,
                   int start_index, std::string stage = "")
      : options_(options),
        simulator_(simulator),
        start_(start),
        start_index_(start_index),
        stage_(std::move(stage)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (options_.progress) {
      FitProgress p;
      p.iteration = s.iteration;
      p.cost = 2 * s.cost;
      p.simulations = simulator_.simulations();
      p.elapsed_s = Seconds(start_);
      const int left = (options_.max_iterations - s.iteration) +
                       (options_.starts - 1 - start_index_) * options_.max_iterations;
      p.eta_s = s.iteration > 0 ? p.elapsed_s / (s.iteration + start_index_ *
                                                                   options_.max_iterations) *
                                      left
                                : 0.0;
      p.start = start_index_;
      p.starts = options_.starts;
      p.stage = stage_;
      options_.progress(p);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const FitOptions& options_;
  const Simulator& simulator_;
  Clock::time_point start_;
  int start_index_;
  std::string stage_;
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
      terms.push_back({static_cast<int>(i), parameters[i].Coordinate(parameters[i].start),
                       kAnchorSigma, true});
  return terms;
}

// The simulated span the fit needs: the measured one shifted by the offset, with room for the
// offset to move and for the interpolation's stencil.
double FitDuration(const std::string& path, const FitOptions& options, const KnotTracks& measured,
                   double margin, std::vector<ScenarioOverride>* set) {
  const Scenario scenario = LoadScenario(path, options.set);
  const double needed = measured.time.back() + options.score.time_offset_s + margin +
                        4 * scenario.output_interval;
  if (needed >= scenario.duration) return scenario.duration;
  char value[32];
  std::snprintf(value, sizeof value, "%.17g", needed);
  set->push_back({"duration", value});
  return needed;
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
// `check`, the cost one sigma either side of the estimate over the rise the Jacobian predicts,
// sigma_i^2 (J^T J)_ii. About 1 on a smooth cost; far from 1 where the cost is rough (the
// simulation's discrete events, a chaotic response), where sigma means nothing. NaN: not checked.
std::vector<std::array<double, 2>> QuadraticCheck(const ShotCost& cost, Simulator* simulator,
                                                  const std::vector<double>& best,
                                                  double best_cost, const Eigen::VectorXd& sigma,
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
        xs.back()[i] += (side == 0 ? -1 : 1) * sigma(i);
        which.push_back({static_cast<int>(i), side});
      }
  if (xs.empty()) return ratio;
  std::string error;
  const auto sims = simulator->Run(xs, &error);
  for (size_t r = 0; r < xs.size(); ++r) {
    const auto [i, side] = which[r];
    const double predicted = sigma(i) * sigma(i) * jtj(i, i);
    // A failed run is a cost that is not smooth there either.
    ratio[i][side] = sims[r] ? (cost.CostWith(xs[r], *sims[r]) - best_cost) / predicted
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
  if (summary->termination_type == ceres::FAILURE && summary->iterations.empty())
    throw std::runtime_error("the fit could not start: " + cost->last_failure());
}

}  // namespace

FitResult FitShot(const std::string& scenario_path, const KnotTracks& measured,
                  const std::vector<FitParameter>& parameters, const FitOptions& options_in,
                  const std::string& measured_name) {
  const auto start = Clock::now();
  FitOptions options = options_in;
  if (options.starts < 1 || options.max_iterations < 1 || !(options.step > 0))
    throw std::invalid_argument("fit options: starts, max_iterations and step must be positive");
  const int p = static_cast<int>(parameters.size());
  bool fit_time = false;
  for (const FitParameter& par : parameters)
    fit_time |= par.kind == FitParameter::Kind::kTimeOffset;
  const double margin = fit_time ? std::min(options.score.max_time_offset_s, 0.05) : 0.0;

  FitResult result;
  if (measured.frames() < 1) throw std::invalid_argument(measured_name + ": no frame");
  result.duration_s = FitDuration(scenario_path, options_in, measured, margin, &options.set);
  const std::vector<PriorTerm> priors = PriorTerms(parameters, options.priors);

  // The start's simulation fixes the points and their weights.
  std::vector<double> x0(p);
  for (int i = 0; i < p; ++i) x0[i] = parameters[i].Coordinate(parameters[i].start);
  Simulator simulator(scenario_path, parameters, options);
  std::string error;
  const auto first = simulator.Run({x0}, &error);
  if (!first[0]) throw std::runtime_error("the starting simulation failed: " + error);
  Residuals residuals(measured, PrepareComparison(measured, *first[0], options.score,
                                                  measured_name, "the starting simulation"));
  // The points are kept a little beyond the bounds of the offset, for its central differences.
  residuals.Fix(*first[0], options.score.time_offset_s, fit_time ? margin + 1e-3 : 0.0,
                options.score.sim_sigma_m);
  if (residuals.count() == 0)
    throw std::invalid_argument(measured_name + ": no measured knot-frame within the simulated " +
                                "span (check --time-offset)");
  result.residuals = residuals.count();
  const auto cost = std::make_unique<ShotCost>(parameters, residuals, &simulator, priors, options, margin);

  // Levenberg-Marquardt from each start; the best one wins.
  std::mt19937 rng(options.seed);
  std::vector<double> best;
  double best_cost = kInf;
  // Each start in two stages when material parameters are fitted with others: first the launch,
  // the drag and the alignment with the material held, then everything. The material's signal
  // in a flight is weak; fitted from a start far off in velocity or drag, the stiffnesses went
  // where they explain the wrong launch (a net of EA = 26 N and EI = 4e-7 N m^2, a valley of
  // wrong minima, in the twin's Net A flight).
  std::vector<bool> all(p, true), launch(p);
  for (int i = 0; i < p; ++i) launch[i] = parameters[i].name.rfind("materials.", 0) != 0;
  const bool staged = std::count(launch.begin(), launch.end(), true) % p != 0;
  for (int s = 0; s < options.starts; ++s) {
    std::vector<double> x = s == 0 ? x0 : DrawStart(parameters, x0, &rng);
    ceres::Solver::Summary summary;
    if (staged) {
      cost->SetActive(launch);
      LevenbergMarquardt(cost.get(), launch, options,
                         ProgressCallback(options, simulator, start, s, "1/2 material held"), &x,
                         &summary);
      if (s == 0) result.cost_initial = 2 * summary.initial_cost;
      result.iterations += static_cast<int>(summary.iterations.size()) - 1;
      cost->SetActive(all);
    }
    if (summary.termination_type != ceres::FAILURE || !staged)
      LevenbergMarquardt(cost.get(), all, options,
                         ProgressCallback(options, simulator, start, s, staged ? "2/2 all" : ""),
                         &x, &summary);
    if (s == 0 && !staged) result.cost_initial = 2 * summary.initial_cost;
    result.iterations += static_cast<int>(summary.iterations.size()) - 1;
    if (summary.IsSolutionUsable() && 2 * summary.final_cost < best_cost) {
      best_cost = 2 * summary.final_cost;
      best = x;
      result.best_start = s;
      result.termination = summary.message;
    }
  }
  if (best.empty()) throw std::runtime_error("the fit failed: " + cost->last_failure());
  result.cost_final = best_cost;

  // The Jacobian at the fit (Ceres' last one when it was taken there).
  std::vector<double> jac;
  if (!cost->JacobianAt(best, &jac)) {
    std::vector<double> r(cost->num_residuals());
    jac.resize(size_t(cost->num_residuals()) * p);
    const double* blocks[] = {best.data()};
    double* jacobians[] = {jac.data()};
    if (!cost->Evaluate(blocks, r.data(), jacobians))
      throw std::runtime_error("the Jacobian at the fit failed: " + cost->last_failure());
  }
  const int n = residuals.count();
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
      j(jac.data(), cost->num_residuals(), p);

  // The final score, and the inflation of the data's information it finds.
  const Alignment6 a = AlignmentOf(parameters, best.data(), options.score.time_offset_s);
  const auto final_sim = simulator.Run({best}, &error);
  if (!final_sim[0]) throw std::runtime_error("the fitted simulation failed: " + error);
  result.score = FinalScore(measured, *final_sim[0], a, options.score, measured_name);
  result.inflation = std::max(1.0, result.score.tau_int) * std::max(1.0, result.score.design_effect) *
                     std::max(1.0, result.score.mean_d2 / 3.0);
  const Eigen::MatrixXd data_information =
      j.topRows(n).transpose() * j.topRows(n) / result.inflation;
  const Eigen::MatrixXd information =
      data_information + j.bottomRows(priors.size()).transpose() * j.bottomRows(priors.size());
  Eigen::VectorXd sigma, data_sigma;
  result.covariance = CovarianceOf(information, &sigma);
  CovarianceOf(data_information, &data_sigma);
  result.correlation = Eigen::MatrixXd::Identity(p, p);
  for (int r = 0; r < p; ++r)
    for (int c = 0; c < p; ++c)
      if (r != c && std::isfinite(sigma(r)) && std::isfinite(sigma(c)) && sigma(r) * sigma(c) > 0)
        result.correlation(r, c) = result.covariance(r, c) / (sigma(r) * sigma(c));
      else if (r != c)
        result.correlation(r, c) = std::numeric_limits<double>::quiet_NaN();

  // Which parameters look identified (sigma below half the reference spread: the prior's sigma,
  // else the parameter's spread, fit_parameters.h), then whether the cost is smooth along the
  // scenario ones among them.
  std::vector<double> reference(p);
  std::vector<bool> looks_identified(p), check(p);
  for (int i = 0; i < p; ++i) {
    reference[i] = parameters[i].spread;  // in coordinate units
    for (const PriorTerm& prior : priors)
      if (prior.parameter == i && !prior.anchor)
        reference[i] = parameters[i].log ? prior.sigma / prior.value : prior.sigma;
    looks_identified[i] = sigma(i) < 0.5 * reference[i];
    check[i] = looks_identified[i] && parameters[i].kind == FitParameter::Kind::kScenario;
  }
  const Eigen::MatrixXd jtj = j.transpose() * j;
  const auto ratio = QuadraticCheck(*cost, &simulator, best, best_cost, sigma, jtj, check);

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
    // Smooth: the cost at +-sigma within a factor 2 of the quadratic model's rise.
    f.rough = check[i] && !(std::min(ratio[i][0], ratio[i][1]) > 0.5 &&
                            std::max(ratio[i][0], ratio[i][1]) < 2.0);
    f.identified = looks_identified[i] && !f.rough;
    f.determined_by = f.identified ? "flight data" : f.has_prior ? "prior" : "neither";
    result.parameters.push_back(f);
  }
  result.fitted_set = ScenarioOverrides(parameters, best);
  result.simulations = simulator.simulations();
  result.wall_s = Seconds(start);
  return result;
}

}  // namespace netlab::netsim
