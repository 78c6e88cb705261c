#include "libnetsim/characterization/heavy_cantilever.h"

#include <gtest/gtest.h>

#include <cmath>

namespace netlab::netsim {
namespace {

// 1 mm Nylon: EI / (mu g) = 9.82e-5 / (8.95e-4 * 9.81).
constexpr double kAlpha = 9.82e-5 / (8.95e-4 * 9.81);

TEST(HeavyCantilever, SmallLoadDeflectsByTheBeamFormula) {
  // mu g L^3 / EI = 0.09: the tip drops by L^4 mu g / (8 EI) to within the O(deflection^2) of the
  // large-deflection terms.
  const double length = 0.1;
  const CantileverShape shape = SolveHeavyCantilever(length, kAlpha, 200);
  ASSERT_TRUE(shape.converged);
  const double beam = std::pow(length, 4) / (8 * kAlpha);
  EXPECT_NEAR(-shape.points.back().y(), beam, 2e-4 * beam);
}

TEST(HeavyCantilever, DiscretisationConvergesAtSecondOrder) {
  const double length = 0.6;
  const double fine = SolveHeavyCantilever(length, kAlpha, 800).points.back().y();
  const double e1 = std::abs(SolveHeavyCantilever(length, kAlpha, 50).points.back().y() - fine);
  const double e2 = std::abs(SolveHeavyCantilever(length, kAlpha, 100).points.back().y() - fine);
  EXPECT_NEAR(std::log2(e1 / e2), 2.0, 0.2);
}

TEST(HeavyCantilever, HeavyThreadHangsDownAndBackTowardsTheClamp) {
  // mu g L^3 / EI = 89: the thread hangs nearly vertical; no joint turns past it (the minimiser
  // does not jump into the thread folded back up).
  const CantileverShape shape = SolveHeavyCantilever(1.0, kAlpha, 200);
  ASSERT_TRUE(shape.converged);
  for (double theta : shape.theta) EXPECT_LT(theta, M_PI / 2 + 1e-9);
  EXPECT_GT(-shape.points.back().y(), 0.9);
}

TEST(HeavyCantilever, FirstModeOfALightlyLoadedThreadIsTheBeams) {
  // omega_1 = 3.516 sqrt(EI / (mu L^4)) and all of its stiffness bending.
  const double length = 0.1, g = 9.81;
  const CantileverMode mode =
      FirstMode(SolveHeavyCantilever(length, kAlpha, 100), length, kAlpha, g);
  const double beam = 3.5160 * std::sqrt(kAlpha * g / std::pow(length, 4));
  EXPECT_NEAR(mode.omega, beam, 1e-3 * beam);
  EXPECT_NEAR(mode.bending_fraction, 1.0, 1e-3);
}

TEST(HeavyCantilever, PeirceAgreesAtSmallDeflectionAndNotAtLarge) {
  const double mu = 8.95e-4, g = 9.81, ei = kAlpha * mu * g;
  const double small =
      PeirceBendStiffness(0.1, SolveHeavyCantilever(0.1, kAlpha).points.back(), mu, g);
  EXPECT_NEAR(small, ei, 1e-3 * ei);
  const double large =
      PeirceBendStiffness(0.6, SolveHeavyCantilever(0.6, kAlpha).points.back(), mu, g);
  EXPECT_GT(large / ei - 1, 0.1);
}

TEST(HeavyCantilever, SignedDistanceIsPositiveAboveTheCurve) {
  const std::vector<Eigen::Vector2d> line = {{0, 0}, {1, 0}, {2, -1}};
  EXPECT_NEAR(SignedDistanceToCurve(line, {0.5, 0.2}), 0.2, 1e-12);
  EXPECT_NEAR(SignedDistanceToCurve(line, {0.5, -0.3}), -0.3, 1e-12);
  EXPECT_NEAR(SignedDistanceToCurve(line, {2, 0}), std::sqrt(0.5), 1e-12);
}

}  // namespace
}  // namespace netlab::netsim
