#pragma once
// The digital twin's small shot that `netlab fit` is tested and benchmarked on: 5 x 5 knots,
// 10 cm mesh, shot at 0.5 m/s through cabin air for 0.4 s, the corner masses flying outward; the
// truth is the scenario's values (drag 1.2, velocity (0.5, 0, 0)). MeasuredTwin: its knots with
// seeded isotropic noise, as a measured track file.

#include <random>

#include "libnetsim/sweep/sweep_runner.h"

namespace netlab::testing {

inline constexpr char kTwinShot[] = R"(name: twin_shot
duration: 0.4
output_interval: 0.005586592178770949
integrator: {type: implicit, dt: auto}
gravity: [0, 0, 0]
drag: {air_density: 1.0, drag_coefficient: 1.2}
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          stretch_damping: 7.6e-4, bend_stiffness: 9.82e-5, bend_damping: 6.0e-9,
          twist_stiffness: 7.07e-5, twist_damping: 5.7e-11}
nets:
  - {name: net, material: nylon, knots: [5, 5], mesh: 0.1, segments_per_link: 2,
     center: [0, 0, 0], normal: [1, 0, 0], x_axis: [0, 1, 0], knot_mass: 3e-05,
     corner_mass: 0.02, corner_radius: 0.01, velocity: [0.5, 0, 0],
     corner_velocities: [[0.05, -0.05, -0.05], [0.05, 0.05, -0.05], [0.05, -0.05, 0.05],
                         [0.05, 0.05, 0.05]]}
)";

// The truth's knots plus isotropic Gaussian noise of `sigma` m.
inline KnotTracks MeasuredTwin(const netsim::SweepRun& truth, double sigma, uint32_t seed) {
  KnotTracks m = truth.Tracks();
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (Eigen::Vector3d& p : m.position) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  return m;
}

}  // namespace netlab::testing
