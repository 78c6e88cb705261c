#include "libnetsim/forces/segment_force.h"

#include <cmath>

#include "libnetsim/model/rotation.h"

namespace netlab::netsim {

void SegmentForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                              ForceBuffers& out) const {
  const Vector3d* x = state.x.data();
  const Vector3d* v = state.v.data();
  const Quaterniond* q = state.q.data();
  Vector3d* f = out.force.data();
  Vector3d* tau = out.torque.data();
  const double stretch_on = stretch_ ? 1.0 : 0.0;
  const double coupling_on = coupling_ ? 1.0 : 0.0;
  const int n = model.num_segments();
  for (int j = 0; j < n; ++j) {
    // Plain scalars: this loop runs once per segment and step, and Eigen temporaries here cost
    // store-forwarding stalls.
    const Segment& s = model.segments[j];
    const double* xa = x[s.node_a].data();
    const double* xb = x[s.node_b].data();
    const double ex = xb[0] - xa[0], ey = xb[1] - xa[1], ez = xb[2] - xa[2];
    const double length = std::sqrt(ex * ex + ey * ey + ez * ez);
    const double inv_length = 1.0 / length;
    const double tx = ex * inv_length, ty = ey * inv_length, tz = ez * inv_length;

    // Stretching: axial force N along t, positive in tension.
    const double inv_l = s.inv_rest_length;
    double axial = s.stretch_stiffness * (length * inv_l - 1.0);
    if (s.stretch_damping != 0.0) {
      const double* va = v[s.node_a].data();
      const double* vb = v[s.node_b].data();
      axial += s.stretch_damping * inv_l *
               (tx * (vb[0] - va[0]) + ty * (vb[1] - va[1]) + tz * (vb[2] - va[2]));
    }
    axial *= stretch_on;

    // Coupling: transverse force k (d3 - (t . d3) t) on b.
    const double* c = q[j].coeffs().data();  // x, y, z, w
    const double qx = c[0], qy = c[1], qz = c[2], qw = c[3];
    const double dx = 2.0 * (qx * qz + qw * qy), dy = 2.0 * (qy * qz - qw * qx),
                 dz = 1.0 - 2.0 * (qx * qx + qy * qy);
    const double kl = coupling_on * s.coupling_stiffness * s.rest_length;
    const double td = tx * dx + ty * dy + tz * dz;
    const double k = kl * inv_length;
    // Force on b: coupling minus the axial pull (the axial force pulls b towards a).
    const double along = -k * td - axial;
    const double fx = k * dx + along * tx, fy = k * dy + along * ty, fz = k * dz + along * tz;
    double* fb = f[s.node_b].data();
    double* fa = f[s.node_a].data();
    fb[0] += fx;
    fb[1] += fy;
    fb[2] += fz;
    fa[0] -= fx;
    fa[1] -= fy;
    fa[2] -= fz;
    if (drag_)
      AddSegmentDrag(*drag_, s.diameter, length, tx, ty, tz, v[s.node_a].data(),
                     v[s.node_b].data(), fa, fb);

    // Body torque kappa l e_z x t_body; t_body = R^T t needs only the frame's d1 and d2.
    const double d1x = 1.0 - 2.0 * (qy * qy + qz * qz), d1y = 2.0 * (qx * qy + qw * qz),
                 d1z = 2.0 * (qx * qz - qw * qy);
    const double d2x = 2.0 * (qx * qy - qw * qz), d2y = 1.0 - 2.0 * (qx * qx + qz * qz),
                 d2z = 2.0 * (qy * qz + qw * qx);
    const double tb_x = d1x * tx + d1y * ty + d1z * tz;
    const double tb_y = d2x * tx + d2y * ty + d2z * tz;
    double* torque = tau[j].data();
    torque[0] -= kl * tb_y;
    torque[1] += kl * tb_x;
  }
}

double SegmentForce::Energy(const Model& model, const State& state) const {
  double energy = 0.0;
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    const Vector3d e = state.x[s.node_b] - state.x[s.node_a];
    const double length = e.norm();
    const double strain = length / s.rest_length - 1.0;
    if (stretch_) energy += 0.5 * s.stretch_stiffness * s.rest_length * strain * strain;
    if (coupling_)
      energy += s.coupling_stiffness * s.rest_length *
                (1.0 - (e / length).dot(Director3(state.q[j])));
  }
  return energy;
}

void SegmentForce::AddStiffnessBounds(const Model& model, const State& state,
                                      StiffnessBounds& bounds) const {
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    if (stretch_) {
      // Axial stiffness EA/l, plus the geometric (string) stiffness |N|/|e| of the current
      // tension, each counted for the node itself and its neighbour.
      const double length = (state.x[s.node_b] - state.x[s.node_a]).norm();
      const double tension = std::abs(s.stretch_stiffness * (length / s.rest_length - 1.0));
      const double k = 2.0 * (s.stretch_stiffness / s.rest_length + tension / length);
      const double c = 2.0 * s.stretch_damping / s.rest_length;
      bounds.node_stiffness[s.node_a] += k;
      bounds.node_stiffness[s.node_b] += k;
      bounds.node_damping[s.node_a] += c;
      bounds.node_damping[s.node_b] += c;
    }
    if (coupling_) {
      // Linearised coupling: E = 1/2 kappa l |u/l - psi|^2 (u transverse displacement of b
      // against a, psi the rotation). With psi measured as the displacement l psi every entry is
      // kappa/l: row sums 3 kappa/l for each node and for the rotation (3 kappa l in N m/rad).
      const double k = 3.0 * s.coupling_stiffness / s.rest_length;
      bounds.node_stiffness[s.node_a] += k;
      bounds.node_stiffness[s.node_b] += k;
      bounds.segment_stiffness[j] += 3.0 * s.coupling_stiffness * s.rest_length;
    }
  }
}

}  // namespace netlab::netsim
