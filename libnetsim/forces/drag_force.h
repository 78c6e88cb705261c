#pragma once
// Quadratic air drag on threads, by the cross-flow principle: each segment sees the air velocity
// relative to its midpoint, split into the normal part v_n and the tangential part v_t,
//   F = -1/2 rho d l (C_n |v_n| v_n + C_t |v_t| v_t),
// half to each end node (rho air density kg/m^3, d thread diameter, l current segment length,
// C_n the drag coefficient of a cylinder in cross flow, ~1.2 for the Reynolds numbers of a 1 mm
// thread at 0.1-3 m/s; C_t the skin-friction coefficient along the thread, default 0).
// The air is at rest in the simulation frame (the aircraft cabin).

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

struct DragOptions {
  double air_density = 1.2;           // kg/m^3
  double drag_coefficient = 1.2;      // C_n, normal to the thread
  double tangential_coefficient = 0;  // C_t, along the thread
  bool IsValid(std::string* error) const;
};

class DragForce final : public Force {
 public:
  explicit DragForce(const DragOptions& options) : options_(options) {}
  std::string name() const override { return "drag"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;

 private:
  DragOptions options_;
};

}  // namespace netlab::netsim
