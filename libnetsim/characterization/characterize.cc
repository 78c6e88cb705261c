#include "libnetsim/characterization/characterize.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/errors.h"
#include "common/minimize.h"
#include "libnetsim/characterization/damped_oscillator.h"
#include "libnetsim/characterization/heavy_cantilever.h"

namespace netlab::netsim {
namespace {

// Segments of the elastica when fitting (the discretisation error, ~(1/n)^2, is then ~1e-5) and
// when computing its mode.
constexpr int kFitSegments = 200;
constexpr int kModeSegments = 100;

class Builder {
 public:
  explicit Builder(const BenchTest& test) {
    result_.material = test.material;
    result_.test = BenchKindName(test.kind);
    result_.source = test.source;
  }
  void Estimate(const std::string& key, double value, double sigma, const std::string& test) {
    result_.estimates.push_back({result_.material, key, value, sigma, test, result_.source});
  }
  void Diagnostic(const std::string& name, double value) {
    result_.diagnostics.push_back({name, value});
  }
  Characterization Done() { return std::move(result_); }

 private:
  Characterization result_;
};

[[noreturn]] void CannotFit(const Series& series, const std::string& why) {
  throw InputError(series.where + ": cannot be fitted: " + why);
}

// Relative uncertainty of a product or quotient of independent factors.
double Quadrature(std::initializer_list<double> relative) {
  double sum = 0;
  for (double r : relative) sum += r * r;
  return std::sqrt(sum);
}

// ---- tensile --------------------------------------------------------------------------------

// d(eps)/dt by a local linear regression over +-3 samples (a Savitzky-Golay slope): the
// difference of neighbours would amplify the extension's noise by 1/dt.
std::vector<double> StrainRate(const std::vector<double>& t, const std::vector<double>& eps) {
  const int n = static_cast<int>(t.size()), half = 3;
  std::vector<double> rate(n);
  for (int i = 0; i < n; ++i) {
    const int a = std::max(0, i - half), b = std::min(n - 1, i + half);
    double st = 0, se = 0, stt = 0, ste = 0;
    for (int k = a; k <= b; ++k) st += t[k], se += eps[k], stt += t[k] * t[k], ste += t[k] * eps[k];
    const int m = b - a + 1;
    rate[i] = (m * ste - st * se) / (m * stt - st * st);
  }
  return rate;
}

// The direct least-squares fit F = F_0 + EA eps + c_s deps/dt is used rather than c_s from the
// loop's area: in a cycle, eps and deps/dt are a quarter period apart, so the two columns are
// nearly orthogonal and the normal matrix nearly diagonal (well conditioned); it uses every
// sample, needs no closed loop and gives the covariance. The loop's area, W = c_s L_0 (integral of
// (deps/dt)^2 dt) for a Kelvin-Voigt thread, is reported as a check.
void FitTensile(const BenchTest& test, Builder* out) {
  const TensileTest& tt = test.tensile;
  const std::vector<double> t = tt.samples.Column(0), x = tt.samples.Column(1),
                            f = tt.samples.Column(2);
  std::vector<double> eps(x.size());
  for (size_t i = 0; i < x.size(); ++i) eps[i] = x[i] / tt.gauge_length;
  const std::vector<double> rate = StrainRate(t, eps);
  std::vector<int> used;
  for (size_t i = 0; i < f.size(); ++i)
    if (!tt.max_force || f[i] <= *tt.max_force) used.push_back(static_cast<int>(i));
  if (static_cast<int>(used.size()) < kMinTensileSamples)
    CannotFit(tt.samples, std::to_string(used.size()) +
                              " samples at or below max_force (at least " +
                              std::to_string(kMinTensileSamples) + " needed)");
  const int n = static_cast<int>(used.size());
  Eigen::MatrixXd design(n, 3);
  Eigen::VectorXd force(n);
  for (int r = 0; r < n; ++r) {
    design.row(r) << 1.0, eps[used[r]], rate[used[r]];
    force[r] = f[used[r]];
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (qr.rank() < 3)
    CannotFit(tt.samples,
              "the extension and its rate do not vary independently (a cycle of "
              "loading and unloading is needed)");
  const Eigen::Vector3d beta = qr.solve(force);
  const double rss = (design * beta - force).squaredNorm();
  const Eigen::Matrix3d cov = (design.transpose() * design).inverse() * (rss / std::max(n - 3, 1));
  if (!(beta[1] > 0)) CannotFit(tt.samples, "the fitted stiffness is not positive");
  out->Estimate("stretch_stiffness", beta[1], std::sqrt(cov(1, 1)), "tensile");
  out->Estimate("stretch_damping", std::max(beta[2], 0.0), std::sqrt(cov(2, 2)), "tensile");
  // The hysteresis loop: dissipated energy (trapezoids of F dx) and the c_s it implies.
  double loop = 0, rate_squared = 0;
  for (size_t i = 1; i < t.size(); ++i) {
    loop += 0.5 * (f[i] + f[i - 1]) * (x[i] - x[i - 1]);
    rate_squared += 0.5 * (rate[i] * rate[i] + rate[i - 1] * rate[i - 1]) * (t[i] - t[i - 1]);
  }
  out->Diagnostic("points", n);
  out->Diagnostic("residual_rms_n", std::sqrt(rss / n));
  out->Diagnostic("force_offset_n", beta[0]);
  out->Diagnostic("max_strain", *std::max_element(eps.begin(), eps.end()));
  out->Diagnostic("loop_energy_j", loop);
  out->Diagnostic("stretch_damping_from_loop", loop / (tt.gauge_length * rate_squared));
}

// ---- cantilever -----------------------------------------------------------------------------

// Residuals of the shape points against the elastica of alpha = exp(u): signed distances, m.
Eigen::VectorXd ShapeResiduals(const CantileverTest& c, double u) {
  const CantileverShape shape = SolveHeavyCantilever(c.length, std::exp(u), kFitSegments);
  Eigen::VectorXd r(c.shape.size());
  for (int i = 0; i < c.shape.size(); ++i)
    r[i] = SignedDistanceToCurve(shape.points,
                                 Eigen::Vector2d(c.shape.rows[i][0], c.shape.rows[i][1]));
  return r;
}

double TipDeflection(const CantileverTest& c, double u) {
  return -SolveHeavyCantilever(c.length, std::exp(u), kFitSegments).points.back().y();
}

// u = ln alpha and its standard uncertainty from the shape points: a scan of u over +-6 e-folds
// around `u0`, then a golden-section search; sigma from the Jacobian d r / d u.
std::pair<double, double> FitShape(const CantileverTest& c, double u0, double* rms) {
  auto rss = [&](double u) { return ShapeResiduals(c, u).squaredNorm(); };
  double best = u0, best_rss = INFINITY;
  for (int k = -30; k <= 30; ++k) {
    const double u = u0 + 0.2 * k, value = rss(u);
    if (value < best_rss) best = u, best_rss = value;
  }
  const double u = GoldenSection(rss, best - 0.2, best + 0.2, 1e-9);
  const double du = 1e-5;
  const Eigen::VectorXd jacobian =
      (ShapeResiduals(c, u + du) - ShapeResiduals(c, u - du)) / (2 * du);
  const int n = c.shape.size();
  const double residual_rss = rss(u);
  *rms = std::sqrt(residual_rss / n);
  if (!(jacobian.squaredNorm() > 0))
    CannotFit(c.shape, "the points do not depend on the stiffness");
  return {u, std::sqrt(residual_rss / std::max(n - 1, 1) / jacobian.squaredNorm())};
}

// u = ln alpha matching the tip deflection (which falls as alpha grows): bracketed by steps of
// one e-fold from u0, then bisection.
std::pair<double, double> FitTipDeflection(const CantileverTest& c, double u0) {
  const double target = *c.tip_deflection;
  double lo = u0, hi = u0;
  for (int k = 0; k < 40 && TipDeflection(c, lo) < target; ++k) lo -= 1;
  for (int k = 0; k < 40 && TipDeflection(c, hi) > target; ++k) hi += 1;
  if (!(TipDeflection(c, lo) >= target && TipDeflection(c, hi) <= target))
    throw InputError(c.shape.where + ": cannot be fitted: no stiffness gives this tip deflection");
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (TipDeflection(c, mid) > target ? lo : hi) = mid;
  }
  const double u = 0.5 * (lo + hi), du = 1e-5;
  const double slope = (TipDeflection(c, u + du) - TipDeflection(c, u - du)) / (2 * du);
  return {u, *c.tip_deflection_sigma / std::abs(slope)};
}

// The oscillation about the equilibrium: a Kelvin-Voigt c_b damps the first mode at
// sigma = (c_b / EI) beta omega_0^2 / 2 (heavy_cantilever.h), so c_b = 2 sigma EI / (beta
// omega_0^2) with beta, the bending share of the mode's stiffness, from the fitted elastica
// (gravity carries the rest: using omega_0^2 alone would take gravity's stiffness for bending).
void FitBendDamping(const CantileverTest& c, double alpha, double ei, double ei_sigma,
                    Builder* out) {
  OscillatorFit fit;
  std::string error;
  if (!FitDampedOscillator(c.oscillation.Column(0), c.oscillation.Column(1), &fit, &error))
    CannotFit(c.oscillation, error);
  const CantileverShape shape = SolveHeavyCantilever(c.length, alpha, kModeSegments);
  const CantileverMode mode = FirstMode(shape, c.length, alpha, c.gravity);
  const double w2 = fit.natural_frequency() * fit.natural_frequency();
  const double cb = 2 * fit.decay_rate * ei / (mode.bending_fraction * w2);
  const double relative = Quadrature({fit.decay_rate_sigma / fit.decay_rate,
                                      fit.natural_frequency_squared_sigma() / w2, ei_sigma / ei});
  out->Estimate("bend_damping", std::max(cb, 0.0), std::abs(cb) * relative, "cantilever");
  out->Diagnostic("oscillation_points", fit.points);
  out->Diagnostic("oscillation_rms_m", fit.rms);
  out->Diagnostic("frequency_hz", fit.natural_frequency() / (2 * M_PI));
  out->Diagnostic("model_frequency_hz", mode.omega / (2 * M_PI));
  out->Diagnostic("damping_ratio", fit.damping_ratio());
  out->Diagnostic("log_decrement", 2 * M_PI * fit.decay_rate / fit.damped_frequency);
  out->Diagnostic("bending_fraction", mode.bending_fraction);
}

void FitCantilever(const BenchTest& test, Builder* out) {
  const CantileverTest& c = test.cantilever;
  const double mu = test.weighing->LinearDensity(), mu_sigma = test.weighing->LinearDensitySigma();
  const double weight = mu * c.gravity;  // N/m
  // Start from Peirce's formula at the farthest point (or the tip deflection).
  Eigen::Vector2d far(c.length, -(c.tip_deflection ? *c.tip_deflection : 0.0));
  if (c.shape.size() > 0) far.setZero();
  for (const std::vector<double>& p : c.shape.rows)
    if (Eigen::Vector2d(p[0], p[1]).norm() > far.norm()) far = Eigen::Vector2d(p[0], p[1]);
  const double peirce0 = PeirceBendStiffness(c.length, far, mu, c.gravity);
  const double u0 =
      std::log(peirce0 > 0 && std::isfinite(peirce0) ? peirce0 / weight : std::pow(c.length, 3));
  double rms = 0;
  const auto [u, u_sigma] = c.shape.size() > 0 ? FitShape(c, u0, &rms) : FitTipDeflection(c, u0);
  const double alpha = std::exp(u), ei = alpha * weight;
  const double ei_sigma = ei * Quadrature({u_sigma, mu_sigma / mu});
  out->Estimate("bend_stiffness", ei, ei_sigma, "cantilever");
  const CantileverShape shape = SolveHeavyCantilever(c.length, alpha, kFitSegments);
  if (!shape.converged) CannotFit(c.shape.size() ? c.shape : c.oscillation, "no equilibrium found");
  const double peirce = PeirceBendStiffness(c.length, shape.points.back(), mu, c.gravity);
  out->Diagnostic("points", c.shape.size());
  out->Diagnostic("residual_rms_m", rms);
  out->Diagnostic("tip_deflection_m", -shape.points.back().y());
  out->Diagnostic("load_parameter", std::pow(c.length, 3) / alpha);  // mu g L^3 / EI
  out->Diagnostic("peirce_bend_stiffness", peirce);
  out->Diagnostic("peirce_error", peirce / ei - 1);
  if (c.oscillation.size() > 0) FitBendDamping(c, alpha, ei, ei_sigma, out);
}

// ---- torsion --------------------------------------------------------------------------------

// The pendulum J phi'' + (c_t / L) phi' + (GJ / L) phi = M: a thread twisted uniformly by phi over
// its length L has the twist rate Omega_3 = phi / L, so material.h's torque GJ Omega_3 and damping
// torque c_t dOmega_3/dt act on the bob. Hence omega_0^2 = GJ / (J L) and 2 sigma = c_t / (J L):
// GJ = J L omega_0^2, c_t = 2 sigma J L. (The thread's own twist inertia, mu r^2 L / 2, adds a
// third of itself to J: 1e-3 of a 5e-8 kg m^2 bob's for 1 mm Nylon; left out.)
void FitTorsion(const BenchTest& test, Builder* out) {
  const TorsionTest& tt = test.torsion;
  OscillatorFit fit;
  std::string error;
  if (!FitDampedOscillator(tt.samples.Column(0), tt.samples.Column(1), &fit, &error))
    CannotFit(tt.samples, error);
  const double jl = tt.inertia * tt.length, w2 = fit.natural_frequency() * fit.natural_frequency();
  const double j_relative = tt.inertia_sigma / tt.inertia;
  const double gj = jl * w2, ct = 2 * fit.decay_rate * jl;
  out->Estimate("twist_stiffness", gj,
                gj * Quadrature({fit.natural_frequency_squared_sigma() / w2, j_relative}),
                "torsion");
  out->Estimate("twist_damping", std::max(ct, 0.0),
                2 * jl * Quadrature({fit.decay_rate_sigma, fit.decay_rate * j_relative}),
                "torsion");
  out->Diagnostic("points", fit.points);
  out->Diagnostic("residual_rms_rad", fit.rms);
  out->Diagnostic("frequency_hz", fit.natural_frequency() / (2 * M_PI));
  out->Diagnostic("damping_ratio", fit.damping_ratio());
  out->Diagnostic("log_decrement", 2 * M_PI * fit.decay_rate / fit.damped_frequency);
  out->Diagnostic("amplitude_rad", fit.amplitude());
}

std::string Significant(double v, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.*g", digits, v);
  return buffer;
}

}  // namespace

std::string MaterialKeyUnit(const std::string& key) {
  if (key == "diameter") return "m";
  if (key == "linear_density") return "kg/m";
  if (key == "stretch_stiffness") return "N";
  if (key == "stretch_damping") return "N s";
  if (key == "bend_stiffness" || key == "twist_stiffness") return "N m^2";
  return "N m^2 s";  // bend_damping, twist_damping
}

Characterization Characterize(const BenchTest& test) {
  Builder out(test);
  if (test.weighing)
    out.Estimate("linear_density", test.weighing->LinearDensity(),
                 test.weighing->LinearDensitySigma(), "weighing");
  switch (test.kind) {
    case BenchKind::kTensile: FitTensile(test, &out); break;
    case BenchKind::kCantilever: FitCantilever(test, &out); break;
    case BenchKind::kTorsion: FitTorsion(test, &out); break;
  }
  return out.Done();
}

std::string Characterization::BriefReport() const {
  std::ostringstream out;
  out << material << ": " << test << " test from " << source << "\n";
  for (const ParameterEstimate& e : estimates) {
    const double relative = e.value != 0 ? 100.0 * e.sigma / std::abs(e.value) : 0.0;
    out << "  " << e.key << " = " << Significant(e.value, 5) << " +- " << Significant(e.sigma, 2)
        << " " << MaterialKeyUnit(e.key) << "  (" << Significant(relative, 2) << " %, " << e.test
        << ")\n";
  }
  out << "  fit:";
  for (const FitDiagnostic& d : diagnostics) out << " " << d.name << " " << Significant(d.value, 4);
  out << "\n";
  return out.str();
}

}  // namespace netlab::netsim
