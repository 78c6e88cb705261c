#include "libnetsim/forces/rotating_frame_force.h"

namespace netlab::netsim {

void RotatingFrameForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                                    ForceBuffers& out) const {
  const Vector3d omega = Omega(state.time);
  const Vector3d omega_rate = OmegaRate(state.time);
  for (int i = 0; i < model.num_nodes(); ++i) {
    const Vector3d& x = state.x[i];
    const Vector3d a = 2.0 * omega.cross(state.v[i]) + omega.cross(omega.cross(x)) +
                       omega_rate.cross(x);
    out.force[i] -= model.node_mass[i] * a;
  }
}

double RotatingFrameForce::Energy(const Model& model, const State& state) const {
  const Vector3d omega = Omega(state.time);
  double energy = 0.0;
  for (int i = 0; i < model.num_nodes(); ++i)
    energy -= 0.5 * model.node_mass[i] * omega.cross(state.x[i]).squaredNorm();
  return energy;
}

void RotatingFrameForce::AddStiffnessBounds(const Model& model, const State& /*state*/,
                                            StiffnessBounds& bounds) const {
  // Centrifugal stiffness m |Omega|^2 and Coriolis "damping" 2 m |Omega| (tiny for an aircraft).
  double omega_max = constant_.norm();
  if (series_) {
    for (double t = series_->first_time(); t <= series_->last_time();
         t += (series_->last_time() - series_->first_time()) / 64.0 + 1e-12)
      omega_max = std::max(omega_max, series_->Value(t).norm());
  }
  for (int i = 0; i < model.num_nodes(); ++i) {
    bounds.node_stiffness[i] += model.node_mass[i] * omega_max * omega_max;
    bounds.node_damping[i] += 2.0 * model.node_mass[i] * omega_max;
  }
}

}  // namespace netlab::netsim
