#include "libnetsim/forces/rotating_frame_force.h"

namespace netlab::netsim {

void RotatingFrameForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                                    ForceBuffers& out) const {
  const Vector3d omega = Omega(state.time);
  const Vector3d omega_rate = OmegaRate(state.time);
  const double wx = omega.x(), wy = omega.y(), wz = omega.z();
  const double ax = omega_rate.x(), ay = omega_rate.y(), az = omega_rate.z();
  const double w2 = wx * wx + wy * wy + wz * wz;
  for (int i = 0; i < model.num_nodes(); ++i) {
    // a = 2 w x v + w x (w x x) + dw/dt x x, with w x (w x x) = w (w . x) - x |w|^2.
    const double* x = state.x[i].data();
    const double* v = state.v[i].data();
    const double wdx = wx * x[0] + wy * x[1] + wz * x[2];
    const double a0 =
        2.0 * (wy * v[2] - wz * v[1]) + wx * wdx - x[0] * w2 + (ay * x[2] - az * x[1]);
    const double a1 =
        2.0 * (wz * v[0] - wx * v[2]) + wy * wdx - x[1] * w2 + (az * x[0] - ax * x[2]);
    const double a2 =
        2.0 * (wx * v[1] - wy * v[0]) + wz * wdx - x[2] * w2 + (ax * x[1] - ay * x[0]);
    const double m = model.node_mass[i];
    double* f = out.force[i].data();
    f[0] -= m * a0;
    f[1] -= m * a1;
    f[2] -= m * a2;
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
