#include "libnetsim/forces/segment_force.h"

#include <cmath>
#include <utility>

#include "libnetsim/model/rotation.h"

namespace netlab::netsim {

SegmentForce::Terms SegmentForce::SegmentTerms(const Model& model, const State& state,
                                               int j) const {
  // Plain scalars: this runs once per segment and step, and Eigen temporaries here cost
  // store-forwarding stalls.
  const Segment& s = model.segments[j];
  const double* xa = state.x[s.node_a].data();
  const double* xb = state.x[s.node_b].data();
  const double ex = xb[0] - xa[0], ey = xb[1] - xa[1], ez = xb[2] - xa[2];
  const double length = std::sqrt(ex * ex + ey * ey + ez * ez);
  const double inv_length = 1.0 / length;
  const double tx = ex * inv_length, ty = ey * inv_length, tz = ez * inv_length;

  // Stretching: axial force N along t, positive in tension.
  const double inv_l = s.inv_rest_length;
  double axial = s.stretch_stiffness * (length * inv_l - 1.0);
  if (s.stretch_damping != 0.0) {
    const double* va = state.v[s.node_a].data();
    const double* vb = state.v[s.node_b].data();
    axial += s.stretch_damping * inv_l *
             (tx * (vb[0] - va[0]) + ty * (vb[1] - va[1]) + tz * (vb[2] - va[2]));
  }
  axial *= stretch_ && !implicit_ ? 1.0 : 0.0;

  // Coupling: transverse force k (d3 - (t . d3) t) on b.
  const double* c = state.q[j].coeffs().data();  // x, y, z, w
  const double qx = c[0], qy = c[1], qz = c[2], qw = c[3];
  const double dx = 2.0 * (qx * qz + qw * qy), dy = 2.0 * (qy * qz - qw * qx),
               dz = 1.0 - 2.0 * (qx * qx + qy * qy);
  const double kl = (coupling_ ? 1.0 : 0.0) * s.coupling_stiffness * s.rest_length;
  const double td = tx * dx + ty * dy + tz * dz;
  const double k = kl * inv_length;
  // Force on b: coupling minus the axial pull (the axial force pulls b towards a).
  const double along = -k * td - axial;
  Terms terms{{k * dx + along * tx, k * dy + along * ty, k * dz + along * tz}, {0, 0, 0}, {0, 0}};
  if (drag_) {
    double on_b[3] = {0, 0, 0};
    AddSegmentDrag(*drag_, s.diameter, length, tx, ty, tz, state.v[s.node_a].data(),
                   state.v[s.node_b].data(), terms.drag, on_b);
  }

  // Body torque kappa l e_z x t_body; t_body = R^T t needs only the frame's d1 and d2.
  const double d1x = 1.0 - 2.0 * (qy * qy + qz * qz), d1y = 2.0 * (qx * qy + qw * qz),
               d1z = 2.0 * (qx * qz - qw * qy);
  const double d2x = 2.0 * (qx * qy - qw * qz), d2y = 1.0 - 2.0 * (qx * qx + qz * qz),
               d2z = 2.0 * (qy * qz + qw * qx);
  const double klt = implicit_frames_ ? 0.0 : kl;            // the implicit stepper turns the frame
  terms.torque[0] = klt * (d2x * tx + d2y * ty + d2z * tz);  // subtracted from torque x
  terms.torque[1] = klt * (d1x * tx + d1y * ty + d1z * tz);  // added to torque y
  return terms;
}

void SegmentForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                              ForceBuffers& out) const {
  if (threads_ > 1) {
    AccumulateThreaded(model, state, out);
    return;
  }
  Vector3d* f = out.force.data();
  Vector3d* tau = out.torque.data();
  const int n = model.num_segments();
  for (int j = 0; j < n; ++j) {
    const Terms t = SegmentTerms(model, state, j);
    const Segment& s = model.segments[j];
    double* fb = f[s.node_b].data();
    double* fa = f[s.node_a].data();
    for (int i = 0; i < 3; ++i) {
      fb[i] += t.f[i];
      fa[i] -= t.f[i];
    }
    if (drag_)
      for (int i = 0; i < 3; ++i) {
        fa[i] += t.drag[i];
        fb[i] += t.drag[i];
      }
    double* torque = tau[j].data();
    torque[0] -= t.torque[0];
    torque[1] += t.torque[1];
  }
}

void SegmentForce::AccumulateThreaded(const Model& model, const State& state,
                                      ForceBuffers& out) const {
  const int n = model.num_segments(), nodes = model.num_nodes();
  if (segments_of_.start.size() != static_cast<size_t>(nodes) + 1) {
    segments_of_ = Incidence(nodes, n, [&](int j) {
      return std::pair(model.segments[j].node_a, model.segments[j].node_b);
    });
    terms_.resize(n);
  }
  Vector3d* f = out.force.data();
  Vector3d* tau = out.torque.data();
  const bool drag = drag_.has_value();
#pragma omp parallel num_threads(threads_)
  {
#pragma omp for schedule(static)
    for (int j = 0; j < n; ++j) {
      terms_[j] = SegmentTerms(model, state, j);
      double* torque = tau[j].data();  // only segment j's own
      torque[0] -= terms_[j].torque[0];
      torque[1] += terms_[j].torque[1];
    }
    // Each node's sum in the one thread's order: by segment, its force then its drag.
#pragma omp for schedule(static)
    for (int i = 0; i < nodes; ++i) {
      double* fi = f[i].data();
      for (int e = segments_of_.start[i]; e < segments_of_.start[i + 1]; ++e) {
        const Terms& t = terms_[segments_of_.entries[e] / 2];
        const bool is_b = segments_of_.entries[e] % 2 == 1;
        for (int k = 0; k < 3; ++k) fi[k] = is_b ? fi[k] + t.f[k] : fi[k] - t.f[k];
        if (drag)
          for (int k = 0; k < 3; ++k) fi[k] += t.drag[k];
      }
    }
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
      energy +=
          s.coupling_stiffness * s.rest_length * (1.0 - (e / length).dot(Director3(state.q[j])));
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
      const double axial = implicit_ ? 0.0 : 1.0;
      const double k = 2.0 * (axial * s.stretch_stiffness / s.rest_length + tension / length);
      const double c = 2.0 * axial * s.stretch_damping / s.rest_length;
      bounds.node_stiffness[s.node_a] += k;
      bounds.node_stiffness[s.node_b] += k;
      bounds.node_damping[s.node_a] += c;
      bounds.node_damping[s.node_b] += c;
    }
    if (coupling_ && !implicit_frames_) {
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
