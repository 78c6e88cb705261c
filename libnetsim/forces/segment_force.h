#pragma once
// The forces that live on each segment, evaluated in one pass because they share the segment's
// geometry (t, |e|), its velocities and its node forces: the two energies of CoRdE [9] (sections
// 4.1 and 4.3) and, when the scene has air, the drag of drag_force.h.
//
// Stretching, linear in the axial strain (paper section 2):
//   epsilon = |x_b - x_a| / l - 1,          E_s = 1/2 EA l epsilon^2,
//   depsilon/dt = t . (v_b - v_a) / l,      D_s = 1/2 c_s l (depsilon/dt)^2,
// giving the axial force N = EA epsilon + c_s depsilon/dt along t = (x_b - x_a)/|x_b - x_a|.
//
// Coupling: the penalty that ties the segment's orientation to its centreline (paper section 2:
// "chains loosely coupled by penalty forces"), with d3 = q e_z:
//   E_c = 1/2 kappa l |t - d3|^2 = kappa l (1 - t . d3),
//   force on x_b  F = kappa l (d3 - (t . d3) t) / |e|,   on x_a  -F,
//   torque        kappa l d3 x t (world),   kappa l e_z x (q^-1 t) (body frame).
// The pair F, -F has moment -kappa l d3 x t, so the coupling exerts no net moment. kappa acts as
// a shear stiffness (N): a transverse force V leaves a shear angle V / kappa. It is chosen per
// segment by ModelBuilderOptions::coupling_stiffness_ratio.

#include <array>
#include <optional>
#include <vector>

#include "libnetsim/forces/drag_force.h"
#include "libnetsim/forces/force.h"

namespace netlab::netsim {

class SegmentForce final : public Force {
 public:
  // Which of the two energies to include (tests check each alone), and the air drag if any.
  explicit SegmentForce(bool stretch = true, bool coupling = true,
                        std::optional<DragOptions> drag = std::nullopt)
      : stretch_(stretch), coupling_(coupling), drag_(drag) {}

  std::string name() const override { return drag_ ? "stretch+coupling+drag" : "stretch+coupling"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kElastic; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;
  void SetThreads(int threads) override { threads_ = threads < 1 ? 1 : threads; }

  // Which energies this force includes.
  bool stretch() const { return stretch_; }
  bool coupling() const { return coupling_; }
  // Under the implicit integrator the stepper solves the axial force (EA epsilon + c_s
  // depsilon/dt along t; simulation/axial_step.h) and, with `frames`, the coupling's torque
  // (against the centreline at the end of the step) itself: Accumulate leaves those out, keeping
  // the coupling's node forces, and AddStiffnessBounds leaves their bounds out (the axial ones
  // but the geometric stiffness of the tension; with frames, the coupling's).
  void SetImplicit(bool axial, bool frames) {
    implicit_ = axial;
    implicit_frames_ = frames;
  }

  // One segment's terms: the force on node b (on a: minus it), the drag on each node, the body
  // torque's x and y.
  struct Terms {
    double f[3];
    double drag[3];
    double torque[2];
  };

 private:
  Terms SegmentTerms(const Model& model, const State& state, int j) const;
  void AccumulateThreaded(const Model& model, const State& state, ForceBuffers& out) const;

  bool stretch_;
  bool coupling_;
  bool implicit_ = false;
  bool implicit_frames_ = false;
  std::optional<DragOptions> drag_;
  int threads_ = 1;
  // With threads: each segment's terms, and each node's segments, built on first use.
  mutable std::vector<Terms> terms_;
  mutable Incidence segments_of_;
};

}  // namespace netlab::netsim
