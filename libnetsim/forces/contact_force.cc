#include "libnetsim/forces/contact_force.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace netlab::netsim {

double RigidBody::SignedDistance(const Vector3d& p, double t, Vector3d* normal_out) const {
  const Vector3d c = center + t * velocity;
  switch (shape) {
    case Shape::kSphere: {
      const Vector3d d = p - c;
      const double r = d.norm();
      *normal_out = r > 0.0 ? Vector3d(d / r) : Vector3d::UnitZ();
      return r - radius;
    }
    case Shape::kPlane: *normal_out = normal; return normal.dot(p - c);
    case Shape::kBox: {
      const Vector3d local = orientation.conjugate() * (p - c);
      const Vector3d d = local.cwiseAbs() - half_extents;
      const Vector3d outside = d.cwiseMax(0.0);
      const double outside_norm = outside.norm();
      Vector3d n_local;
      double dist;
      if (outside_norm > 0.0) {
        n_local = outside.cwiseProduct(local.cwiseSign()) / outside_norm;
        dist = outside_norm;
      } else {
        int axis;
        dist = d.maxCoeff(&axis);
        n_local = Vector3d::Zero();
        n_local[axis] = local[axis] >= 0.0 ? 1.0 : -1.0;
      }
      *normal_out = orientation * n_local;
      return dist;
    }
  }
  return 0.0;
}

double RigidBody::BoundingRadius() const {
  switch (shape) {
    case Shape::kSphere: return radius;
    case Shape::kBox: return half_extents.norm();
    case Shape::kPlane: return std::numeric_limits<double>::infinity();
  }
  return std::numeric_limits<double>::infinity();
}

bool RigidBody::IsValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (!center.allFinite() || !velocity.allFinite())
    return fail("center and velocity must be finite");
  if (shape == Shape::kSphere && !(radius > 0.0)) return fail("radius must be > 0");
  if (shape == Shape::kBox && !(half_extents.minCoeff() > 0.0)) return fail("size must be > 0");
  if (shape == Shape::kPlane && !(std::abs(normal.norm() - 1.0) < 1e-9))
    return fail("normal must be a unit vector");
  if (!(friction >= 0.0)) return fail("friction must be >= 0");
  if (!(stiffness >= 0.0)) return fail("stiffness must be >= 0");
  if (!(damping_ratio >= 0.0)) return fail("damping_ratio must be >= 0");
  return true;
}

ContactForce::ContactForce(std::vector<RigidBody> bodies, double friction_velocity)
    : bodies_(std::move(bodies)), friction_velocity_(friction_velocity) {
  for (const RigidBody& body : bodies_) bounding_radius_.push_back(body.BoundingRadius());
}

double ContactForce::Friction(const RigidBody& body, double fn, double speed, double mass,
                              double dt) const {
  const double ft = body.friction * fn * speed /
                    std::sqrt(speed * speed + friction_velocity_ * friction_velocity_);
  return dt > 0.0 ? std::min(ft, mass * speed / dt) : ft;
}

void ContactForce::Accumulate(const Model& model, const State& state, double dt,
                              ForceBuffers& out) const {
  const int n = model.num_nodes();
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const RigidBody& body = bodies_[b];
    // Broad phase: a node farther from the centre than the bounding radius plus its own radius
    // cannot touch; skipped without a square root.
    const Vector3d center = body.center + state.time * body.velocity;
    for (int i = 0; i < n; ++i) {
      if (model.node_inv_mass[i] == 0.0) continue;  // pinned nodes do not take contact forces
      if (Beyond(b, center, state.x[i], model.node_radius[i])) continue;
      Vector3d normal;
      const double depth =
          model.node_radius[i] - body.SignedDistance(state.x[i], state.time, &normal);
      if (depth <= 0.0) continue;
      if (depth > out.max_penetration) {
        out.max_penetration = depth;
        out.max_penetration_node = i;
      }
      const double m = model.node_mass[i];
      const double k = Stiffness(body, m);
      const double c = 2.0 * body.damping_ratio * std::sqrt(k * m);
      const Vector3d v_rel = state.v[i] - body.velocity;
      const double vn = v_rel.dot(normal);
      const double fn = k * depth - c * vn;
      if (fn <= 0.0) continue;
      Vector3d f = fn * normal;
      if (body.friction > 0.0) {
        const Vector3d vt = v_rel - vn * normal;
        const double speed = vt.norm();
        if (speed > 0.0) f -= (Friction(body, fn, speed, m, dt) / speed) * vt;
      }
      out.force[i] += f;
    }
  }
}

double ContactForce::Energy(const Model& model, const State& state) const {
  double energy = 0.0;
  for (const RigidBody& body : bodies_) {
    for (int i = 0; i < model.num_nodes(); ++i) {
      Vector3d normal;
      const double depth =
          model.node_radius[i] - body.SignedDistance(state.x[i], state.time, &normal);
      if (depth > 0.0) energy += 0.5 * Stiffness(body, model.node_mass[i]) * depth * depth;
    }
  }
  return energy;
}

void ContactForce::AddStiffnessBounds(const Model& model, const State& /*state*/,
                                      StiffnessBounds& bounds) const {
  for (const RigidBody& body : bodies_) {
    for (int i = 0; i < model.num_nodes(); ++i) {
      const double m = model.node_mass[i];
      const double k = Stiffness(body, m);
      bounds.node_stiffness[i] += k;
      bounds.node_damping[i] += 2.0 * body.damping_ratio * std::sqrt(k * m);
    }
  }
}

double ContactForce::NearContactFrequency(const Model& model, const State& state,
                                          double horizon) const {
  double omega2 = 0.0;
  const int n = model.num_nodes();
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const RigidBody& body = bodies_[b];
    const Vector3d center = body.center + state.time * body.velocity;
    for (int i = 0; i < n; ++i) {
      if (model.node_inv_mass[i] == 0.0) continue;
      const double travel = (state.v[i] - body.velocity).norm() * horizon;
      if (Beyond(b, center, state.x[i], model.node_radius[i] + travel)) continue;
      Vector3d normal;
      const double gap =
          body.SignedDistance(state.x[i], state.time, &normal) - model.node_radius[i];
      if (gap > travel + model.node_radius[i]) continue;
      omega2 = std::max(omega2, Stiffness(body, model.node_mass[i]) * model.node_inv_mass[i]);
    }
  }
  return std::sqrt(omega2);
}

double ContactForce::ResolveImplicit(const Model& model, int i, const Vector3d& x, double t,
                                     double h, Vector3d* v) const {
  double deepest = 0.0;
  const double m = model.node_mass[i];
  const double r = model.node_radius[i];
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const RigidBody& body = bodies_[b];
    const Vector3d v_rel = *v - body.velocity;
    const double travel = v_rel.norm() * h;
    if (Beyond(b, body.center + t * body.velocity, x, r + travel)) continue;
    Vector3d normal;
    const double depth = r - body.SignedDistance(x, t, &normal);
    if (depth + travel <= 0.0) continue;  // cannot reach the body within the step
    const double k = Stiffness(body, m);
    const double c = 2.0 * body.damping_ratio * std::sqrt(k * m);
    const double vn = v_rel.dot(normal);
    const double a = h / m;
    const double vn_end = (vn + a * k * depth) / (1.0 + a * (h * k + c));
    const double fn = k * (depth - h * vn_end) - c * vn_end;
    deepest = std::max(deepest, depth);
    if (fn <= 0.0) continue;
    deepest = std::max(deepest, depth - h * vn_end);
    *v += (vn_end - vn) * normal;
    if (body.friction > 0.0) {
      const Vector3d vt = v_rel - vn * normal;
      const double speed = vt.norm();
      if (speed > 0.0) *v -= (a * Friction(body, fn, speed, m, h) / speed) * vt;
    }
  }
  return deepest;
}

}  // namespace netlab::netsim
