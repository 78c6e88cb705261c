#pragma once
// The penalty that couples each segment's orientation to its centreline (CoRdE [9] section 4.3):
//   E = 1/2 kappa l |t - d3|^2 = kappa l (1 - t . d3),   t = (x_b - x_a)/|x_b - x_a|, d3 = q e_z.
// It accelerates d3 towards the tangent and the tangent towards d3 (paper section 2: "chains
// loosely coupled by penalty forces"). Derivatives, with |e| the current segment length:
//   force on x_b   F =  kappa l (d3 - (t . d3) t) / |e|,   on x_a  -F,
//   torque (world) kappa l d3 x t,   in the body frame kappa l e_z x (q^-1 t).
// The node forces and the torque balance exactly: the pair F, -F has moment -kappa l d3 x t.
// kappa acts as a shear stiffness (N): a transverse force V leaves a shear angle V / kappa. It is
// chosen per segment by ModelBuilderOptions::coupling_stiffness_ratio.

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

class CouplingForce final : public Force {
 public:
  std::string name() const override { return "coupling"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kElastic; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;
};

}  // namespace netlab::netsim
