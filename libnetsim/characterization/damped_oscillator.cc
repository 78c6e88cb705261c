#include "libnetsim/characterization/damped_oscillator.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace netlab::netsim {
namespace {

// One sample's residual of the oscillator; parameters (c, a, b, sigma, omega_d).
struct DampedOscillatorCostFunctor {
  DampedOscillatorCostFunctor(double t, double y) : t_(t), y_(y) {}
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    const T envelope = exp(-p[3] * t_);
    residual[0] = p[0] + envelope * (p[1] * cos(p[4] * t_) + p[2] * sin(p[4] * t_)) - y_;
    return true;
  }
  static ceres::CostFunction* Create(double t, double y) {
    return new ceres::AutoDiffCostFunction<DampedOscillatorCostFunctor, 1, 5>(
        new DampedOscillatorCostFunctor(t, y));
  }
  double t_, y_;
};

// omega_d from the mean crossings: n crossings span (n - 1) half periods. 0 when fewer than 3.
double CrossingFrequency(const std::vector<double>& t, const std::vector<double>& y) {
  const double mean = std::accumulate(y.begin(), y.end(), 0.0) / y.size();
  std::vector<double> crossings;
  for (size_t i = 1; i < y.size(); ++i)
    if ((y[i - 1] - mean) * (y[i] - mean) < 0)
      crossings.push_back(t[i - 1] + (t[i] - t[i - 1]) * (mean - y[i - 1]) / (y[i] - y[i - 1]));
  if (crossings.size() < 3) return 0;
  return M_PI * (crossings.size() - 1) / (crossings.back() - crossings.front());
}

// (c, a, b) solved linearly for a given (sigma, omega_d); returns the residual sum of squares.
double LinearPart(const std::vector<double>& t, const std::vector<double>& y, double sigma,
                  double omega, Eigen::Vector3d* cab) {
  Eigen::MatrixXd x(t.size(), 3);
  Eigen::VectorXd rhs(t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    const double e = std::exp(-sigma * t[i]);
    x.row(i) << 1.0, e * std::cos(omega * t[i]), e * std::sin(omega * t[i]);
    rhs[i] = y[i];
  }
  *cab = x.colPivHouseholderQr().solve(rhs);
  return (x * *cab - rhs).squaredNorm();
}

// The start (c, a, b, sigma, omega_d): sigma scanned over [0, 10 / duration].
std::array<double, 5> StartingPoint(const std::vector<double>& t, const std::vector<double>& y,
                                    double omega) {
  const double duration = t.back() - t.front();
  double best = INFINITY;
  std::array<double, 5> start{};
  for (int k = 0; k <= 100; ++k) {
    const double sigma = 10.0 / duration * k / 100.0;
    Eigen::Vector3d cab;
    const double rss = LinearPart(t, y, sigma, omega, &cab);
    if (rss < best) best = rss, start = {cab[0], cab[1], cab[2], sigma, omega};
  }
  return start;
}

}  // namespace

double OscillatorFit::amplitude() const { return std::hypot(cosine, sine); }
double OscillatorFit::natural_frequency() const {
  return std::sqrt(damped_frequency * damped_frequency + decay_rate * decay_rate);
}
double OscillatorFit::damping_ratio() const { return decay_rate / natural_frequency(); }
double OscillatorFit::Evaluate(double t) const {
  const double s = t - start_time;
  return offset + std::exp(-decay_rate * s) * (cosine * std::cos(damped_frequency * s) +
                                               sine * std::sin(damped_frequency * s));
}
double OscillatorFit::natural_frequency_squared_sigma() const {
  // omega_0^2 = omega_d^2 + sigma^2: gradient (2 omega_d, 2 sigma) through the covariance.
  const double w = damped_frequency, s = decay_rate;
  const double var = 4 * w * w * damped_frequency_sigma * damped_frequency_sigma +
                     4 * s * s * decay_rate_sigma * decay_rate_sigma +
                     8 * w * s * covariance_decay_frequency;
  return std::sqrt(std::max(var, 0.0));
}

bool FitDampedOscillator(const std::vector<double>& t_in, const std::vector<double>& y,
                         OscillatorFit* fit, std::string* error) {
  const int n = static_cast<int>(t_in.size());
  if (n < 6 || static_cast<int>(y.size()) != n) {
    *error = "too few samples for a damped oscillation (" + std::to_string(n) + ")";
    return false;
  }
  std::vector<double> t(t_in);
  for (double& ti : t) ti -= t_in.front();
  const double omega = CrossingFrequency(t, y);
  if (!(omega > 0)) {
    *error = "no oscillation: the series crosses its mean fewer than 3 times";
    return false;
  }
  std::array<double, 5> p = StartingPoint(t, y, omega);
  ceres::Problem problem;
  for (int i = 0; i < n; ++i)
    problem.AddResidualBlock(DampedOscillatorCostFunctor::Create(t[i], y[i]), nullptr, p.data());
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) {
    *error = "the damped-oscillator fit did not converge: " + summary.message;
    return false;
  }
  // Covariance (J^T J)^-1 scaled by the residual variance.
  ceres::CRSMatrix crs;
  std::vector<double> residuals;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &residuals, nullptr, &crs);
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(n, 5);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) jac(r, crs.cols[k]) = crs.values[k];
  const double rss = 2.0 * summary.final_cost;
  const Eigen::Matrix<double, 5, 5> info = jac.transpose() * jac;
  Eigen::FullPivLU<Eigen::Matrix<double, 5, 5>> lu(info);
  if (!lu.isInvertible() || !(std::abs(p[1]) + std::abs(p[2]) > 0)) {
    *error = "the series does not determine a damped oscillation (singular fit)";
    return false;
  }
  const Eigen::Matrix<double, 5, 5> cov = lu.inverse() * (rss / std::max(n - 5, 1));
  fit->offset = p[0];
  fit->cosine = p[1];
  fit->sine = p[4] < 0 ? -p[2] : p[2];  // sin is odd: the same curve with omega_d > 0
  fit->decay_rate = p[3];
  fit->damped_frequency = std::abs(p[4]);
  fit->decay_rate_sigma = std::sqrt(cov(3, 3));
  fit->damped_frequency_sigma = std::sqrt(cov(4, 4));
  fit->covariance_decay_frequency = cov(3, 4) * (p[4] < 0 ? -1 : 1);
  fit->start_time = t_in.front();
  fit->rms = std::sqrt(rss / n);
  fit->points = n;
  return true;
}

}  // namespace netlab::netsim
