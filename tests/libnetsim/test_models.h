#pragma once
// Shared fixtures of the libnetsim tests: materials and small models.

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/segment_force.h"
#include "libnetsim/model/model_builder.h"
#include "libnetsim/model/rotation.h"
#include "libnetsim/simulation/simulation.h"

namespace netlab::netsim::testing {

// Every integrator, for the parameterised suites: an integrator added here is tested by all of
// them.
inline auto AllIntegrators() {
  return ::testing::Values(IntegratorType::kSymplecticEuler, IntegratorType::kVelocityVerlet,
                           IntegratorType::kImplicit);
}
inline std::string IntegratorTestName(const ::testing::TestParamInfo<IntegratorType>& info) {
  return IntegratorName(info.param);
}

// The polypropylene yarn of the paper's examples (the values of scenarios/pendulum.yaml).
inline Material PpYarn() {
  Material m;
  m.name = "pp_yarn";
  m.diameter = 1.0e-3;
  m.linear_density = 7.1e-4;
  m.stretch_stiffness = 1178;
  m.bend_stiffness = 7.36e-5;
  m.twist_stiffness = 5.45e-5;
  return m;
}

// 1 mm Nylon thread (scenarios/net_a_0.5.yaml), undamped.
inline Material Nylon() {
  Material m;
  m.name = "nylon";
  m.diameter = 1.0e-3;
  m.linear_density = 8.95e-4;
  m.stretch_stiffness = 1571;
  m.bend_stiffness = 9.82e-5;
  m.twist_stiffness = 7.07e-5;
  return m;
}

// The internal forces of a model: stretching and coupling, and bending/torsion where it has joints.
inline std::vector<std::unique_ptr<Force>> ElasticForces(const Model& model) {
  std::vector<std::unique_ptr<Force>> forces;
  forces.push_back(std::make_unique<SegmentForce>());
  if (!model.bend_pairs.empty() || !model.anchors.empty())
    forces.push_back(std::make_unique<BendTwistForce>(model));
  return forces;
}

// A straight rod along +x from the origin.
inline std::pair<Model, State> StraightRod(const Material& material, double length, int segments,
                                           Fixity start = Fixity::kFree, Fixity end = Fixity::kFree,
                                           ModelBuilderOptions options = {}) {
  ModelBuilder builder(options);
  RodSpec rod;
  rod.name = "rod";
  rod.material = builder.AddMaterial(material);
  rod.end = Vector3d(length, 0, 0);
  rod.segments = segments;
  rod.fix_start = start;
  rod.fix_end = end;
  builder.AddRod(rod);
  return std::move(builder).Build();
}

// The paper's net (6 x 6 knots of PP yarn, 20 cm links of 5 segments, 0.5 kg corners) centred
// `height` above the origin, falling at 5 m/s: the hard contact case.
inline std::pair<Model, State> PaperNetFalling(double height) {
  ModelBuilder builder;
  NetSpec net;
  net.name = "net";
  net.material = builder.AddMaterial(PpYarn());
  net.rows = net.cols = 6;
  net.mesh = 0.2;
  net.segments_per_link = 5;
  net.corner_mass = 0.5;
  net.center = Vector3d(0, 0, height);
  net.velocity = Vector3d(0, 0, -5.0);
  builder.AddNet(net);
  return std::move(builder).Build();
}

// An oscillation's period, from the upward crossings of the middle of its range (interpolated
// between samples), and its range (max - min): of a signal y sampled at times t. Expects at least
// three crossings; the period is 0 with fewer than two.
inline std::pair<double, double> PeriodAndRange(const std::vector<double>& t,
                                                const std::vector<double>& y) {
  const auto [low, high] = std::minmax_element(y.begin(), y.end());
  const double middle = 0.5 * (*low + *high);
  std::vector<double> crossings;
  for (size_t i = 0; i + 1 < y.size(); ++i)
    if (y[i] < middle && y[i + 1] >= middle)
      crossings.push_back(t[i] + (middle - y[i]) / (y[i + 1] - y[i]) * (t[i + 1] - t[i]));
  EXPECT_GE(crossings.size(), 3u);
  if (crossings.size() < 2) return {0.0, *high - *low};
  return {(crossings.back() - crossings.front()) / (crossings.size() - 1), *high - *low};
}

// Moves every node and turns every frame by random amounts (m, rad).
inline void Perturb(State& state, double dx, double dtheta, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vector3d& x : state.x) x += dx * Vector3d(u(rng), u(rng), u(rng));
  for (Vector3d& v : state.v) v = Vector3d(u(rng), u(rng), u(rng));
  for (Quaterniond& q : state.q)
    q = (q * ExpMap(dtheta * Vector3d(u(rng), u(rng), u(rng)))).normalized();
  for (Vector3d& w : state.w) w = Vector3d(u(rng), u(rng), u(rng));
}

}  // namespace netlab::netsim::testing
