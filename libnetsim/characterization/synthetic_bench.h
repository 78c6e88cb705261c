#pragma once
// Bench tests generated with the simulator itself, plus seeded noise: the ground truth every fit
// of characterize.h is tested against, and the generator of scenarios/bench/. Each builds a
// scenario in the scenario format, runs it through libnetsim and records what the bench would
// measure:
//
//   tensile     a short specimen pinned at both ends, one grip driven sinusoidally
//               (x = x_a (1 - cos(omega t)) / 2, prescribed through the state between steps), the
//               load cell's force the reaction at the fixed grip (explicit integrator)
//   cantilever  a clamped thread under gravity relaxed to rest (dynamic relaxation): shape points;
//               then relaxed under an extra tip force and released: the tip's free oscillation
//   torsion     a thread clamped at the top with a rigid bob (`tip`) twisted from rest by a
//   constant
//               moment: the bob's angle about the thread (physical rotational inertia: the default
//               scaling adds twist inertia to the thread)
//
// Every test also carries a weighing of 1 m of the thread. Noise is Gaussian, from std::mt19937.

#include <cstdint>

#include "libnetsim/characterization/bench_file.h"
#include "libnetsim/model/material.h"

namespace netlab::netsim {

struct SyntheticTensile {
  double gauge_length = 0.1;  // m
  int segments = 4;
  double strain_amplitude = 0.01;  // peak strain of the cycle
  double frequency = 10;           // Hz
  int cycles = 2;
  int samples = 200;              // over all cycles
  double force_noise = 0.02;      // N
  double extension_noise = 2e-7;  // m
};

struct SyntheticCantilever {
  // 0.6 m of 1 mm Nylon: mu g L^3 / EI = 19, the tip drops by 0.83 L, Peirce's formula is 15 %
  // off (docs/characterize.md).
  double length = 0.6;  // m
  int segments = 40;
  int shape_points = 20;      // nodes 1..segments, evenly picked
  double shape_noise = 2e-4;  // m, per coordinate
  // Tip force before release, as a fraction of the thread's weight. The oscillation must stay
  // small: the fit's mode is linearised about the rest shape, and a push of 0.05 gave c_b 3.8 %
  // low without noise, 0.02 gives it 0.1 % high.
  double push = 0.02;
  double duration = 8;  // s of oscillation recorded
  int oscillation_samples = 400;
  double oscillation_noise = 5e-5;  // m
};

struct SyntheticTorsion {
  double length = 0.2;  // m, clamp to the thread's end
  int segments = 5;
  double inertia = 5e-8;    // kg m^2, the bob's about the thread
  double bob_mass = 1e-3;   // kg
  double mean_angle = 0.5;  // rad, where the moment holds the bob (it swings from 0 to ~2x)
  double duration = 1.6;    // s
  int samples = 400;
  double angle_noise = 0.01;  // rad
};

struct SyntheticWeighing {
  double length = 1.0;         // m of thread weighed
  double mass_sigma = 1e-6;    // kg (a 1 mg scale)
  double length_sigma = 1e-3;  // m
};

// The 1 mm Nylon thread of scenarios/net_a_0.5.yaml (diameter, density, stiffnesses) with the
// dampings of a loss factor `loss_factor` at each default bench test's own frequency (c = eta K /
// omega: 10 Hz stretching, the cantilever's first mode, the torsion pendulum). A Kelvin-Voigt
// coefficient measured at one frequency is that frequency's: net_a's dampings are the same loss
// factor at the links' frequencies, 10-1000 times higher, hence 10-1000 times smaller.
Material BenchNylon(double loss_factor = 0.02);

// The thread's free twisting length in a simulated torsion test: the bob turns with the last
// segment, so the thread ends at its centre (docs/scenarios.md, `tip`).
double TorsionFreeLength(const SyntheticTorsion& setup);

BenchTest SimulateTensileTest(const Material& truth, const SyntheticTensile& setup,
                              const SyntheticWeighing& weighing, uint32_t seed);
BenchTest SimulateCantileverTest(const Material& truth, const SyntheticCantilever& setup,
                                 const SyntheticWeighing& weighing, uint32_t seed);
BenchTest SimulateTorsionTest(const Material& truth, const SyntheticTorsion& setup,
                              const SyntheticWeighing& weighing, uint32_t seed);

}  // namespace netlab::netsim
