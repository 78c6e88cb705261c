#pragma once
// The small shot the command tests film: a 6 x 6-knot net shot along +x past a box, as in the
// flight scenarios but small and short (0.06 s).

namespace netlab::testing {

inline constexpr char kSmallShotScenario[] = R"(name: small_shot
duration: 0.06
output_interval: 0.005586592178770949
integrator: {type: explicit, dt: auto}
gravity: [0, 0, 0]
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          bend_stiffness: 9.82e-5, twist_stiffness: 7.07e-5}
nets:
  - {name: net, material: nylon, knots: [6, 6], mesh: 0.1, segments_per_link: 2,
     center: [1.0, 0, 0], normal: [1, 0, 0], x_axis: [0, 1, 0], knot_mass: 3e-05,
     corner_mass: 0.02, corner_radius: 0.01, velocity: [0.5, 0, 0]}
bodies:
  - {name: target, shape: box, center: [2.2, 0, 0], size: [0.4, 0.3, 0.3]}
)";

}  // namespace netlab::testing
