#pragma once
// Stretching of every segment (paper eq. 1, CoRdE [9] section 4.1), linear in the axial strain:
//   epsilon = |x_b - x_a| / l - 1,          E = 1/2 EA l epsilon^2,
//   depsilon/dt = t . (v_b - v_a) / l,      D = 1/2 c_s l (depsilon/dt)^2,
// giving the axial force N = EA epsilon + c_s depsilon/dt along t = (x_b - x_a)/|x_b - x_a|.

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

class StretchForce final : public Force {
 public:
  std::string name() const override { return "stretch"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kElastic; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;
};

}  // namespace netlab::netsim
