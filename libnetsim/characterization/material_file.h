#pragma once
// The material file of `netlab characterize` (written) and `netlab fit --prior` (read): measured
// material parameters, each with its standard uncertainty and the bench test it came from. The
// `materials` block is the scenario's (docs/scenarios.md), so it can be pasted into a scenario;
// the `uncertainty` block has one entry for every value of it:
//
//   # netlab characterize: torsion test from torsion.yaml (comment lines are free)
//   materials:
//     nylon_1mm: {twist_stiffness: 7.07e-05, twist_damping: 1.68e-08}
//   uncertainty:
//     nylon_1mm:
//       twist_stiffness: {sigma: 3.1e-07, test: torsion, source: torsion.yaml}
//       twist_damping: {sigma: 2.2e-10, test: torsion, source: torsion.yaml}
//
// Keys are the scenario's material keys (kMaterialKeys), values and sigmas in the same SI units
// (docs/scenarios.md), `test` one of kBenchTests, `source` the test file's name. A material may
// list only the keys that were measured.

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "libnetsim/model/material.h"

namespace netlab::netsim {

// The scenario's material keys, in the order the file lists them.
inline constexpr std::array<std::string_view, 8> kMaterialKeys = {
    "diameter",       "linear_density", "stretch_stiffness", "stretch_damping",
    "bend_stiffness", "bend_damping",   "twist_stiffness",   "twist_damping"};
// The tests a value may come from.
inline constexpr std::array<std::string_view, 4> kBenchTests = {"tensile", "cantilever", "torsion",
                                                                "weighing"};

// The value of material key `key` (one of kMaterialKeys) of `m`; std::invalid_argument for another.
double MaterialValue(const Material& m, std::string_view key);

// One measured material parameter.
struct ParameterEstimate {
  std::string material, key;    // material name; one of kMaterialKeys
  double value = 0, sigma = 0;  // SI units of the key; sigma the standard uncertainty (>= 0)
  std::string test, source;     // one of kBenchTests; the test file's name
};

// Reads a material file. Throws InputError naming the file, the line and the key on bad content:
// an unknown or missing section or key, a value that is not a finite number, a negative sigma, an
// unknown test, a value without its uncertainty entry or an uncertainty entry without its value.
// The estimates come in the file's order of materials, then kMaterialKeys' order.
std::vector<ParameterEstimate> ReadMaterialFile(const std::string& path);

// Writes the estimates (grouped by material, in order of first appearance; keys in kMaterialKeys'
// order) to `path` through "<path>.partial" and a rename, so `path` is either the old file or the
// complete new one. `header_comment` (may hold several lines) is written as '#' lines first.
// Throws std::runtime_error when the file cannot be written, std::invalid_argument on an unknown
// key or test or a duplicated (material, key).
void WriteMaterialFile(const std::string& path, const std::vector<ParameterEstimate>& estimates,
                       const std::string& header_comment);

}  // namespace netlab::netsim
