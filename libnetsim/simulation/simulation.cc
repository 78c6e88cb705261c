
#include "libnetsim/simulation/simulation.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libnetsim/forces/contact_force.h"
#include "libnetsim/model/rotation.h"

namespace netlab::netsim {

std::string IntegratorName(IntegratorType type) {
  return type == IntegratorType::kVelocityVerlet ? "verlet" : "explicit";
}

bool ParseIntegratorType(const std::string& text, IntegratorType* type) {
  if (text == "explicit" || text == "symplectic_euler") {
    *type = IntegratorType::kSymplecticEuler;
    return true;
  }
  if (text == "verlet") {
    *type = IntegratorType::kVelocityVerlet;
    return true;
  }
  return false;
}

bool SimulationOptions::IsValid(std::string* error) const {
  auto fail = [&](const char* message) {
    if (error) *error = message;
    return false;
  };
  if (!(dt >= 0.0) || !std::isfinite(dt)) return fail("dt must be > 0 or auto");
  if (!(safety > 0.0 && safety <= 1.0)) return fail("safety must be in (0, 1]");
  if (!(align_interval >= 0.0) || !std::isfinite(align_interval))
    return fail("align_interval must be >= 0");
  if (!(contact_frequency_ratio > 0.0 && contact_frequency_ratio <= 1.0))
    return fail("contact_frequency_ratio must be in (0, 1]");
  if (!(max_speed > 0.0)) return fail("max_speed must be > 0");
  if (threads < 1 || threads > 256) return fail("threads must be in 1..256");
  if (kinetic_damping && integrator != IntegratorType::kSymplecticEuler)
    return fail("kinetic_damping needs type explicit (its peak correction is symplectic Euler's)");
  return true;
}

Simulation::Simulation(Model model, State state, std::vector<std::unique_ptr<Force>> forces,
                       const SimulationOptions& options)
    : model_(std::move(model)), state_(std::move(state)), forces_(std::move(forces)),
      options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("integrator: " + error);
  if (state_.x.size() != model_.node_mass.size() || state_.v.size() != state_.x.size() ||
      state_.q.size() != model_.segments.size() || state_.w.size() != state_.q.size())
    throw std::invalid_argument("simulation: state does not match the model's sizes");

  std::vector<const Force*> views;
  ContactForce* contact = nullptr;
  for (const auto& f : forces_) {
    f->SetThreads(options_.threads);
    views.push_back(f.get());
    if (auto* c = dynamic_cast<ContactForce*>(f.get())) contact = c;
  }
  StabilityOptions stability_options;
  stability_options.scale_rotational_inertia = options_.scale_rotational_inertia;
  stability_options.contact_frequency_ratio = options_.contact_frequency_ratio;
  stability_options.fallback_dt = options_.dt;
  stability_ = PrepareStability(model_, state_, views, contact, stability_options);

  if (options_.dt > 0.0) {
    dt_ = options_.dt;
  } else {
    if (!std::isfinite(stability_.dt_limit))
      throw std::invalid_argument(
          "integrator: dt auto needs a model with stiffness or damping; give dt in seconds");
    dt_ = options_.safety * stability_.dt_limit;
    if (options_.align_interval > 0.0) {
      const double steps = std::ceil(options_.align_interval / dt_ - 1e-9);
      dt_ = options_.align_interval / steps;
    }
  }
  for (const Vector3d& inertia : model_.segment_inertia)
    if (inertia.maxCoeff() - inertia.minCoeff() > 1e-12 * inertia.maxCoeff()) gyroscopic_ = true;
  buffers_.Resize(model_.num_nodes(), model_.num_segments());
}

std::vector<std::string> Simulation::active_forces() const {
  std::vector<std::string> names;
  for (const auto& f : forces_) names.push_back(f->name());
  return names;
}

void Simulation::EvaluateForces() {
  buffers_.Zero();
  for (const auto& f : forces_) f->Accumulate(model_, state_, dt_, buffers_);
  if (buffers_.max_penetration > max_penetration_) {
    max_penetration_ = buffers_.max_penetration;
    max_penetration_node_ = buffers_.max_penetration_node;
  }
  forces_current_ = true;
}

bool Simulation::Kick(double h, double drift) {
  const int n = model_.num_nodes();
  const double limit2 = options_.max_speed * options_.max_speed;
  const int s = model_.num_segments();
  // The first bad node and segment (each element on its own: any thread count, the same bits).
  int bad_node = n, bad_segment = s;
  const int threads = options_.threads;
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
#pragma omp for schedule(static) reduction(min : bad_node) nowait
    for (int i = 0; i < n; ++i) {
      Vector3d& v = state_.v[i];
      v += (h * model_.node_inv_mass[i]) * buffers_.force[i];
      // Written so that a NaN fails the comparison.
      if (!(v.squaredNorm() <= limit2) && i < bad_node) bad_node = i;
      state_.x[i] += drift * v;  // symplectic Euler moves the node with its new velocity
    }
#pragma omp for schedule(static) reduction(min : bad_segment)
    for (int j = 0; j < s; ++j) {
      const Vector3d& inv_inertia = model_.segment_inv_inertia[j];
      Vector3d& w = state_.w[j];
      Vector3d torque = buffers_.torque[j];
      if (gyroscopic_) torque -= w.cross(model_.segment_inertia[j].cwiseProduct(w));
      w += h * inv_inertia.cwiseProduct(torque);
      // More than 1 rad per step is no longer a resolved rotation.
      if (!(w.squaredNorm() * dt_ * dt_ <= 1.0) && j < bad_segment) bad_segment = j;
    }
  }
  if (bad_node == n) bad_node = -1;
  if (bad_segment == s) bad_segment = -1;
  if (bad_node < 0 && bad_segment < 0) return true;

  Failure failure;
  failure.time = state_.time;
  std::ostringstream os;
  os << "simulation blew up at t = " << state_.time << " s (step " << steps_ << ", dt " << dt_
     << " s): ";
  if (bad_node >= 0) {
    const Vector3d& v = state_.v[bad_node];
    failure.node = bad_node;
    failure.quantity = "velocity";
    os << model_.DescribeNode(bad_node) << " (node " << bad_node << ") has velocity ";
    if (v.allFinite()) {
      os << "|v| = " << v.norm() << " m/s, above max_speed " << options_.max_speed << " m/s";
    } else {
      os << "NaN/inf (force " << buffers_.force[bad_node].transpose() << " N)";
    }
  } else {
    const Vector3d& w = state_.w[bad_segment];
    failure.segment = bad_segment;
    failure.quantity = "angular velocity";
    os << model_.DescribeSegment(bad_segment) << " (segment " << bad_segment
       << ") has angular velocity ";
    if (w.allFinite()) {
      os << "|w| = " << w.norm() << " rad/s, turning more than 1 rad per step";
    } else {
      os << "NaN/inf";
    }
  }
  os << "; reduce dt or the safety factor (stable estimate " << stability_.dt_limit << " s)";
  failure.message = os.str();
  failure_ = failure;
  return false;
}

void Simulation::Drift(double h, bool nodes) {
  const int n = model_.num_nodes();
  const int s = model_.num_segments();
  const int threads = options_.threads;
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    if (nodes) {
#pragma omp for schedule(static) nowait
      for (int i = 0; i < n; ++i) state_.x[i] += h * state_.v[i];
    }
#pragma omp for schedule(static)
    for (int j = 0; j < s; ++j) RotateBody(state_.q[j], h * state_.w[j]);
  }
  state_.time += h;
}

bool Simulation::Step() {
  if (failure_) return false;
  bool ok;
  if (options_.integrator == IntegratorType::kSymplecticEuler) {
    // Nodes are kicked and drifted in one pass; a failed kick leaves a state that is discarded.
    EvaluateForces();
    ok = Kick(dt_, dt_);
    if (ok) Drift(dt_, /*nodes=*/false);
  } else {
    if (!forces_current_) EvaluateForces();
    ok = Kick(0.5 * dt_, 0.0);
    if (ok) {
      Drift(dt_, /*nodes=*/true);
      EvaluateForces();
      ok = Kick(0.5 * dt_, 0.0);
    }
  }
  forces_current_ = forces_current_ && options_.integrator == IntegratorType::kVelocityVerlet;
  if (!ok) return false;
  ++steps_;

  if (options_.kinetic_damping) {
    const double kinetic = KineticEnergy();
    if (kinetic < last_kinetic_) {
      // Kinetic damping (Barnes): the kinetic energy peaked about half a step ago, so return
      // the configuration there, x -= 3/2 dt v - 1/2 dt^2 a (likewise the frames), before
      // zeroing the velocities. Without this correction the resets pump the fastest modes: a
      // cantilever of 40 segments blew up at 0.45 of the stable step; with it, relaxation runs
      // at the full step.
      for (int i = 0; i < model_.num_nodes(); ++i)
        state_.x[i] -= 1.5 * dt_ * state_.v[i] -
                       0.5 * dt_ * dt_ * model_.node_inv_mass[i] * buffers_.force[i];
      for (int j = 0; j < model_.num_segments(); ++j)
        RotateBody(state_.q[j], -1.5 * dt_ * state_.w[j] +
                                    0.5 * dt_ * dt_ *
                                        model_.segment_inv_inertia[j].cwiseProduct(buffers_.torque[j]));
      for (Vector3d& v : state_.v) v.setZero();
      for (Vector3d& w : state_.w) w.setZero();
      last_kinetic_ = 0.0;
      forces_current_ = false;  // damping forces depend on the velocities just reset
    } else {
      last_kinetic_ = kinetic;
    }
  }
  return true;
}

bool Simulation::Advance(long steps) {
  for (long k = 0; k < steps; ++k)
    if (!Step()) return false;
  return true;
}

bool Simulation::Relax(double max_time, double force_tolerance, double torque_tolerance) {
  // Kinetic damping with Barnes' correction, which is written for symplectic Euler.
  const SimulationOptions saved = options_;
  options_.kinetic_damping = true;
  options_.integrator = IntegratorType::kSymplecticEuler;
  last_kinetic_ = 0.0;
  const double t_end = state_.time + max_time;
  bool converged = false;
  int check = 0;
  while (state_.time < t_end) {
    if (!Step()) break;
    if (++check % 16 != 0) continue;
    EvaluateForces();
    double f_max = 0.0, tau_max = 0.0;
    for (int i = 0; i < model_.num_nodes(); ++i)
      if (model_.node_inv_mass[i] > 0.0) f_max = std::max(f_max, buffers_.force[i].norm());
    for (int j = 0; j < model_.num_segments(); ++j)
      if (model_.segment_inv_inertia[j].squaredNorm() > 0.0)
        tau_max = std::max(tau_max, buffers_.torque[j].norm());
    if (f_max < force_tolerance && tau_max < torque_tolerance) {
      converged = true;
      break;
    }
  }
  options_ = saved;
  for (Vector3d& v : state_.v) v.setZero();
  for (Vector3d& w : state_.w) w.setZero();
  forces_current_ = false;
  return converged;
}

double Simulation::KineticEnergy() const {
  double kinetic = 0.0;
  for (int i = 0; i < model_.num_nodes(); ++i)
    kinetic += 0.5 * model_.node_mass[i] * state_.v[i].squaredNorm();
  for (int j = 0; j < model_.num_segments(); ++j)
    kinetic += 0.5 * state_.w[j].dot(model_.segment_inertia[j].cwiseProduct(state_.w[j]));
  return kinetic;
}

Energy Simulation::ComputeEnergy() const {
  Energy energy;
  energy.kinetic = KineticEnergy();
  for (const auto& f : forces_) {
    switch (f->energy_kind()) {
      case EnergyKind::kElastic:
        energy.elastic += f->Energy(model_, state_);
        break;
      case EnergyKind::kPotential:
        energy.potential += f->Energy(model_, state_);
        break;
      case EnergyKind::kNone:
        break;
    }
  }
  return energy;
}

}  // namespace netlab::netsim
