#include "libnetsim/forces/bend_twist_force.h"

#include <utility>

#include "libnetsim/model/rotation.h"

namespace netlab::netsim {

BendTwistForce::BendTwistForce(const Model& model) {
  for (const BendPair& p : model.bend_pairs)
    if (p.damping.squaredNorm() > 0.0) damped_ = true;
  for (const AnchorJoint& a : model.anchors)
    if (a.damping.squaredNorm() > 0.0) damped_ = true;
}

namespace {

// One joint on plain scalars (the hot loop of the simulator; Eigen temporaries here cost
// store-forwarding stalls). Same formulas as the header: r = qa^-1 qb, phi = Log(r),
// g = (K (phi - phi0) + C dphi/dt) / l, tau_a += Jr^-1 g, tau_b -= Jl^-1 g.
inline void Joint(const Quaterniond& qa, const Quaterniond& qb, const Vector3d& wa,
                  const Vector3d& wb, const BendPair& p, bool damped, Vector3d& tau_a,
                  Vector3d& tau_b) {
  const double* a = qa.coeffs().data();  // x, y, z, w
  const double* b = qb.coeffs().data();
  const double ax = -a[0], ay = -a[1], az = -a[2], aw = a[3];  // conjugate of qa
  const double bx = b[0], by = b[1], bz = b[2], bw = b[3];
  const LogScalars log =
      LogMap(aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
             aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw);
  const double px = log.x, py = log.y, pz = log.z, lb = log.b;
  double gx = p.stiffness.x() * (px - p.rest_phi.x());
  double gy = p.stiffness.y() * (py - p.rest_phi.y());
  double gz = p.stiffness.z() * (pz - p.rest_phi.z());
  if (damped) {
    // dphi/dt = d + 1/2 phi x (wa + wb) + b phi x (phi x d), d = wb - wa.
    const double dx = wb.x() - wa.x(), dy = wb.y() - wa.y(), dz = wb.z() - wa.z();
    const double sx = wb.x() + wa.x(), sy = wb.y() + wa.y(), sz = wb.z() + wa.z();
    const double cx = py * dz - pz * dy, cy = pz * dx - px * dz, cz = px * dy - py * dx;
    const double ex = py * cz - pz * cy, ey = pz * cx - px * cz, ez = px * cy - py * cx;
    gx += p.damping.x() * (dx + 0.5 * (py * sz - pz * sy) + lb * ex);
    gy += p.damping.y() * (dy + 0.5 * (pz * sx - px * sz) + lb * ey);
    gz += p.damping.z() * (dz + 0.5 * (px * sy - py * sx) + lb * ez);
  }
  gx *= p.inv_length;
  gy *= p.inv_length;
  gz *= p.inv_length;
  // c = phi x g, e = phi x c; Jr^-1 g = g + c/2 + b e, Jl^-1 g = g - c/2 + b e.
  const double cx = py * gz - pz * gy, cy = pz * gx - px * gz, cz = px * gy - py * gx;
  const double ex = gx + lb * (py * cz - pz * cy), ey = gy + lb * (pz * cx - px * cz),
               ez = gz + lb * (px * cy - py * cx);
  double* ta = tau_a.data();
  double* tb = tau_b.data();
  ta[0] += ex + 0.5 * cx;
  ta[1] += ey + 0.5 * cy;
  ta[2] += ez + 0.5 * cz;
  tb[0] -= ex - 0.5 * cx;
  tb[1] -= ey - 0.5 * cy;
  tb[2] -= ez - 0.5 * cz;
}

}  // namespace

void BendTwistForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                                ForceBuffers& out) const {
  const Quaterniond* q = state.q.data();
  const Vector3d* w = state.w.data();
  Vector3d* tau = out.torque.data();
  if (threads_ > 1) {
    AccumulateThreaded(model, state, out);
  } else {
    for (const BendPair& p : model.bend_pairs)
      Joint(q[p.segment_a], q[p.segment_b], w[p.segment_a], w[p.segment_b], p, damped_,
            tau[p.segment_a], tau[p.segment_b]);
  }
  // Clamped ends: the same with a fixed first frame.
  for (const AnchorJoint& a : model.anchors) {
    const LogResult log = LogMap(a.frame.conjugate() * q[a.segment]);
    Vector3d g = a.stiffness.cwiseProduct(log.phi);
    if (damped_) g += a.damping.cwiseProduct(ApplyJrInv(log, w[a.segment]));
    g *= a.inv_length;
    tau[a.segment] -= ApplyJlInv(log, g);
  }
}

void BendTwistForce::AccumulateThreaded(const Model& model, const State& state,
                                        ForceBuffers& out) const {
  const int n = static_cast<int>(model.bend_pairs.size()), segments = model.num_segments();
  if (joints_of_.start.size() != static_cast<size_t>(segments) + 1) {
    joints_of_ = Incidence(segments, n, [&](int i) {
      return std::pair(model.bend_pairs[i].segment_a, model.bend_pairs[i].segment_b);
    });
    on_a_.resize(n);
    on_b_.resize(n);
  }
  const Quaterniond* q = state.q.data();
  const Vector3d* w = state.w.data();
  Vector3d* tau = out.torque.data();
#pragma omp parallel num_threads(threads_)
  {
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      const BendPair& p = model.bend_pairs[i];
      // Joint adds to a and subtracts from b: from zero, the terms themselves (negated on b).
      on_a_[i].setZero();
      on_b_[i].setZero();
      Joint(q[p.segment_a], q[p.segment_b], w[p.segment_a], w[p.segment_b], p, damped_, on_a_[i],
            on_b_[i]);
    }
#pragma omp for schedule(static)
    for (int j = 0; j < segments; ++j) {
      double* t = tau[j].data();
      for (int e = joints_of_.start[j]; e < joints_of_.start[j + 1]; ++e) {
        const int joint = joints_of_.entries[e] / 2;
        // On b, Joint's "t -= term" is "t + (0 - term)": the same bits.
        const double* add = joints_of_.entries[e] % 2 ? on_b_[joint].data() : on_a_[joint].data();
        for (int k = 0; k < 3; ++k) t[k] += add[k];
      }
    }
  }
}

double BendTwistForce::Energy(const Model& model, const State& state) const {
  double energy = 0.0;
  for (const BendPair& p : model.bend_pairs) {
    const LogResult log = LogMap(state.q[p.segment_a].conjugate() * state.q[p.segment_b]);
    const Vector3d d = log.phi - p.rest_phi;
    energy += 0.5 * p.inv_length * d.dot(p.stiffness.cwiseProduct(d));
  }
  for (const AnchorJoint& a : model.anchors) {
    const Vector3d phi = LogMap(a.frame.conjugate() * state.q[a.segment]).phi;
    energy += 0.5 * a.inv_length * phi.dot(a.stiffness.cwiseProduct(phi));
  }
  return energy;
}

void BendTwistForce::AddStiffnessBounds(const Model& model, const State& /*state*/,
                                        StiffnessBounds& bounds) const {
  for (const BendPair& p : model.bend_pairs) {
    const double la = model.segments[p.segment_a].rest_length;
    const double lb = model.segments[p.segment_b].rest_length;
    // Rotations scaled by their segment's length: self entry K/l, neighbour entry scaled by la/lb.
    const double k = p.stiffness.maxCoeff() * p.inv_length;
    const double c = p.damping.maxCoeff() * p.inv_length;
    bounds.segment_stiffness[p.segment_a] += k * (1.0 + la / lb);
    bounds.segment_stiffness[p.segment_b] += k * (1.0 + lb / la);
    bounds.segment_damping[p.segment_a] += c * (1.0 + la / lb);
    bounds.segment_damping[p.segment_b] += c * (1.0 + lb / la);
  }
  for (const AnchorJoint& a : model.anchors) {
    bounds.segment_stiffness[a.segment] += a.stiffness.maxCoeff() * a.inv_length;
    bounds.segment_damping[a.segment] += a.damping.maxCoeff() * a.inv_length;
  }
  if (!frames_follow_) return;
  // With frames that follow the centreline, a joint turns by phi = g . u for transverse node
  // displacements u of its three nodes, g = (1/la, -(1/la + 1/lb), 1/lb): the node stiffness
  // K/l g g^T has row sums K/l |g_i| sum|g| (16 EI/l^3 at a node of a uniform rod, as for a
  // discrete beam). An anchor joint over half a segment: g = (-1/l, 1/l) with K 2/l.
  auto add = [&](int node, double k, double c) {
    bounds.node_stiffness[node] += k;
    bounds.node_damping[node] += c;
  };
  for (const BendPair& p : model.bend_pairs) {
    const Segment& sa = model.segments[p.segment_a];
    const Segment& sb = model.segments[p.segment_b];
    const double ga = sa.inv_rest_length, gb = sb.inv_rest_length, gm = ga + gb;
    const double sum = 2.0 * gm;
    const double k = p.stiffness.head<2>().maxCoeff() * p.inv_length * sum;
    const double c = p.damping.head<2>().maxCoeff() * p.inv_length * sum;
    add(sa.node_a, k * ga, c * ga);
    add(sa.node_b, k * gm, c * gm);
    add(sb.node_b, k * gb, c * gb);
  }
  for (const AnchorJoint& a : model.anchors) {
    const Segment& s = model.segments[a.segment];
    const double g = s.inv_rest_length;
    const double k = a.stiffness.head<2>().maxCoeff() * a.inv_length * 2.0 * g * g;
    const double c = a.damping.head<2>().maxCoeff() * a.inv_length * 2.0 * g * g;
    add(s.node_a, k, c);
    add(s.node_b, k, c);
  }
}

}  // namespace netlab::netsim
