// Static equilibria against closed forms and published tables. Equilibria are found by dynamic
// relaxation (Simulation::Relax, kinetic damping) of the full dynamic model.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/gravity_force.h"
#include "libnetsim/forces/point_load_force.h"
#include "libnetsim/forces/segment_force.h"
#include "libnetsim/simulation/simulation.h"
#include "tests/libnetsim/test_models.h"

namespace netlab::netsim {
namespace {

using testing::ElasticForces;
using testing::PpYarn;
using testing::StraightRod;

// A unit rod (L = 1 m, EI = 1 N m^2) nearly inextensible (EA = 1e5 N), for the elastica.
Material UnitRod() {
  Material m;
  m.name = "unit";
  m.diameter = 0.01;
  m.linear_density = 1.0;
  m.stretch_stiffness = 1e5;
  m.bend_stiffness = 1.0;
  m.twist_stiffness = 1.0;
  return m;
}

// Small-deflection cantilever under its own weight: tip deflection q L^4 / (8 EI).
TEST(Statics, CantileverUnderSelfWeightMatchesBeamTheory) {
  for (int segments : {11, 40}) {
    const Material pp = PpYarn();  // paper sec. 3: 8 cm PP yarn, 11 segments, clamped
    const double length = 0.08, g = 9.81;
    auto [model, state] = StraightRod(pp, length, segments, Fixity::kClamped);
    auto forces = ElasticForces(model);
    forces.push_back(std::make_unique<GravityForce>(Vector3d(0, -g, 0)));
    Simulation sim(std::move(model), std::move(state), std::move(forces), SimulationOptions{});
    // Residuals below 2e-6 of a node's weight (~5e-5 N).
    ASSERT_TRUE(sim.Relax(20.0, 1e-10, 1e-11)) << segments;
    const double q = pp.linear_density * g;
    const double expected = q * std::pow(length, 4) / (8.0 * pp.bend_stiffness);
    const double tip = -sim.state().x.back().y();
    // Second-order discretisation, measured 1.04 / n^2 (0.86 % at the paper's 11 segments).
    EXPECT_NEAR(tip / expected, 1.0, 1.2 / (segments * segments)) << segments << " segments";
  }
}

// A clamped rod under a dead end moment M rolls up into a circular arc of radius EI / M. The
// discrete rod (log-map curvature, half-segment clamp joint) forms the inscribed regular polygon
// exactly: M = 2 pi EI / L closes it, M = pi EI / L makes a half circle of chord 2 rho with
// rho = l / (2 sin(pi / (2 n))). A dead moment is not conservative in 3D, so kinetic damping does
// not apply: the rod rolls up under its own bending damping, as a real one would.
TEST(Statics, EndMomentRollsARodIntoACircle) {
  const int n = 24;
  const double length = 1.0;
  Material rod = UnitRod();
  rod.stretch_stiffness = 1e4;  // no axial force in pure bending: EA only sets the step
  rod.bend_damping = 0.3;       // N m^2 s: about critical for the first bending mode
  rod.twist_damping = 0.3;
  for (double turns : {0.5, 1.0}) {
    auto [model, state] = StraightRod(rod, length, n, Fixity::kClamped);
    const int last = model.num_segments() - 1;
    auto forces = ElasticForces(model);
    PointLoad moment;
    moment.kind = PointLoad::Kind::kMoment;
    moment.index = last;
    moment.vector = Vector3d(0, 0, 2.0 * std::numbers::pi * turns / length);  // EI = 1
    forces.push_back(std::make_unique<PointLoadForce>(std::vector<PointLoad>{moment}));
    Simulation sim(std::move(model), std::move(state), std::move(forces), SimulationOptions{});
    ASSERT_TRUE(sim.Advance(std::lround(8.0 / sim.dt()))) << sim.failure()->message;
    const Vector3d tip = sim.state().x.back();
    const double rho = (length / n) / (2.0 * std::sin(std::numbers::pi * turns / n));
    if (turns == 1.0) {
      EXPECT_LT(tip.norm(), 1e-6 * length);  // the circle closes
    } else {
      EXPECT_NEAR(tip.x(), 0.0, 1e-6);
      EXPECT_NEAR(tip.y(), 2.0 * rho, 1e-6);
      // ... and the continuum half circle, chord 2 L / pi, within the O(1/n^2) polygon error.
      EXPECT_NEAR(tip.y(), 2.0 * length / std::numbers::pi, 2e-3);
    }
    // Every node lies on the circle of radius rho about (0, rho, 0), in the plane z = 0.
    for (const Vector3d& x : sim.state().x) {
      EXPECT_NEAR((x - Vector3d(0, rho, 0)).norm(), rho, 1e-6);
      EXPECT_NEAR(x.z(), 0.0, 1e-9);
    }
  }
}

struct ElasticaCase {
  double lambda;        // P L^2 / EI
  double v_over_l;      // tip deflection along the load
  double u_over_l;      // tip shortening along the rod
  double tip_rotation;  // rad
};

// Mattiasson (1981), large-deflection cantilever with a dead tip load, v/L and u/L; the tip
// rotation from an independent shooting solve of the elastica (RK4, 4000 steps).
const ElasticaCase kMattiasson[] = {
    {1.0, 0.30172, 0.05643, 0.46135},
    {2.0, 0.49346, 0.16064, 0.78175},
    {5.0, 0.71379, 0.38763, 1.21537},
    {10.0, 0.81061, 0.55500, 1.43029},
};

struct ElasticaResult {
  double v, u, rotation;
};

ElasticaResult SolveTipLoadedCantilever(double lambda, int segments) {
  auto [model, state] = StraightRod(UnitRod(), 1.0, segments, Fixity::kClamped);
  const int tip = model.num_nodes() - 1;
  auto forces = ElasticForces(model);
  PointLoad load;
  load.index = tip;
  load.vector = Vector3d(0, -lambda, 0);  // EI = L = 1
  forces.push_back(std::make_unique<PointLoadForce>(std::vector<PointLoad>{load}));
  Simulation sim(std::move(model), std::move(state), std::move(forces), SimulationOptions{});
  EXPECT_TRUE(sim.Relax(60.0, 1e-8, 1e-8)) << "lambda " << lambda;
  const Vector3d x = sim.state().x[tip];
  const Vector3d t = (x - sim.state().x[tip - 1]).normalized();
  return {-x.y(), 1.0 - x.x(), std::atan2(-t.y(), t.x())};
}

TEST(Statics, LargeDeflectionCantileverMatchesMattiassonTable) {
  for (const ElasticaCase& c : kMattiasson) {
    const ElasticaResult r = SolveTipLoadedCantilever(c.lambda, 40);
    // Axial strain P/EA <= 1e-4 and O(1/n^2) discretisation: 2e-3 of L covers both.
    EXPECT_NEAR(r.v, c.v_over_l, 2e-3) << "lambda " << c.lambda;
    EXPECT_NEAR(r.u, c.u_over_l, 2e-3) << "lambda " << c.lambda;
    // The last segment's direction is the tangent half a segment before the tip.
    EXPECT_NEAR(r.rotation, c.tip_rotation, 2e-2) << "lambda " << c.lambda;
  }
}

// Halving the segment length quarters the error: second-order convergence in space.
TEST(Statics, ConvergesWithSecondOrderInTheSegmentLength) {
  const ElasticaCase& c = kMattiasson[1];  // lambda = 2
  double previous = 0.0;
  for (int segments : {8, 16, 32}) {
    const ElasticaResult r = SolveTipLoadedCantilever(c.lambda, segments);
    const double error = std::abs(r.v - c.v_over_l);
    if (previous > 0.0) {
      const double order = std::log2(previous / error);
      EXPECT_GT(order, 1.7) << segments << " segments: error " << error << " after " << previous;
    }
    previous = error;
  }
}

}  // namespace
}  // namespace netlab::netsim
