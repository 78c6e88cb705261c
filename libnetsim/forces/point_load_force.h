#pragma once
// Point forces at nodes (N, simulation frame) and point moments on segments (N m, simulation
// frame), constant in time and direction (dead loads). A moment "at a node" acts on the segment
// that ends there (a rod's end segment at its end node). Potential energy of the forces: -F . x;
// the moments have none reported (a dead moment in 3D has no single-valued potential).

#include <vector>

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

struct PointLoad {
  enum class Kind { kForce, kMoment };
  Kind kind = Kind::kForce;
  int index = 0;                       // node for a force, segment for a moment
  Vector3d vector = Vector3d::Zero();  // N or N m, simulation frame
};

class PointLoadForce final : public Force {
 public:
  explicit PointLoadForce(std::vector<PointLoad> loads) : loads_(std::move(loads)) {}
  std::string name() const override { return "point_loads"; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kPotential; }
  double Energy(const Model& model, const State& state) const override;

 private:
  std::vector<PointLoad> loads_;
};

}  // namespace netlab::netsim
