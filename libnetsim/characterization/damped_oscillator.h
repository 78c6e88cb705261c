#pragma once
// A damped harmonic oscillation fitted to a time series by least squares (Ceres):
//
//   y(t) = c + exp(-sigma t') (a cos(omega_d t') + b sin(omega_d t')),   t' = t - t_0
//
// sigma the decay rate (1/s), omega_d the damped angular frequency (rad/s), t_0 the first sample's
// time. The oscillator m x'' + c x' + k x = 0 behind it has omega_0^2 = k/m = omega_d^2 + sigma^2
// and damping ratio zeta = sigma / omega_0; the logarithmic decrement per period is
// 2 pi sigma / omega_d. The start comes from the mean crossings (omega_d) and a scan of sigma
// with (c, a, b) solved linearly for each; Ceres then refines all five. The standard
// uncertainties are the covariance (J^T J)^-1 scaled by the residual variance RSS / (n - 5).

#include <string>
#include <vector>

namespace netlab::netsim {

struct OscillatorFit {
  double offset = 0;            // c, units of y
  double cosine = 0, sine = 0;  // a, b, units of y
  double decay_rate = 0;        // sigma, 1/s
  double damped_frequency = 0;  // omega_d, rad/s
  double decay_rate_sigma = 0;  // standard uncertainties, same units
  double damped_frequency_sigma = 0;
  double covariance_decay_frequency = 0;  // cov(sigma, omega_d), rad/s^2
  double start_time = 0;                  // t_0, s
  double rms = 0;                         // residual RMS, units of y
  int points = 0;

  double amplitude() const;          // sqrt(a^2 + b^2) at t_0
  double natural_frequency() const;  // omega_0, rad/s
  double damping_ratio() const;      // zeta
  double Evaluate(double t) const;
  // Standard uncertainty of omega_0^2 and of sigma (with their correlation), for mappings.
  double natural_frequency_squared_sigma() const;
};

// Fits y(t). False, with the reason in *error, when the series does not show an oscillation to fit
// (fewer than two mean crossings, a flat series, or a fit that does not converge).
bool FitDampedOscillator(const std::vector<double>& t, const std::vector<double>& y,
                         OscillatorFit* fit, std::string* error);

}  // namespace netlab::netsim
