#include "libnetsim/forces/stretch_force.h"

#include <cmath>

namespace netlab::netsim {

void StretchForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                              ForceBuffers& out) const {
  const Vector3d* x = state.x.data();
  const Vector3d* v = state.v.data();
  Vector3d* f = out.force.data();
  for (const Segment& s : model.segments) {
    const Vector3d e = x[s.node_b] - x[s.node_a];
    const double length = e.norm();
    const Vector3d t = e / length;
    const double inv_l = 1.0 / s.rest_length;
    const double strain = length * inv_l - 1.0;
    double axial = s.stretch_stiffness * strain;  // N, positive in tension
    if (s.stretch_damping != 0.0)
      axial += s.stretch_damping * t.dot(v[s.node_b] - v[s.node_a]) * inv_l;
    const Vector3d fa = axial * t;
    f[s.node_a] += fa;
    f[s.node_b] -= fa;
  }
}

double StretchForce::Energy(const Model& model, const State& state) const {
  double energy = 0.0;
  for (const Segment& s : model.segments) {
    const double strain = (state.x[s.node_b] - state.x[s.node_a]).norm() / s.rest_length - 1.0;
    energy += 0.5 * s.stretch_stiffness * s.rest_length * strain * strain;
  }
  return energy;
}

void StretchForce::AddStiffnessBounds(const Model& model, const State& state,
                                      StiffnessBounds& bounds) const {
  for (const Segment& s : model.segments) {
    // Axial stiffness EA/l, plus the geometric (string) stiffness |N|/|e| of the current tension,
    // each counted for the node itself and its neighbour.
    const double length = (state.x[s.node_b] - state.x[s.node_a]).norm();
    const double tension = std::abs(s.stretch_stiffness * (length / s.rest_length - 1.0));
    const double k = 2.0 * (s.stretch_stiffness / s.rest_length + tension / length);
    const double c = 2.0 * s.stretch_damping / s.rest_length;
    bounds.node_stiffness[s.node_a] += k;
    bounds.node_stiffness[s.node_b] += k;
    bounds.node_damping[s.node_a] += c;
    bounds.node_damping[s.node_b] += c;
  }
}

}  // namespace netlab::netsim
