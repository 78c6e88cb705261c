#include "libnetsim/model/rotation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace netlab::netsim {
namespace {

Quaterniond RandomRotation(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vector3d axis(u(rng), u(rng), u(rng));
  axis.normalize();
  return Quaterniond(Eigen::AngleAxisd(max_angle * std::abs(u(rng)), axis));
}

TEST(Rotation, Director3IsTheRotatedZAxis) {
  std::mt19937 rng(1);
  for (int i = 0; i < 20; ++i) {
    const Quaterniond q = RandomRotation(rng, 3.0);
    EXPECT_LT((Director3(q) - q * Vector3d::UnitZ()).norm(), 1e-14);
  }
}

TEST(Rotation, LogInvertsExpOverTheWholeRange) {
  // Either side of each series/closed-form switch: |phi| = 0.02 (Exp), theta = 2 atan(0.2) (Log).
  for (double angle : {0.0, 1e-9, 1e-5, 1e-3, 0.01, 0.0199, 0.0201, 0.0999, 0.1001, 0.3947, 0.3948,
                       0.5, 2.0, 3.1, std::numbers::pi - 1e-6}) {
    const Vector3d phi = angle * Vector3d(1, -2, 0.5).normalized();
    const LogResult log = LogMap(ExpMap(phi));
    EXPECT_LT((log.phi - phi).norm(), 1e-12 * std::max(1.0, angle)) << "angle " << angle;
  }
}

TEST(Rotation, LogPicksTheShorterOfQAndMinusQ) {
  const Quaterniond q(Eigen::AngleAxisd(0.3, Vector3d::UnitX()));
  const Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  EXPECT_LT((LogMap(minus_q).phi - Vector3d(0.3, 0, 0)).norm(), 1e-14);
}

TEST(Rotation, ExpMatchesAngleAxis) {
  for (double scale : {1e-6, 0.01, 1.0}) {
    const Vector3d phi = scale * Vector3d(0.2, -0.4, 1.1);
    const Quaterniond expected(Eigen::AngleAxisd(phi.norm(), phi.normalized()));
    EXPECT_LT((ExpMap(phi).coeffs() - expected.coeffs()).norm(), 1e-15) << scale;
  }
}

// The series coefficient b of Jr^-1 agrees with its closed form on both sides of the switch.
TEST(Rotation, LogCoefficientMatchesClosedForm) {
  for (double theta : {0.05, 0.0999, 0.1001, 0.2, 0.39, 0.4, 1.0}) {
    const LogResult log = LogMap(ExpMap(Vector3d(0, 0, theta)));
    const double exact = (1.0 - 0.5 * theta / std::tan(0.5 * theta)) / (theta * theta);
    EXPECT_NEAR(log.b, exact, 1e-12) << theta;
  }
}

TEST(Rotation, RotateBodyIsProductWithExp) {
  for (double scale : {1e-4, 0.05}) {
    Quaterniond q(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
    const Vector3d phi = scale * Vector3d(0.3, -1.0, 0.4);
    const Quaterniond expected = (q * ExpMap(phi)).normalized();
    RotateBody(q, phi);
    EXPECT_LT((q.coeffs() - expected.coeffs()).norm(), 1e-15) << scale;
  }
}

// Log(r Exp(d)) = phi + Jr^-1 d and Log(Exp(-d) r) = phi - Jl^-1 d, checked by finite differences.
TEST(Rotation, JacobianInversesMatchFiniteDifferences) {
  std::mt19937 rng(7);
  const double h = 1e-6;
  for (double max_angle : {1e-4, 0.09, 0.3, 0.45, 2.5}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Quaterniond r = RandomRotation(rng, max_angle);
      const LogResult log = LogMap(r);
      for (int k = 0; k < 3; ++k) {
        const Vector3d d = h * Vector3d::Unit(k);
        const Vector3d right = (LogMap(r * ExpMap(d)).phi - LogMap(r * ExpMap(-d)).phi) / (2 * h);
        const Vector3d left = (LogMap(ExpMap(d) * r).phi - LogMap(ExpMap(-d) * r).phi) / (2 * h);
        EXPECT_LT((right - ApplyJrInv(log, Vector3d::Unit(k))).norm(), 1e-7);
        EXPECT_LT((left - ApplyJlInv(log, Vector3d::Unit(k))).norm(), 1e-7);
      }
    }
  }
}

TEST(Rotation, FrameFromTangentAlongXIsThePaperPendulumFrame) {
  // Paper section 3: d1 = y, d2 = z, d3 = x for a rod along x.
  const Quaterniond q = FrameFromTangent(Vector3d::UnitX());
  EXPECT_LT((q * Vector3d::UnitX() - Vector3d::UnitY()).norm(), 1e-14);
  EXPECT_LT((q * Vector3d::UnitY() - Vector3d::UnitZ()).norm(), 1e-14);
  EXPECT_LT((q * Vector3d::UnitZ() - Vector3d::UnitX()).norm(), 1e-14);
}

TEST(Rotation, FrameFromTangentHandlesTangentsAlongY) {
  const Quaterniond q = FrameFromTangent(Vector3d(0, -1, 0));
  EXPECT_LT((Director3(q) - Vector3d(0, -1, 0)).norm(), 1e-14);
  EXPECT_NEAR(q.norm(), 1.0, 1e-14);
}

}  // namespace
}  // namespace netlab::netsim
