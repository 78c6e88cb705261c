#pragma once
// Bending and torsion at the joints between consecutive segments (paper section 2; CoRdE [9]
// section 4.2), with the relative rotation measured by the logarithm map:
//   phi = Log(q_a^-1 q_b)                                     (rad, material frame)
//   E = 1/2 (1/l) sum_k K_k (phi_k - phi0_k)^2,  K = (EI, EI, GJ), l the mean segment length,
// i.e. the Darboux vector Omega = phi / l with energy density 1/2 K Omega^2. Damping uses the
// rate of phi, dphi/dt = Jr^-1 w_b - Jl^-1 w_a (w body-frame angular velocities), in
// D = 1/2 (1/l) sum_k C_k (dphi_k/dt)^2, C = (c_b, c_b, c_t). With g = (K (phi - phi0) + C
// dphi/dt)/l the body-frame torques are
//   tau_a = Jr^-1^T ... = g + 1/2 phi x g + b phi x (phi x g),
//   tau_b = -(g - 1/2 phi x g + b phi x (phi x g)),
// (rotation.h: LogMap and its Jacobians). A rod under an end moment M therefore turns by exactly
// M l / EI per joint. Clamped ends (Model::anchors) are joints to a fixed frame over half a
// segment.

#include <vector>

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

class BendTwistForce final : public Force {
 public:
  explicit BendTwistForce(const Model& model);
  std::string name() const override { return "bend_twist"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kElastic; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;
  void SetThreads(int threads) override { threads_ = threads < 1 ? 1 : threads; }
  // Under the implicit integrator each segment's frame follows its centreline within the step
  // (the coupling's torque is implicit), so a joint's bending stiffness acts on the three nodes of
  // its two segments: AddStiffnessBounds then adds that node stiffness too.
  void SetFramesFollowCentreline(bool follow) { frames_follow_ = follow; }

 private:
  void AccumulateThreaded(const Model& model, const State& state, ForceBuffers& out) const;

  bool frames_follow_ = false;
  bool damped_ = false;  // any joint with non-zero damping; if not, the rates are never computed
  int threads_ = 1;
  // With threads: each joint's torques on its two segments, and each segment's joints, built
  // on first use.
  mutable std::vector<Vector3d> on_a_, on_b_;
  mutable Incidence joints_of_;
};

}  // namespace netlab::netsim
