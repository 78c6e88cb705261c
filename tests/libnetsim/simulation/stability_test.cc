#include "libnetsim/simulation/stability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/segment_force.h"
#include "libnetsim/simulation/simulation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

// Spectral radius of the symplectic Euler step of m x'' + c x' + k x = 0.
double SpectralRadius(double k, double c, double m, double dt) {
  const double a11 = 1.0 - dt * dt * k / m, a12 = dt * (1.0 - dt * c / m);
  const double a21 = -dt * k / m, a22 = 1.0 - dt * c / m;
  const double trace = a11 + a22, det = a11 * a22 - a12 * a21;
  const std::complex<double> root = std::sqrt(std::complex<double>(trace * trace / 4.0 - det));
  return std::max(std::abs(trace / 2.0 + root), std::abs(trace / 2.0 - root));
}

TEST(Stability, StableStepIsTheExactLimitOfTheDampedOscillator) {
  for (double c : {0.0, 0.5, 3.0, 30.0}) {
    const double dt = StableStep(100.0, c, 1.0);
    EXPECT_LE(SpectralRadius(100.0, c, 1.0, 0.999 * dt), 1.0 + 1e-12) << c;
    EXPECT_GT(SpectralRadius(100.0, c, 1.0, 1.01 * dt), 1.0) << c;
  }
  EXPECT_TRUE(std::isinf(StableStep(0.0, 0.0, 1.0)));
}

std::unique_ptr<Simulation> Thread(double dt, bool scale) {
  auto [model, state] = testing::StraightRod(testing::PpYarn(), 0.3, 30, Fixity::kPinned);
  testing::Perturb(state, 1e-5, 1e-3, 3);
  std::vector<std::unique_ptr<Force>> forces;
  forces.push_back(std::make_unique<SegmentForce>());
  forces.push_back(std::make_unique<BendTwistForce>(model));
  SimulationOptions o;
  o.dt = dt;
  o.scale_rotational_inertia = scale;
  return std::make_unique<Simulation>(std::move(model), std::move(state), std::move(forces), o);
}

// The estimate is an upper bound on every frequency, so the automatic step is stable, and it is
// tight: 30 % above the estimated limit the thread blows up.
TEST(Stability, EstimatedLimitIsSafeAndTight) {
  const double limit = Thread(0.0, true)->stability().dt_limit;
  auto stable = Thread(0.0, true);
  EXPECT_NEAR(stable->dt(), 0.9 * limit, 1e-15);
  EXPECT_TRUE(stable->Advance(20000)) << stable->failure()->message;
  auto unstable = Thread(1.3 * limit, true);
  EXPECT_FALSE(unstable->Advance(20000));
}

// The thin-thread treatment: with physical cross-section inertia the rotations limit the step;
// scaled, the stretching wave does, and the step grows accordingly.
TEST(Stability, RotationalInertiaScalingLiftsTheRotationalLimit) {
  const auto physical = Thread(0.0, false);
  const auto scaled = Thread(0.0, true);
  EXPECT_GE(physical->stability().limiting_segment, 0);  // a rotation limits
  EXPECT_GE(scaled->stability().limiting_node, 0);       // a node limits
  EXPECT_GT(scaled->dt() / physical->dt(), 5.0);
  EXPECT_GT(scaled->stability().max_inertia_scale, 10.0);
  // The stretching wave: dt_limit ~ l / c with c = sqrt(EA / mu).
  const double c = std::sqrt(1178 / 7.1e-4), l = 0.01;
  EXPECT_NEAR(scaled->stability().dt_limit / (l / c), 1.0, 0.1);
}

}  // namespace
}  // namespace netlab::netsim
