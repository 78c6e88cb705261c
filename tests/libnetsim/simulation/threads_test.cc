// Threads within a simulation (SimulationOptions::threads): a net with every force that splits
// its loop (stretching, coupling, drag, bending and torsion with damping), falling onto a sphere,
// gives the same bits with 2 and 3 threads as with 1, step after step; with the explicit and the
// implicit integrator (whose stretching solve is one thread, its frame update split by segment).

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {
namespace {

const char* kNet = R"(name: threads
duration: 0.01
output_interval: 0.005
integrator: {type: explicit, dt: auto}
gravity: [0, 0, -9.81]
drag: {air_density: 1.2, drag_coefficient: 1.2, tangential_coefficient: 0.1}
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          stretch_damping: 7.6e-4, bend_stiffness: 9.82e-5, bend_damping: 6.0e-9,
          twist_stiffness: 7.07e-5, twist_damping: 5.7e-11}
nets:
  - {name: net, material: nylon, knots: [9, 9], mesh: 0.06, segments_per_link: 3,
     center: [0, 0, 0.203], normal: [0, 0, 1], x_axis: [1, 0, 0], corner_mass: 0.02,
     velocity: [0, 0, -1.5], spread: 0.97}
bodies:
  - {name: ball, shape: sphere, center: [0, 0, 0], radius: 0.2}
)";

struct EndState {
  std::vector<Vector3d> x, v, w;
  std::vector<Quaterniond> q;
  double max_penetration = 0.0;
};

EndState Steps(int threads, int steps, IntegratorType integrator) {
  Scenario s = ParseScenario(kNet, "threads", "");
  s.simulation.threads = threads;
  s.simulation.integrator = integrator;
  BuiltScenario built = BuildScenario(s);
  for (int i = 0; i < steps; ++i) EXPECT_TRUE(built.simulation->Step());
  const State& state = built.simulation->state();
  return {state.x, state.v, state.w, state.q, built.simulation->max_penetration()};
}

TEST(Threads, GiveTheSameBitsAsOneThread) {
  for (const IntegratorType integrator :
       {IntegratorType::kSymplecticEuler, IntegratorType::kImplicit}) {
    SCOPED_TRACE(IntegratorName(integrator));
    // The implicit step is ~30 times longer: the same 0.01 s or more.
    const int steps = integrator == IntegratorType::kImplicit ? 60 : 1000;
    const EndState one = Steps(1, steps, integrator);
    ASSERT_EQ(one.x.size(), 81u + 144u * 2u);  // knots, and two inner nodes a link
    // The net touched the ball: the contact and every force were exercised.
    EXPECT_GT(one.max_penetration, 0.0);
    for (const int threads : {2, 3}) {
      const EndState many = Steps(threads, steps, integrator);
      ASSERT_EQ(many.x.size(), one.x.size());
      int differ = 0;
      for (size_t i = 0; i < one.x.size(); ++i)
        differ += one.x[i] != many.x[i] || one.v[i] != many.v[i];
      for (size_t j = 0; j < one.q.size(); ++j)
        differ += one.w[j] != many.w[j] || one.q[j].coeffs() != many.q[j].coeffs();
      EXPECT_EQ(differ, 0) << threads << " threads";
    }
  }
}

TEST(Threads, ACountOutOfRangeIsRefused) {
  Scenario s = ParseScenario(kNet, "threads", "");
  s.simulation.threads = 0;
  EXPECT_THROW(BuildScenario(s), std::exception);
  std::string text = kNet;
  text.replace(text.find("dt: auto}"), 9, "dt: auto, threads: 0}");
  EXPECT_THROW(ParseScenario(text, "threads", ""), std::exception);
}

}  // namespace
}  // namespace netlab::netsim
