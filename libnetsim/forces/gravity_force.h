#pragma once
// Gravity on every node: F = m g(t). g is constant or a measured time series (accelerometer).
// A time series gives the apparent gravity in the simulation frame at its origin, m/s^2: minus the
// specific force an accelerometer fixed to the rig reads (level flight: (0, 0, -9.81) with z up).
// Potential energy -sum m g(t) . x, with g at the state's time.

#include <optional>

#include "libnetsim/forces/force.h"
#include "libnetsim/model/time_series.h"

namespace netlab::netsim {

class GravityForce final : public Force {
 public:
  explicit GravityForce(const Vector3d& g) : constant_(g) {}
  explicit GravityForce(TimeSeries3 series) : series_(std::move(series)) {}

  std::string name() const override { return series_ ? "gravity(series)" : "gravity"; }
  Vector3d At(double t) const { return series_ ? series_->Value(t) : constant_; }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kPotential; }
  double Energy(const Model& model, const State& state) const override;

 private:
  Vector3d constant_ = Vector3d::Zero();
  std::optional<TimeSeries3> series_;
};

}  // namespace netlab::netsim
