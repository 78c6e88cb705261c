#include "libnetsim/characterization/synthetic_bench.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

#include "libnetsim/characterization/heavy_cantilever.h"
#include "libnetsim/scenario/scenario.h"

namespace netlab::netsim {
namespace {

constexpr double kGravity = 9.81;

std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", v);
  return buffer;
}

std::string MaterialYaml(const Material& m) {
  return "{diameter: " + Num(m.diameter) + ", linear_density: " + Num(m.linear_density) +
         ", stretch_stiffness: " + Num(m.stretch_stiffness) +
         ", stretch_damping: " + Num(m.stretch_damping) +
         ", bend_stiffness: " + Num(m.bend_stiffness) + ", bend_damping: " + Num(m.bend_damping) +
         ", twist_stiffness: " + Num(m.twist_stiffness) +
         ", twist_damping: " + Num(m.twist_damping) + "}";
}

void Advance(Simulation& sim, long steps) {
  if (!sim.Advance(steps)) throw std::runtime_error(sim.failure()->message);
}

class Noise {
 public:
  explicit Noise(uint32_t seed) : engine_(seed) {}
  double operator()(double sigma) { return sigma * normal_(engine_); }

 private:
  std::mt19937 engine_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

BenchTest NewTest(BenchKind kind, const Material& truth, const SyntheticWeighing& w, Noise& noise) {
  BenchTest test;
  test.kind = kind;
  test.material = truth.name.empty() ? "nylon_1mm" : truth.name;
  test.source = BenchKindName(kind) + ".yaml";
  test.path = test.source;
  Weighing weighing;
  weighing.mass = truth.linear_density * w.length + noise(w.mass_sigma);
  weighing.mass_sigma = w.mass_sigma;
  weighing.length = w.length + noise(w.length_sigma);
  weighing.length_sigma = w.length_sigma;
  test.weighing = weighing;
  return test;
}

// The cantilever rod, clamped at the origin along +x, gravity along -y.
std::string CantileverRod(const SyntheticCantilever& s) {
  return "{name: thread, material: thread, start: [0, 0, 0], end: [" + Num(s.length) +
         ", 0, 0], segments: " + std::to_string(s.segments) + ", fixed: {start: clamped}}";
}

// Relaxed to rest (kinetic damping): every node force below 1e-9 N, torque below 1e-12 N m.
void RelaxCantilever(Simulation& sim) {
  if (!sim.Relax(60.0, 1e-9, 1e-12))
    throw std::runtime_error("synthetic cantilever: the relaxation did not converge");
}

// The truth with only the dampings `kind` measures: the others change nothing the test records
// but would set the explicit step (a stretch damping of 0.5 N s makes it 40 times smaller).
Material OnlyDampingsOf(Material m, BenchKind kind) {
  if (kind != BenchKind::kTensile) m.stretch_damping = 0;
  if (kind != BenchKind::kCantilever) m.bend_damping = 0;
  if (kind != BenchKind::kTorsion) m.twist_damping = 0;
  return m;
}

// A one-rod scene: `integrator` and `extra` (gravity, loads) as YAML lines, the rod as a flow map.
BuiltScenario Build(BenchKind kind, double interval, const std::string& integrator,
                    const Material& truth, const std::string& rod, const std::string& extra) {
  const Material m = OnlyDampingsOf(truth, kind);
  const std::string name = BenchKindName(kind);
  const std::string text = "name: " + name + "\nduration: 1\noutput_interval: " + Num(interval) +
                           "\nintegrator: " + integrator +
                           "\nmaterials:\n  thread: " + MaterialYaml(m) + "\nrods:\n  - " + rod +
                           "\n" + extra;
  return BuildScenario(ParseScenario(text, "synthetic " + name, ""));
}

}  // namespace

double TorsionFreeLength(const SyntheticTorsion& setup) {
  return setup.length * (1.0 - 0.5 / setup.segments);
}

Material BenchNylon(double loss_factor) {
  Material m;
  m.name = "nylon_1mm";
  m.diameter = 1.0e-3;
  m.linear_density = 8.95e-4;
  m.stretch_stiffness = 1571;
  m.bend_stiffness = 9.82e-5;
  m.twist_stiffness = 7.07e-5;
  // c = eta K / omega at each default test's frequency.
  m.stretch_damping = loss_factor * m.stretch_stiffness / (2 * M_PI * SyntheticTensile().frequency);
  const SyntheticCantilever cantilever;
  const double alpha = m.bend_stiffness / (m.linear_density * kGravity);
  const double bend_omega = FirstMode(SolveHeavyCantilever(cantilever.length, alpha, 100),
                                      cantilever.length, alpha, kGravity)
                                .omega;
  m.bend_damping = loss_factor * m.bend_stiffness / bend_omega;
  const SyntheticTorsion torsion;
  const double twist_omega =
      std::sqrt(m.twist_stiffness / (torsion.inertia * TorsionFreeLength(torsion)));
  m.twist_damping = loss_factor * m.twist_stiffness / twist_omega;
  return m;
}

BenchTest SimulateTensileTest(const Material& truth, const SyntheticTensile& s,
                              const SyntheticWeighing& weighing, uint32_t seed) {
  Noise noise(seed);
  BenchTest test = NewTest(BenchKind::kTensile, truth, weighing, noise);
  test.description = "simulated cyclic stretch at " + Num(s.frequency) + " Hz";
  test.tensile.gauge_length = s.gauge_length;
  const double duration = s.cycles / s.frequency, interval = duration / s.samples;
  const std::string rod = "{name: specimen, material: thread, start: [0, 0, 0], end: [" +
                          Num(s.gauge_length) + ", 0, 0], segments: " + std::to_string(s.segments) +
                          ", fixed: {start: pinned, end: pinned}}";
  BuiltScenario built = Build(BenchKind::kTensile, interval, "{type: explicit}", truth, rod, "");
  Simulation& sim = *built.simulation;
  const int grip = sim.model().num_nodes() - 1;
  const long steps_per_sample = std::lround(interval / sim.dt());
  const double omega = 2 * M_PI * s.frequency, amplitude = s.strain_amplitude * s.gauge_length;
  for (int k = 0; k <= s.samples; ++k) {
    // The load cell at the fixed grip reads the specimen's pull on node 0.
    sim.EvaluateForces();
    const double t = sim.state().time;
    test.tensile.samples.rows.push_back(
        {t, sim.state().x[grip].x() - s.gauge_length + noise(s.extension_noise),
         sim.forces().force[0].x() + noise(s.force_noise)});
    for (long i = 0; i < steps_per_sample && k < s.samples; ++i) {
      // The moving grip (pinned: the integrator drifts it with the velocity it is given), at
      // the middle of the step's velocity so its position follows x_a (1 - cos) / 2 closely.
      const double mid = sim.state().time + 0.5 * sim.dt();
      sim.mutable_state().v[grip].x() = 0.5 * amplitude * omega * std::sin(omega * mid);
      Advance(sim, 1);
    }
  }
  return test;
}

BenchTest SimulateCantileverTest(const Material& truth, const SyntheticCantilever& s,
                                 const SyntheticWeighing& weighing, uint32_t seed) {
  Noise noise(seed);
  BenchTest test = NewTest(BenchKind::kCantilever, truth, weighing, noise);
  test.description = "simulated clamped thread under its own weight, then tapped";
  test.cantilever.length = s.length;
  test.cantilever.gravity = kGravity;
  const double interval = s.duration / s.oscillation_samples;
  const std::string gravity = "gravity: [0, " + Num(-kGravity) + ", 0]\n";
  // The shape at rest.
  BuiltScenario rest =
      Build(BenchKind::kCantilever, interval, "{type: explicit}", truth, CantileverRod(s), gravity);
  RelaxCantilever(*rest.simulation);
  const std::vector<Vector3d>& x = rest.simulation->state().x;
  for (int k = 1; k <= s.shape_points; ++k) {
    const Vector3d& p = x[std::lround(static_cast<double>(k) * s.segments / s.shape_points)];
    test.cantilever.shape.rows.push_back(
        {p.x() + noise(s.shape_noise), p.y() + noise(s.shape_noise)});
  }
  // Pushed down by a tip force, released: the free oscillation about the rest shape.
  const double push = s.push * truth.linear_density * kGravity * s.length;
  BuiltScenario pushed =
      Build(BenchKind::kCantilever, interval, "{type: explicit}", truth, CantileverRod(s),
            gravity + "loads:\n  - {type: force, rod: thread, node: end, vector: [0, " +
                Num(-push) + ", 0]}\n");
  RelaxCantilever(*pushed.simulation);
  BuiltScenario released =
      Build(BenchKind::kCantilever, interval, "{type: explicit}", truth, CantileverRod(s), gravity);
  Simulation& sim = *released.simulation;
  sim.mutable_state().x = pushed.simulation->state().x;
  sim.mutable_state().q = pushed.simulation->state().q;
  const long steps_per_sample = std::lround(interval / sim.dt());
  for (int k = 0; k < s.oscillation_samples; ++k) {
    test.cantilever.oscillation.rows.push_back(
        {sim.state().time, sim.state().x.back().y() + noise(s.oscillation_noise)});
    Advance(sim, steps_per_sample);
  }
  return test;
}

BenchTest SimulateTorsionTest(const Material& truth, const SyntheticTorsion& s,
                              const SyntheticWeighing& weighing, uint32_t seed) {
  Noise noise(seed);
  BenchTest test = NewTest(BenchKind::kTorsion, truth, weighing, noise);
  test.description = "simulated torsion pendulum, twisted from rest by a constant moment";
  const double free_length = TorsionFreeLength(s);
  test.torsion.length = free_length;
  test.torsion.inertia = s.inertia;
  const double interval = s.duration / s.samples;
  const double moment = s.mean_angle * truth.twist_stiffness / free_length;
  const std::string rod = "{name: thread, material: thread, start: [0, 0, 0], end: [0, 0, " +
                          Num(-s.length) + "], segments: " + std::to_string(s.segments) +
                          ", fixed: {start: clamped}, tip: {mass: " + Num(s.bob_mass) +
                          ", inertia: [" + Num(s.inertia / 2) + ", " + Num(s.inertia / 2) + ", " +
                          Num(s.inertia) + "]}}";
  // The moment about d3, which points down the thread (-z).
  BuiltScenario built = Build(
      BenchKind::kTorsion, interval, "{type: explicit, rotational_inertia: physical}", truth, rod,
      "loads:\n  - {type: moment, rod: thread, node: end, vector: [0, 0, " + Num(-moment) + "]}\n");
  Simulation& sim = *built.simulation;
  const Quaterniond start = sim.state().q.back();
  const long steps_per_sample = std::lround(interval / sim.dt());
  for (int k = 0; k < s.samples; ++k) {
    // The bob's turn about the thread: the twist part of its rotation since t = 0.
    const Quaterniond turn = start.conjugate() * sim.state().q.back();
    test.torsion.samples.rows.push_back(
        {sim.state().time, 2.0 * std::atan2(turn.z(), turn.w()) + noise(s.angle_noise)});
    Advance(sim, steps_per_sample);
  }
  return test;
}

}  // namespace netlab::netsim
