#pragma once
// Contact of nodes with rigid targets: spheres, boxes and planes, static or moving at a constant
// velocity. Each node is a sphere of its contact radius (half the thread diameter, or the corner
// mass radius). For a penetration delta > 0 along the body's outward normal n:
//   normal force    F_n = max(0, k delta - c v_n),  c = 2 zeta sqrt(k m)
//   friction        F_t = -mu F_n v_t / sqrt(|v_t|^2 + v_reg^2)          (regularised Coulomb)
// with v the node's velocity relative to the body. The friction force is capped at m |v_t| / dt,
// the force that stops the sliding within one step, so it never reverses the motion (an explicit
// step with a stiffer friction would be unstable).
//
// Penalty stiffness: a body's `stiffness` (N/m) if given, otherwise k = m omega_c^2 per node, with
// omega_c a fraction of the highest frequency of the elastic model (set by the simulation through
// SetContactFrequency). Every node then penetrates at most ~ v / omega_c for an impact speed v,
// whatever its mass, and the contact never lowers the stable time step by more than the fraction.

#include <cmath>
#include <string>
#include <vector>

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

struct RigidBody {
  enum class Shape { kSphere, kBox, kPlane };
  std::string name;
  Shape shape = Shape::kSphere;
  Vector3d center = Vector3d::Zero();        // m at t = 0: sphere or box centre, a point of a plane
  Vector3d velocity = Vector3d::Zero();      // m/s, constant
  double radius = 0.0;                       // sphere, m
  Vector3d half_extents = Vector3d::Zero();  // box, m
  Quaterniond orientation = Quaterniond::Identity();  // box: box axes to simulation frame
  Vector3d normal = Vector3d::UnitZ();                // plane: outward unit normal
  double friction = 0.0;                              // Coulomb coefficient mu
  double stiffness = 0.0;                             // N/m; 0 = automatic (see above)
  double damping_ratio = 0.3;  // zeta of the normal penalty spring (restitution ~0.37)

  // Signed distance (m, negative inside) from point p to the body's surface at time t, and the
  // outward unit normal at the closest surface point.
  double SignedDistance(const Vector3d& p, double t, Vector3d* normal_out) const;
  // Radius of a sphere about `center` that holds the whole body (infinite for a plane).
  double BoundingRadius() const;
  bool IsValid(std::string* error) const;
};

class ContactForce final : public Force {
 public:
  // `friction_velocity` (m/s) is the regularisation v_reg of Coulomb friction.
  explicit ContactForce(std::vector<RigidBody> bodies, double friction_velocity = 1e-3);

  std::string name() const override { return "contact"; }
  void SetContactFrequency(double omega) { contact_omega_ = omega; }  // rad/s
  double contact_frequency() const { return contact_omega_; }
  const std::vector<RigidBody>& bodies() const { return bodies_; }

  void Accumulate(const Model& model, const State& state, double dt,
                  ForceBuffers& out) const override;
  EnergyKind energy_kind() const override { return EnergyKind::kPotential; }
  double Energy(const Model& model, const State& state) const override;
  void AddStiffnessBounds(const Model& model, const State& state,
                          StiffnessBounds& bounds) const override;
  // The highest contact frequency sqrt(k / m) (rad/s) of the nodes that touch a body now or may
  // within `horizon` seconds at their present speed relative to it, with a margin of their own
  // radius (a node resting just above a body must not drop in and out of the check from step to
  // step: that toggling pumped a thread on a rising plane unstable); 0 when none. The implicit
  // integrator's step-by-step check.
  double NearContactFrequency(const Model& model, const State& state, double horizon) const;
  // The contact of node i over one step of length h, taken implicitly (the implicit integrator's,
  // whose step the penalty's frequency would otherwise limit): given the node's position x at
  // time t and its velocity v after the kick of every other force, for each body it may touch
  // within the step, the normal force at the end of the step, linearised about the prediction,
  //   F_n = k (delta - h v+_n) - c v+_n,   v+_n = v_n + (h / m) F_n   (backward Euler),
  // is applied when it pushes (F_n > 0), then the friction of that force, capped as above. Adds
  // the impulses to *v; returns the deepest penetration, now or at the end of the step (m).
  // Without the step's own resolution of the penalty's oscillation, a node lands on a body dead
  // and rests at the same depth F / k.
  double ResolveImplicit(const Model& model, int i, const Vector3d& x, double t, double h,
                         Vector3d* v) const;

 private:
  // Broad phase: true when a point `reach` or more outside body b's bounding sphere (about
  // `center`) cannot touch it; tested without a square root. Never for a plane.
  bool Beyond(size_t b, const Vector3d& center, const Vector3d& x, double reach) const {
    const double r = bounding_radius_[b] + reach;
    return std::isfinite(r) && (x - center).squaredNorm() > r * r;
  }
  // The regularised Coulomb friction's magnitude (N) for a normal force fn and a sliding speed,
  // capped (dt > 0) at what stops the sliding within dt.
  double Friction(const RigidBody& body, double fn, double speed, double mass, double dt) const;
  double Stiffness(const RigidBody& body, double mass) const {
    return body.stiffness > 0.0 ? body.stiffness : mass * contact_omega_ * contact_omega_;
  }

  std::vector<RigidBody> bodies_;
  std::vector<double> bounding_radius_;  // per body, m
  double friction_velocity_;
  double contact_omega_ = 0.0;
};

}  // namespace netlab::netsim
