#include "libnetsim/forces/coupling_force.h"

#include "libnetsim/rotation.h"

namespace netlab::netsim {

void CouplingForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                               ForceBuffers& out) const {
  const Vector3d* x = state.x.data();
  const Quaterniond* q = state.q.data();
  Vector3d* f = out.force.data();
  Vector3d* tau = out.torque.data();
  const int n = model.num_segments();
  for (int j = 0; j < n; ++j) {
    const Segment& s = model.segments[j];
    const Vector3d e = x[s.node_b] - x[s.node_a];
    const double inv_length = 1.0 / e.norm();
    const Vector3d t = e * inv_length;
    const Vector3d d3 = Director3(q[j]);
    const double kl = s.coupling_stiffness * s.rest_length;
    const Vector3d fb = (kl * inv_length) * (d3 - t.dot(d3) * t);
    f[s.node_b] += fb;
    f[s.node_a] -= fb;
    const Vector3d t_body = q[j].conjugate() * t;
    tau[j] += kl * Vector3d(-t_body.y(), t_body.x(), 0.0);
  }
}

double CouplingForce::Energy(const Model& model, const State& state) const {
  double energy = 0.0;
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    const Vector3d t = (state.x[s.node_b] - state.x[s.node_a]).normalized();
    energy += s.coupling_stiffness * s.rest_length * (1.0 - t.dot(Director3(state.q[j])));
  }
  return energy;
}

void CouplingForce::AddStiffnessBounds(const Model& model, const State& /*state*/,
                                       StiffnessBounds& bounds) const {
  // Linearised: E = 1/2 kappa l |u/l - psi|^2 (u transverse displacement of b against a, psi the
  // rotation). With psi measured as the displacement l psi, every entry is kappa/l: row sums
  // 3 kappa/l for each node and 3 kappa/l for the rotation, i.e. 3 kappa l in N m/rad.
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    const double k = 3.0 * s.coupling_stiffness / s.rest_length;
    bounds.node_stiffness[s.node_a] += k;
    bounds.node_stiffness[s.node_b] += k;
    bounds.segment_stiffness[j] += 3.0 * s.coupling_stiffness * s.rest_length;
  }
}

}  // namespace netlab::netsim
