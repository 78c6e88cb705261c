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
  const double half_rho = 0.5 * options_.air_density;
  for (const Segment& s : model.segments) {
    const Vector3d e = state.x[s.node_b] - state.x[s.node_a];
    const double length = e.norm();
    const Vector3d t = e / length;
    const Vector3d v = 0.5 * (state.v[s.node_a] + state.v[s.node_b]);
    const double vt = v.dot(t);
    const Vector3d vn = v - vt * t;
    const double area = s.diameter * length;  // projected area, m^2
    Vector3d f = -(half_rho * area * options_.drag_coefficient * vn.norm()) * vn;
    if (options_.tangential_coefficient > 0.0)
      f -= (half_rho * area * options_.tangential_coefficient * std::abs(vt) * vt) * t;
    out.force[s.node_a] += 0.5 * f;
    out.force[s.node_b] += 0.5 * f;
  }
}

}  // namespace netlab::netsim
