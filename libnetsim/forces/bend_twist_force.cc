#include "libnetsim/forces/bend_twist_force.h"

#include "libnetsim/rotation.h"

namespace netlab::netsim {

BendTwistForce::BendTwistForce(const Model& model) {
  for (const BendPair& p : model.bend_pairs)
    if (p.damping.squaredNorm() > 0.0) damped_ = true;
  for (const AnchorJoint& a : model.anchors)
    if (a.damping.squaredNorm() > 0.0) damped_ = true;
}

void BendTwistForce::Accumulate(const Model& model, const State& state, double /*dt*/,
                                ForceBuffers& out) const {
  const Quaterniond* q = state.q.data();
  const Vector3d* w = state.w.data();
  Vector3d* tau = out.torque.data();
  for (const BendPair& p : model.bend_pairs) {
    const LogResult log = LogMap(q[p.segment_a].conjugate() * q[p.segment_b]);
    Vector3d g = p.stiffness.cwiseProduct(log.phi - p.rest_phi);
    if (damped_) {
      const Vector3d rate = ApplyJrInv(log, w[p.segment_b]) - ApplyJlInv(log, w[p.segment_a]);
      g += p.damping.cwiseProduct(rate);
    }
    g *= p.inv_length;
    // tau_a = Jl^-1^T g = Jr^-1 g;  tau_b = -Jr^-1^T g = -Jl^-1 g.
    tau[p.segment_a] += ApplyJrInv(log, g);
    tau[p.segment_b] -= ApplyJlInv(log, g);
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
}

}  // namespace netlab::netsim
