#include "libnetsim/forces/point_load_force.h"

namespace netlab::netsim {

void PointLoadForce::Accumulate(const Model& /*model*/, const State& state, double /*dt*/,
                                ForceBuffers& out) const {
  for (const PointLoad& load : loads_) {
    if (load.kind == PointLoad::Kind::kForce) {
      out.force[load.index] += load.vector;
    } else {
      out.torque[load.index] += state.q[load.index].conjugate() * load.vector;
    }
  }
}

double PointLoadForce::Energy(const Model& /*model*/, const State& state) const {
  double energy = 0.0;
  for (const PointLoad& load : loads_)
    if (load.kind == PointLoad::Kind::kForce) energy -= load.vector.dot(state.x[load.index]);
  return energy;
}

}  // namespace netlab::netsim
