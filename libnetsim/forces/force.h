#pragma once
// One interface for every force of the simulator (after dismech-rods): each force lives in its own
// file, accumulates node forces and segment torques, and the stepper sums them. A force a scene
// does not use is never constructed, so it costs nothing.
//
// Generalised forces:
//   node forces    world (simulation) frame, N, one per node
//   segment torques body frame of the segment, N m, one per segment: the work conjugate of a
//                  body-frame rotation q -> q Exp(dtheta).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libnetsim/model/model.h"

namespace netlab::netsim {

struct ForceBuffers {
  std::vector<Vector3d> force;   // per node, N
  std::vector<Vector3d> torque;  // per segment, N m
  // Deepest contact penetration found by this evaluation (m) and its node (-1: none).
  double max_penetration = 0.0;
  int max_penetration_node = -1;

  void Resize(int nodes, int segments) {
    force.assign(nodes, Vector3d::Zero());
    torque.assign(segments, Vector3d::Zero());
  }
  void Zero() {
    for (Vector3d& f : force) f.setZero();
    for (Vector3d& t : torque) t.setZero();
    max_penetration = 0.0;
    max_penetration_node = -1;
  }
};

// Per-DOF bounds on the stiffness and damping a force adds, for the explicit stability estimate
// (stability.h): Gershgorin row sums of the linearised stiffness and damping matrices, with
// rotations measured as displacements at the segment's length scale.
struct StiffnessBounds {
  std::vector<double> node_stiffness;     // N/m
  std::vector<double> node_damping;       // N s/m
  std::vector<double> segment_stiffness;  // N m/rad (divide by an inertia in kg m^2 for omega^2)
  std::vector<double> segment_damping;    // N m s/rad

  void Resize(int nodes, int segments) {
    node_stiffness.assign(nodes, 0.0);
    node_damping.assign(nodes, 0.0);
    segment_stiffness.assign(segments, 0.0);
    segment_damping.assign(segments, 0.0);
  }
};

// Which of `items` (segments, joints), each acting on two places (its ends a and b: nodes,
// segments), act on each place, in ascending order: a threaded force sums each place's terms in
// the order its one-thread loop adds them. Entries are item * 2 (as a) or item * 2 + 1 (as b);
// place p's run from start[p] to start[p + 1].
struct Incidence {
  std::vector<int> start;
  std::vector<int> entries;

  // ends(i) -> {a, b} of item i.
  template <typename Ends>
  Incidence(int places, int items, Ends ends) : start(places + 1, 0) {
    for (int i = 0; i < items; ++i) {
      const auto [a, b] = ends(i);
      ++start[a + 1];
      ++start[b + 1];
    }
    for (int p = 0; p < places; ++p) start[p + 1] += start[p];
    entries.assign(start[places], 0);
    std::vector<int> next(start.begin(), start.end() - 1);
    for (int i = 0; i < items; ++i) {
      const auto [a, b] = ends(i);
      entries[next[a]++] = 2 * i;
      entries[next[b]++] = 2 * i + 1;
    }
  }
  Incidence() = default;
};

// Where a force's stored energy is reported (Energy in simulation.h).
enum class EnergyKind { kNone, kElastic, kPotential };

class Force {
 public:
  virtual ~Force() = default;

  // Short name shown in summaries: "stretch", "gravity", ...
  virtual std::string name() const = 0;

  // Adds this force to `out`. dt (s) is the step the integrator will take with it; only forces
  // that must not overshoot within one step (friction) use it.
  virtual void Accumulate(const Model& model, const State& state, double dt,
                          ForceBuffers& out) const = 0;

  // Energy this force stores in `state` (J), and where it is reported. Non-conservative forces
  // (damping, drag, Coriolis, friction) return 0 with kNone.
  virtual EnergyKind energy_kind() const { return EnergyKind::kNone; }
  virtual double Energy(const Model& /*model*/, const State& /*state*/) const { return 0.0; }

  // Adds this force's stiffness and damping bounds, linearised about `state`.
  virtual void AddStiffnessBounds(const Model& /*model*/, const State& /*state*/,
                                  StiffnessBounds& /*bounds*/) const {}

  // The threads Accumulate may use (>= 1). A force that splits its loop over them gives the
  // same bits as with one: each element's terms are computed apart, then summed into each node
  // or segment in the order one thread adds them. The others ignore it.
  virtual void SetThreads(int /*threads*/) {}
};

}  // namespace netlab::netsim
