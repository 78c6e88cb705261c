#pragma once
// Material parameters from one bench test (the paper's sec. 4.2), each with its standard
// uncertainty and the test it came from; the engine of `netlab characterize`
// (docs/characterize.md has the models and their formulas).
//
//   tensile     F = F_0 + EA eps + c_s d(eps)/dt by linear least squares over the samples at or
//               below max_force: stretch_stiffness EA, stretch_damping c_s
//   cantilever  the heavy elastica (heavy_cantilever.h) fitted to the shape or the tip
//               deflection: bend_stiffness EI; with an oscillation, the damped oscillator and the
//               elastica's first mode: bend_damping c_b
//   torsion     the damped oscillator of the pendulum: twist_stiffness GJ, twist_damping c_t
//   weighing    (any test) linear_density mass / length
//
// Every sigma is the fit's covariance scaled by its residual variance, propagated to first order
// with the inputs' given uncertainties (weighing, inertia_sigma, tip_deflection.sigma).

#include <string>
#include <utility>
#include <vector>

#include "libnetsim/characterization/bench_file.h"
#include "libnetsim/characterization/material_file.h"

namespace netlab::netsim {

// One number describing a fit (residual RMS, points, frequency, ...), for the summaries.
struct FitDiagnostic {
  std::string name;  // snake_case with its unit as suffix where it has one: "residual_rms_n"
  double value = 0;
};

struct Characterization {
  std::string material, test, source;
  std::vector<ParameterEstimate> estimates;
  std::vector<FitDiagnostic> diagnostics;

  // A few lines: each value +- sigma with its unit and test, and the fit's quality.
  std::string BriefReport() const;
};

// Fits the test. Throws InputError naming the file and the series when a series cannot be fitted
// (no oscillation, a strain that does not vary, an elastica that does not converge).
Characterization Characterize(const BenchTest& test);

// The unit of a material key ("N m^2" for bend_stiffness).
std::string MaterialKeyUnit(const std::string& key);

}  // namespace netlab::netsim
