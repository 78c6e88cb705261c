#pragma once
// fit.yaml: what `netlab fit` found, readable by people and by any YAML reader (docs/fit.md):
// the command that reruns the fitted shot (a comment), scenario, measured, parameters (value,
// sigma, units, start, data_sigma, identified, rough, ambiguous, alternative, alternative_rise,
// check, determined_by, prior), correlation, cost_initial, cost_final, residuals, inflation,
// simulations, iterations, wall_s, duration_s, dt_s, score, set, notes, and shots when several.
// `netlab fit --out` and the simulation room write it.

#include <string>
#include <vector>

#include "libnetsim/identification/shot_fit.h"

namespace netlab::netsim {

// A number as fit.yaml writes it: %.6g, .nan, .inf, -.inf.
std::string FitNumber(double value);
// The file's text: one scenario and one measured track file per shot, in the fit's order.
std::string FitYaml(const std::vector<std::string>& scenarios,
                    const std::vector<std::string>& measured, const FitResult& result);
// Writes FitYaml through "<path>.partial" and a rename; std::runtime_error when it cannot.
void WriteFit(const std::string& path, const std::vector<std::string>& scenarios,
              const std::vector<std::string>& measured, const FitResult& result);

}  // namespace netlab::netsim
