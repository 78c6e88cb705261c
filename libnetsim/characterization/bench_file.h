#pragma once
// The bench-test file of `netlab characterize` (docs/characterize.md): one test per file, the
// measured series and the specimen, SI units throughout.
//
//   test: torsion            # tensile | cantilever | torsion
//   material: nylon_1mm      # the material's name in the output
//   description: free text   # optional
//   weighing: {mass: 1.79e-4, mass_sigma: 1.0e-7, length: 0.2, length_sigma: 2.0e-4}  # optional
//   ... the test's own keys (below)
//
// tensile:    gauge_length (m), optional max_force (N: the stiffness is linearised below it),
//             samples: [[t s, extension m, force N], ...]
// cantilever: length (m), optional gravity (m/s^2, 9.81); either shape: [[x m, y m], ...] (points
//             along the thread from the clamp, x horizontal away from it, y up) or tip_deflection:
//             {vertical: m, sigma: m} (downwards, > 0); optional oscillation: [[t s, tip y m],
//             ...]. Needs the weighing (the self weight loads it).
// torsion:    length (m, of the thread from the clamp to the pendulum), inertia (kg m^2, the
//             pendulum's about the thread), optional inertia_sigma, samples: [[t s, angle rad],
//             ...]
//
// ReadBenchTest checks everything a fit needs: unknown or missing keys, a value of the wrong kind,
// NaN, lengths and masses <= 0, times that do not increase, too few points are InputErrors naming
// the file, the line and the key ("torsion.yaml:9: samples[3]: time 0.02 does not increase").

#include <optional>
#include <string>
#include <vector>

namespace netlab::netsim {

// The specimen's linear density from weighing a known length of it.
struct Weighing {
  double mass = 0, mass_sigma = 0;                        // kg
  double length = 0, length_sigma = 0;                    // m
  double LinearDensity() const { return mass / length; }  // kg/m
  double LinearDensitySigma() const;                      // kg/m, first-order propagation
};

// A measured series: rows of equal width, the first column time (s) where the test has one.
struct Series {
  std::vector<std::vector<double>> rows;
  std::string where;  // "file:line: key", the start of an error about the series as a whole

  int size() const { return static_cast<int>(rows.size()); }
  std::vector<double> Column(int c) const;
};

struct TensileTest {
  double gauge_length = 0;  // m, the specimen's free length between the grips at zero extension
  std::optional<double> max_force;  // N: the linear fit uses the samples at or below it
  Series samples;                   // [t s, extension m, force N]
};

struct CantileverTest {
  double length = 0;      // m, free length from the clamp
  double gravity = 9.81;  // m/s^2
  Series shape;           // [x m, y m] from the clamp, y up; empty when tip_deflection is given
  std::optional<double> tip_deflection, tip_deflection_sigma;  // m, downwards
  Series oscillation;                                          // [t s, tip y m]; may be empty
};

struct TorsionTest {
  double length = 0;         // m
  double inertia = 0;        // kg m^2
  double inertia_sigma = 0;  // kg m^2
  Series samples;            // [t s, angle rad]
};

// The bench tests a thread is characterized with; each has its own keys in the test's file.
enum class BenchKind { kTensile, kCantilever, kTorsion };
std::string BenchKindName(BenchKind kind);  // "tensile" | "cantilever" | "torsion"

struct BenchTest {
  BenchKind kind = BenchKind::kTensile;
  std::string material;
  std::string description;
  std::string path;    // the file read ("" when parsed from text)
  std::string source;  // its file name, for the output's `source`
  std::optional<Weighing> weighing;
  TensileTest tensile;        // when kind == kTensile
  CantileverTest cantilever;  // when kind == kCantilever
  TorsionTest torsion;        // when kind == kTorsion
};

// Minimum points of a series: below it no fit is attempted.
inline constexpr int kMinTensileSamples = 10;
inline constexpr int kMinShapePoints = 3;
inline constexpr int kMinOscillationSamples = 20;

BenchTest ReadBenchTest(const std::string& path);
// `origin` names the text in errors and is the test's path.
BenchTest ParseBenchTest(const std::string& text, const std::string& origin);

// The YAML text of a test (the generator of scenarios/bench/ writes it); `comment` heads it as '#'
// lines. ParseBenchTest reads it back to the same values (to 10 significant digits).
std::string BenchTestText(const BenchTest& test, const std::string& comment);

}  // namespace netlab::netsim
