#pragma once
// Quadratic air drag on threads, by the cross-flow principle: each segment sees the air velocity
// relative to its midpoint, split into the normal part v_n and the tangential part v_t,
//   F = -1/2 rho d l (C_n |v_n| v_n + C_t |v_t| v_t),
// half to each end node (rho air density kg/m^3, d thread diameter, l current segment length,
// C_n the drag coefficient of a cylinder in cross flow, ~1.2 for the Reynolds numbers of a 1 mm
// thread at 0.1-3 m/s; C_t the skin-friction coefficient along the thread, default 0).
// The air is at rest in the simulation frame (the aircraft cabin).

#include <cmath>

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

struct DragOptions {
  double air_density = 1.2;           // kg/m^3
  double drag_coefficient = 1.2;      // C_n, normal to the thread
  double tangential_coefficient = 0;  // C_t, along the thread
  bool IsValid(std::string* error) const;
};

// Drag of one segment with unit tangent (tx, ty, tz), current length `length` and end velocities
// va, vb: adds half of F to fa and half to fb. The kernel shared by DragForce and SegmentForce
// (which evaluates it in its own pass over the segments, where t and |e| are already known).
inline void AddSegmentDrag(const DragOptions& o, double diameter, double length, double tx,
                           double ty, double tz, const double* va, const double* vb, double* fa,
                           double* fb) {
  const double ux = 0.5 * (va[0] + vb[0]), uy = 0.5 * (va[1] + vb[1]), uz = 0.5 * (va[2] + vb[2]);
  const double vt = ux * tx + uy * ty + uz * tz;
  const double nx = ux - vt * tx, ny = uy - vt * ty, nz = uz - vt * tz;
  const double k = 0.25 * o.air_density * diameter * length;  // half of 1/2 rho d l per node
  const double kn = k * o.drag_coefficient * std::sqrt(nx * nx + ny * ny + nz * nz);
  const double kt = k * o.tangential_coefficient * std::abs(vt) * vt;
  const double fx = -(kn * nx + kt * tx), fy = -(kn * ny + kt * ty), fz = -(kn * nz + kt * tz);
  fa[0] += fx;
  fa[1] += fy;
  fa[2] += fz;
  fb[0] += fx;
  fb[1] += fy;
  fb[2] += fz;
}

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
