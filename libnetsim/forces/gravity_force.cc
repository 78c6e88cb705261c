#include "libnetsim/forces/gravity_force.h"

namespace netlab::netsim {

void GravityForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                              ForceBuffers& out) const {
  const Vector3d g = At(state.time);
  const int n = model.num_nodes();
  for (int i = 0; i < n; ++i) out.force[i] += model.node_mass[i] * g;
}

double GravityForce::Energy(const Model& model, const State& state) const {
  const Vector3d g = At(state.time);
  double energy = 0.0;
  for (int i = 0; i < model.num_nodes(); ++i) energy -= model.node_mass[i] * g.dot(state.x[i]);
  return energy;
}

}  // namespace netlab::netsim
