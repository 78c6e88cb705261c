#pragma once
// Fictitious forces of a simulation frame that rotates with the aircraft (paper section 4.1: the
// plane pitches during a parabola and the net drifts). With Omega(t) the frame's angular velocity
// (gyro, rad/s, in the frame's own axes) about its origin:
//   F = -m (2 Omega x v + Omega x (Omega x x) + dOmega/dt x x)     (Coriolis, centrifugal, Euler).
// The translational acceleration of the origin belongs to the apparent gravity (gravity_force.h).
// Fictitious torques on the segments' cross-section inertia (~ I Omega^2, I ~ 1e-13 kg m^2 for a
// 1 mm thread) are left out. Potential energy: the centrifugal one, -1/2 m |Omega x x|^2.

#include <optional>

#include "libnetsim/forces/force.h"
#include "libnetsim/model/time_series.h"

namespace netlab::netsim {

class RotatingFrameForce final : public Force {
 public:
  explicit RotatingFrameForce(const Vector3d& omega) : constant_(omega) {}
  explicit RotatingFrameForce(TimeSeries3 series) : series_(std::move(series)) {}

  std::string name() const override {
    return series_ ? "rotating_frame(series)" : "rotating_frame";
  }
  Vector3d Omega(double t) const { return series_ ? series_->Value(t) : constant_; }
  Vector3d OmegaRate(double t) const { return series_ ? series_->Rate(t) : Vector3d::Zero(); }
  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kPotential; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;

 private:
  Vector3d constant_ = Vector3d::Zero();
  std::optional<TimeSeries3> series_;
};

}  // namespace netlab::netsim
