#include "libnetsim/forces/drag_force.h"

#include <cmath>

namespace netlab::netsim {

bool DragOptions::IsValid(std::string* error) const {
  if (!(air_density >= 0.0) || !std::isfinite(air_density)) {
    if (error) *error = "air_density must be >= 0";
    return false;
  }
  if (!(drag_coefficient >= 0.0) || !std::isfinite(drag_coefficient)) {
    if (error) *error = "drag_coefficient must be >= 0";
    return false;
  }
  if (!(tangential_coefficient >= 0.0) || !std::isfinite(tangential_coefficient)) {
    if (error) *error = "tangential_coefficient must be >= 0";
    return false;
  }
  return true;
}

void DragForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                           ForceBuffers& out) const {
  for (const Segment& s : model.segments) {
    const Vector3d e = state.x[s.node_b] - state.x[s.node_a];
    const double length = e.norm();
    const Vector3d t = e / length;
    AddSegmentDrag(options_, s.diameter, length, t.x(), t.y(), t.z(), state.v[s.node_a].data(),
                   state.v[s.node_b].data(), out.force[s.node_a].data(),
                   out.force[s.node_b].data());
  }
}

}  // namespace netlab::netsim
