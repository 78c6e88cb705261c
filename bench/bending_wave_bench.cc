// How each integrator carries a bending wave: the first mode of a clamped Nylon thread (net A's,
// 2.5 cm segments as in its links, no gravity, no material damping), started in its shape, its
// tip's oscillation fitted with a damped oscillator (characterization/damped_oscillator.h).
//
//   bench_bending [SECONDS_PER_PERIOD_COUNT]
//
// Per thread length and integrator: the step, omega h (the mode's angular frequency times the
// step), the frequency against the explicit step's at a tenth of its own (the discrete thread's
// mode, undamped: symplectic), and the damping ratio the step itself adds, beside the one net A's
// bending damping (c_b = 6e-9 N m^2 s) gives the same mode, c_b omega / (2 EI). Over 2 s of flight
// a mode of damping ratio zeta keeps exp(-zeta omega 2 s) of its amplitude. Prints a Markdown
// table (docs/benchmarks.md).

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "libnetsim/characterization/damped_oscillator.h"
#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {
namespace {

constexpr double kMu = 8.95e-4, kEI = 9.82e-5, kNetBendDamping = 6.0e-9;
constexpr double kSegment = 0.025;  // m, net A's links: 10 cm in 4 segments

// The clamped-free Euler-Bernoulli beam's first mode: beta L and the shape (tip = 1).
constexpr double kBetaL = 1.8751040687119611;
double ModeShape(double s, double length) {
  const double b = kBetaL / length, sigma = (std::cosh(kBetaL) + std::cos(kBetaL)) /
                                            (std::sinh(kBetaL) + std::sin(kBetaL));
  auto phi = [&](double u) {
    return std::cosh(b * u) - std::cos(b * u) - sigma * (std::sinh(b * u) - std::sin(b * u));
  };
  return phi(s) / phi(length);
}

struct Wave {
  bool ok = false;
  std::string error;
  double dt = 0, omega = 0, zeta = 0;
};

// The thread of `length` started in its first mode (tip speed omega_eb * 0.5 mm), run for
// `periods` of the Euler-Bernoulli mode; dt 0: the integrator's automatic step.
Wave Run(double length, const std::string& integrator, double dt, double periods) {
  const int segments = std::lround(length / kSegment);
  const double omega_eb = std::pow(kBetaL / length, 2) * std::sqrt(kEI / kMu);
  char step[32] = "auto";
  if (dt > 0) std::snprintf(step, sizeof step, "%.17g", dt);
  char text[1024];
  std::snprintf(text, sizeof text,
                "name: bending_wave\nduration: 1\noutput_interval: 0.01\n"
                "integrator: {type: %s, dt: %s}\ngravity: [0, 0, 0]\n"
                "materials:\n  nylon: {diameter: 1.0e-3, linear_density: %.17g, "
                "stretch_stiffness: 1571, stretch_damping: 7.6e-4, bend_stiffness: %.17g, "
                "bend_damping: 0, twist_stiffness: 7.07e-5, twist_damping: 0}\n"
                "rods:\n  - {name: link, material: nylon, start: [0, 0, 0], end: [%.17g, 0, 0], "
                "segments: %d, fixed: {start: clamped}}\n",
                integrator.c_str(), step, kMu, kEI, length, segments);
  Wave w;
  BuiltScenario built = BuildScenario(ParseScenario(text, "bending wave", ""));
  Simulation& sim = *built.simulation;
  w.dt = sim.dt();
  State& state = sim.mutable_state();
  const int n = static_cast<int>(state.x.size());
  const double tip_speed = omega_eb * 5e-4;
  for (int i = 0; i < n; ++i)
    state.v[i] = Vector3d(0, tip_speed * ModeShape(state.x[i].x(), length), 0);
  // Each segment's frame turning with its tangent (body frame), so no shear is started.
  for (int j = 0; j + 1 < n; ++j) {
    const Vector3d world =
        Vector3d::UnitX().cross(state.v[j + 1] - state.v[j]) / (state.x[j + 1] - state.x[j]).norm();
    state.w[j] = state.q[j].conjugate() * world;
  }
  const double duration = periods * 2 * M_PI / omega_eb;
  const long steps = std::lround(duration / w.dt);
  const long every = std::max(1L, steps / 4000);
  std::vector<double> t, y;
  for (long k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      t.push_back(sim.state().time);
      y.push_back(sim.state().x.back().y());
    }
    if (k < steps && !sim.Step()) {
      w.error = sim.failure()->message;
      return w;
    }
  }
  OscillatorFit fit;
  if (!FitDampedOscillator(t, y, &fit, &w.error)) return w;
  w.ok = true;
  w.omega = fit.natural_frequency();
  w.zeta = fit.damping_ratio();
  return w;
}

}  // namespace
}  // namespace netlab::netsim

int main(int argc, char** argv) {
  using namespace netlab::netsim;
  const double periods = argc > 1 ? std::atof(argv[1]) : 10.0;
  std::printf(
      "| thread | EB mode (Hz) | integrator | dt (s) | omega h | frequency (Hz) | vs reference |"
      " damping ratio, the step's | net A's c_b | amplitude left after 2 s, step / c_b |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  for (const double length : {0.2, 0.1, 0.05}) {
    const double omega_eb = std::pow(kBetaL / length, 2) * std::sqrt(kEI / kMu);
    const double zeta_material = kNetBendDamping * omega_eb / (2 * kEI);
    const Wave auto_explicit = Run(length, "explicit", 0, periods);
    const Wave reference = Run(length, "explicit", auto_explicit.dt / 10, periods);
    struct Case {
      const char* integrator;
      double dt;
    };
    // The implicit step at its automatic value, at net A's flight step (5.08e-4 s, that of its
    // stiffest, knotted nodes) and at a quarter of it.
    const Case cases[] = {{"explicit", 0},       {"implicit", 0},       {"implicit", 5.08e-4},
                          {"implicit", 2.54e-4}, {"implicit", 1.27e-4}, {"verlet", 0}};
    for (const Case& c : cases) {
      const Wave w = c.integrator == std::string("explicit") && c.dt == 0
                         ? auto_explicit
                         : Run(length, c.integrator, c.dt, periods);
      if (!w.ok) {
        std::printf("| %.2f m, %d segments | %.2f | %s | %.3g | – | failed: %s |\n", length,
                    static_cast<int>(std::lround(length / kSegment)), omega_eb / (2 * M_PI),
                    c.integrator, c.dt, w.error.c_str());
        continue;
      }
      std::printf(
          "| %.2f m, %d segments | %.2f | %s%s | %.3g | %.3f | %.3f | %+.2f %% | %.2e | %.2e |"
          " %.3f / %.3f |\n",
          length, static_cast<int>(std::lround(length / kSegment)), omega_eb / (2 * M_PI),
          c.integrator, c.dt == 0 ? " (auto)" : "", w.dt, reference.omega * w.dt,
          w.omega / (2 * M_PI), 100 * (w.omega / reference.omega - 1), w.zeta, zeta_material,
          std::exp(-w.zeta * reference.omega * 2), std::exp(-zeta_material * omega_eb * 2));
      std::fflush(stdout);
    }
  }
  return 0;
}
