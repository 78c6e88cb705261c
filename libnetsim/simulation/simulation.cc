
#include "libnetsim/simulation/simulation.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/contact_force.h"
#include "libnetsim/forces/segment_force.h"
#include "libnetsim/model/rotation.h"
#include "libnetsim/simulation/axial_step.h"

namespace netlab::netsim {

std::string IntegratorName(IntegratorType type) {
  switch (type) {
    case IntegratorType::kVelocityVerlet: return "verlet";
    case IntegratorType::kImplicit: return "implicit";
    case IntegratorType::kSymplecticEuler: break;
  }
  return "explicit";
}

std::string StretchingName(StretchingScheme scheme) {
  return scheme == StretchingScheme::kSdirk2 ? "sdirk2" : "backward_euler";
}

bool ParseStretchingScheme(const std::string& text, StretchingScheme* scheme) {
  if (text == "backward_euler") {
    *scheme = StretchingScheme::kBackwardEuler;
    return true;
  }
  if (text == "sdirk2") {
    *scheme = StretchingScheme::kSdirk2;
    return true;
  }
  return false;
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
  if (text == "implicit") {
    *type = IntegratorType::kImplicit;
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
  if (!(safety >= 0.0 && safety <= 1.0)) return fail("safety must be in (0, 1] (0: the default)");
  if (!(align_interval >= 0.0) || !std::isfinite(align_interval))
    return fail("align_interval must be >= 0");
  if (!(contact_frequency_ratio > 0.0 && contact_frequency_ratio <= 1.0))
    return fail("contact_frequency_ratio must be in (0, 1]");
  if (!(max_speed > 0.0)) return fail("max_speed must be > 0");
  if (threads < 1 || threads > 256) return fail("threads must be in 1..256");
  if (kinetic_damping && integrator == IntegratorType::kVelocityVerlet)
    return fail(
        "kinetic_damping needs type explicit or implicit (its peak correction is "
        "symplectic Euler's)");
  return true;
}

Simulation::Simulation(Model model, State state, std::vector<std::unique_ptr<Force>> forces,
                       const SimulationOptions& options)
    : model_(std::move(model)),
      state_(std::move(state)),
      forces_(std::move(forces)),
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
    if (auto* segment = dynamic_cast<SegmentForce*>(f.get()))
      if (options_.integrator == IntegratorType::kImplicit) segment_force_ = segment;
  }
  contact_ = contact;
  StabilityOptions stability_options;
  stability_options.scale_rotational_inertia = options_.scale_rotational_inertia;
  stability_options.contact_frequency_ratio = options_.contact_frequency_ratio;
  stability_options.fallback_dt = options_.dt;
  if (segment_force_) {
    // The contact keeps the stiffness the explicit step gives it (the axial wave's frequency), so
    // it presses no deeper; its bounds enter step by step, for the nodes about to touch.
    stability_options.contact_omega_translation =
        TranslationalFrequency(model_, state_, views, contact);
    stability_options.contact_in_limit = false;
    // With the physical rotational inertia the frames' own motion is asked for: it stays
    // explicit, resolved at its own (small) step.
    implicit_frames_ = segment_force_->coupling() && options_.scale_rotational_inertia;
    segment_force_->SetImplicit(true, implicit_frames_);
    stability_options.implicit_frames = implicit_frames_;
    if (implicit_frames_)
      for (const auto& f : forces_)
        if (auto* joints = dynamic_cast<BendTwistForce*>(f.get())) {
          joints->SetFramesFollowCentreline(true);
          joints_ = joints;
        }
  }
  stability_ = PrepareStability(model_, state_, views, contact, stability_options);

  if (options_.dt > 0.0) {
    dt_ = options_.dt;
  } else {
    if (!std::isfinite(stability_.dt_limit))
      throw std::invalid_argument(
          "integrator: dt auto needs a model with stiffness or damping; give dt in seconds");
    dt_ = options_.EffectiveSafety() * stability_.dt_limit;
    if (options_.align_interval > 0.0) {
      const double steps = std::ceil(options_.align_interval / dt_ - 1e-9);
      dt_ = options_.align_interval / steps;
    }
  }
  for (const Vector3d& inertia : model_.segment_inertia)
    if (inertia.maxCoeff() - inertia.minCoeff() > 1e-12 * inertia.maxCoeff()) gyroscopic_ = true;
  buffers_.Resize(model_.num_nodes(), model_.num_segments());
  if (segment_force_ && segment_force_->stretch()) {
    axial_ = std::make_unique<AxialStep>(model_);
    // Each node's own step under the static bounds, capped at dt (ImplicitSubsteps).
    node_step_.resize(model_.num_nodes());
    for (int i = 0; i < model_.num_nodes(); ++i)
      node_step_[i] =
          std::min(dt_, options_.EffectiveSafety() * StableStep(stability_.bounds.node_stiffness[i],
                                                                stability_.bounds.node_damping[i],
                                                                model_.node_mass[i]));
  }
  if (implicit_frames_) {
    // Each frame's own bending damping coefficient: c_b / l over its joints (2 c_b / l at a clamp).
    frame_damping_.assign(model_.num_segments(), 0.0);
    frame_twist_.assign(model_.num_segments(), 0.0);
    frame_twist_damping_.assign(model_.num_segments(), 0.0);
    if (joints_) {
      for (const BendPair& p : model_.bend_pairs) {
        const double c = p.damping.head<2>().maxCoeff() * p.inv_length;
        for (const int j : {p.segment_a, p.segment_b}) {
          frame_damping_[j] += c;
          frame_twist_[j] += p.stiffness.z() * p.inv_length;
          frame_twist_damping_[j] += p.damping.z() * p.inv_length;
        }
      }
      for (const AnchorJoint& a : model_.anchors) {
        frame_damping_[a.segment] += a.damping.head<2>().maxCoeff() * a.inv_length;
        frame_twist_[a.segment] += a.stiffness.z() * a.inv_length;
        frame_twist_damping_[a.segment] += a.damping.z() * a.inv_length;
      }
    }
  }
  step_ = dt_;
}

Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;

std::vector<std::string> Simulation::active_forces() const {
  std::vector<std::string> names;
  for (const auto& f : forces_) names.push_back(f->name());
  return names;
}

void Simulation::EvaluateForces() {
  buffers_.Zero();
  for (const auto& f : forces_)
    if (!(skip_joints_ && f.get() == joints_) && !(skip_contact_ && f.get() == contact_))
      f->Accumulate(model_, state_, step_, buffers_);
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
      if (!(w.squaredNorm() * step_ * step_ <= 1.0) && j < bad_segment) bad_segment = j;
    }
  }
  if (bad_node == n) bad_node = -1;
  if (bad_segment == s) bad_segment = -1;
  if (bad_node < 0 && bad_segment < 0) return true;
  return BlowUp(bad_node, bad_segment);
}

bool Simulation::BlowUp(int bad_node, int bad_segment) {
  Failure failure;
  failure.time = state_.time;
  std::ostringstream os;
  os << "simulation blew up at t = " << state_.time << " s (step " << steps_ << ", dt " << step_
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
  } else if (options_.integrator == IntegratorType::kImplicit) {
    if (steps_ == 0 && !options_.kinetic_damping) StaggerVelocities();
    const int substeps = ImplicitSubsteps();
    ok = true;
    for (int k = 0; k < substeps && ok; ++k) ok = ImplicitSubstep(dt_ / substeps);
    step_ = dt_;
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
  if (options_.integrator != IntegratorType::kImplicit) {
    ++substeps_total_;
    max_substeps_ = 1;
  }

  if (options_.kinetic_damping) {
    const double kinetic = KineticEnergy();
    if (kinetic < last_kinetic_ && options_.integrator == IntegratorType::kImplicit) {
      for (Vector3d& v : state_.v) v.setZero();
      for (Vector3d& w : state_.w) w.setZero();
      last_kinetic_ = 0.0;
    } else if (kinetic < last_kinetic_) {
      // Kinetic damping (Barnes): the kinetic energy peaked about half a step ago, so return
      // the configuration there, x -= 3/2 dt v - 1/2 dt^2 a (likewise the frames), before
      // zeroing the velocities. Without this correction the resets pump the fastest modes: a
      // cantilever of 40 segments blew up at 0.45 of the stable step; with it, relaxation runs
      // at the full step.
      for (int i = 0; i < model_.num_nodes(); ++i)
        state_.x[i] -=
            1.5 * dt_ * state_.v[i] - 0.5 * dt_ * dt_ * model_.node_inv_mass[i] * buffers_.force[i];
      for (int j = 0; j < model_.num_segments(); ++j)
        RotateBody(
            state_.q[j],
            -1.5 * dt_ * state_.w[j] +
                0.5 * dt_ * dt_ * model_.segment_inv_inertia[j].cwiseProduct(buffers_.torque[j]));
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

// The contact of a node with a target is as stiff as the elastic model's fastest mode allows
// (contact_force.h): the implicit step, 35x longer, does not resolve it. Rather than the whole net
// taking the explicit step's substeps while any node touches (what implicit_contact = false
// does), each node's penalty is taken as backward Euler within the step, on its own
// (ContactForce::ResolveImplicit), after the stretching: a node the tension pulls onto the target
// is held at the depth where the penalty carries the tension, in the same step. Taken in node
// order, one node at a time: the same bits for any thread count.
void Simulation::ImplicitContact(double h) {
  const int n = model_.num_nodes();
  // Under the two-stage stretching drift_ holds the drift, state_.v the end velocities.
  const bool apart = axial_ && options_.stretching == StretchingScheme::kSdirk2;
  for (int i = 0; i < n; ++i) {
    if (model_.node_inv_mass[i] == 0.0) continue;
    Vector3d& drift = apart ? drift_[i] : state_.v[i];
    const Vector3d before = drift;
    const double depth = contact_->ResolveImplicit(model_, i, state_.x[i], state_.time, h, &drift);
    if (apart) state_.v[i] += drift - before;
    if (depth > max_penetration_) {
      max_penetration_ = depth;
      max_penetration_node_ = i;
    }
  }
}

// Symplectic Euler (kick, then drift) holds the velocity of the middle of the step it takes: a
// node started at v0 under a constant acceleration a lands at x0 + v0 t + a t^2 / 2 + a h t / 2.
// At the explicit step that offset is 1e-4 m after a second of free fall under g; at the
// implicit step, 35-50x longer, it was 0.6 mm after 0.1 s of the paper's capture and growing.
// Started with the velocity half a step back, v = v0 - a0 h / 2, the kick takes it to
// v0 + a0 h / 2, the velocity of the middle of the first step (leapfrog), and the scheme lands on
// x0 + v0 t + a t^2 / 2 exactly. Nodes only: no constant torque acts on the frames.
void Simulation::StaggerVelocities() {
  step_ = dt_;
  skip_joints_ = implicit_frames_;
  skip_contact_ = contact_ && options_.implicit_contact;
  EvaluateForces();
  skip_contact_ = false;
  skip_joints_ = false;
  for (int i = 0; i < model_.num_nodes(); ++i)
    state_.v[i] -= (0.5 * dt_ * model_.node_inv_mass[i]) * buffers_.force[i];
}

int Simulation::ImplicitSubsteps() {
  constexpr double kExplicitSafety = 0.9;  // the explicit step's default
  // The static bounds hold for the whole run; the tension's string stiffness and contact come and
  // go. A node whose tension raises its bounds needs the step that keeps its margin: safety times
  // its own limit, or, where the step is already above that (a dt the user chose), the step
  // shrunk by the ratio its limit shrank, so such a dt still blows up. Without implicit_contact
  // a contact is resolved by the whole net as the explicit step resolves it, omega_c h <= 2 x 0.9
  // x contact_frequency_ratio (0.54): at the stability limit instead (0.75 with the critically
  // damped boxes) a thread dropped on a box bounced back at half its speed where the explicit step
  // lands it dead. With it (the default) the contact takes no substeps (ImplicitContact).
  double ratio = 1.0;
  if (axial_) {
    const std::vector<double>& geometric = axial_->geometric_stiffness();
    const StiffnessBounds& fixed = stability_.bounds;
    for (int i = 0; i < model_.num_nodes(); ++i) {
      if (model_.node_inv_mass[i] == 0.0 || geometric[i] == 0.0) continue;
      const double h_tension =
          options_.EffectiveSafety() * StableStep(fixed.node_stiffness[i] + geometric[i],
                                                  fixed.node_damping[i], model_.node_mass[i]);
      ratio = std::max(ratio, node_step_[i] / h_tension);
    }
  }
  if (contact_ && !options_.implicit_contact) {
    const double omega = contact_->NearContactFrequency(model_, state_, dt_);
    if (omega > 0.0)
      ratio =
          std::max(ratio, dt_ * omega / (2.0 * kExplicitSafety * options_.contact_frequency_ratio));
  }
  constexpr int kMaxSubsteps = 4096;  // beyond it the blow-up check stops the run
  const int substeps =
      ratio < kMaxSubsteps ? static_cast<int>(std::ceil(ratio - 1e-9)) : kMaxSubsteps;
  substeps_total_ += substeps;
  max_substeps_ = std::max(max_substeps_, substeps);
  return substeps;
}

bool Simulation::ImplicitSubstep(double h) {
  step_ = h;
  skip_joints_ = implicit_frames_;  // evaluated below, on the frames turned to the new tangents
  skip_contact_ = contact_ && options_.implicit_contact;  // resolved below
  EvaluateForces();
  skip_contact_ = false;
  skip_joints_ = false;
  const int n = model_.num_nodes();
  const int s = model_.num_segments();
  const double limit2 = options_.max_speed * options_.max_speed;
  const int threads = options_.threads;
  // Nodes: the explicit kick, the implicit stretching (backward Euler, or with the drift in two
  // stages: axial_step.h) and contact (on the drift, its change added to the velocities), the
  // drift.
  int bad_node = n;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) \
    reduction(min                                                               \
              : bad_node)
  for (int i = 0; i < n; ++i) {
    Vector3d& v = state_.v[i];
    v += (h * model_.node_inv_mass[i]) * buffers_.force[i];
    if (!(v.squaredNorm() <= limit2) && i < bad_node) bad_node = i;
  }
  if (bad_node < n) return BlowUp(bad_node, -1);
  const bool two_stage = options_.stretching == StretchingScheme::kSdirk2;
  if (axial_ && !(two_stage ? axial_->Step(model_, h, state_.x, state_.v, drift_)
                            : axial_->Apply(model_, h, state_.x, state_.v))) {
    Failure failure;
    failure.time = state_.time;
    failure.quantity = "tension";
    std::ostringstream os;
    os << "simulation blew up at t = " << state_.time << " s (step " << steps_ << ", dt " << h
       << " s): the implicit stretching step has no finite solution (a node's position or "
          "velocity is no longer finite); reduce dt or the safety factor (stable estimate "
       << stability_.dt_limit << " s)";
    failure.message = os.str();
    failure_ = failure;
    return false;
  }
  if (contact_ && options_.implicit_contact) ImplicitContact(h);
  const std::vector<Vector3d>& drift = axial_ && two_stage ? drift_ : state_.v;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
  for (int i = 0; i < n; ++i) state_.x[i] += h * drift[i];

  // Frames. Each is first turned by the minimal rotation onto its segment's new tangent (exact:
  // the frame follows its centreline within the step instead of swinging about it), then by the
  // small turn w' that balances the bending and twist torques tau there, with the coupling's
  // restoring torque -kappa l (h w') on x and y implicit in it:
  //   I (w+ - w) = h (tau - h kappa l w'),  w+ = r / h + w',  r the minimal rotation (body frame).
  // The nodes then feel bending through the coupling, as a Kirchhoff rod. tau is taken on the
  // turned frames: on the old ones the nodes would feel the bending of the step before, a delayed
  // force that is unstable at any step. Linearising the coupling about the old frame instead of
  // turning it exactly overshot by ~alpha^3 / 3 for a tangent turning by alpha in a step, which
  // a net snapping straight amplified into a blow-up.
  if (implicit_frames_) {
    turned_.resize(s);
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
    for (int j = 0; j < s; ++j) {
      const Segment& seg = model_.segments[j];
      const Vector3d t = (state_.x[seg.node_b] - state_.x[seg.node_a]).normalized();
      turned_[j] = model_.segment_inv_inertia[j].squaredNorm() == 0.0
                       ? state_.q[j]
                       : Quaterniond(MinimalRotation(Director3(state_.q[j]), t) * state_.q[j]);
    }
    if (joints_) {
      std::swap(state_.q, turned_);
      joints_->Accumulate(model_, state_, h, buffers_);
      std::swap(state_.q, turned_);
    }
  }
  int bad_segment = s;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) \
    reduction(min                                                               \
              : bad_segment)
  for (int j = 0; j < s; ++j) {
    if (model_.segment_inv_inertia[j].squaredNorm() == 0.0) continue;
    const Vector3d& inertia = model_.segment_inertia[j];
    Vector3d& w = state_.w[j];
    Vector3d torque = buffers_.torque[j];
    if (gyroscopic_ && !implicit_frames_) torque -= w.cross(inertia.cwiseProduct(w));
    if (implicit_frames_) {
      const Segment& seg = model_.segments[j];
      const Vector3d r = LogMap(state_.q[j].conjugate() * turned_[j]).phi;
      const Vector3d w_r = r / h;
      const double stiff = h * h * seg.coupling_stiffness * seg.rest_length;
      // The joints' damping of this frame's own turn (tau holds -C w), implicit as well:
      // explicit, it overshoots once h C exceeds twice the frame's (thin) inertia.
      const double c = h * frame_damping_[j];
      Vector3d turn;
      turn.x() =
          ((inertia.x() + c) * (w.x() - w_r.x()) + h * torque.x()) / (inertia.x() + stiff + c);
      turn.y() =
          ((inertia.y() + c) * (w.y() - w_r.y()) + h * torque.y()) / (inertia.y() + stiff + c);
      // The twist likewise: its own stiffness and damping implicit (in a curved thread the
      // twist of a frame that follows its centreline was unstable with them explicit).
      const double cz = h * frame_twist_damping_[j], kz = h * h * frame_twist_[j];
      turn.z() =
          ((inertia.z() + cz) * (w.z() - w_r.z()) + h * torque.z()) / (inertia.z() + kz + cz);
      w = w_r + turn;
      if (!(w.squaredNorm() * h * h <= 1.0) && j < bad_segment) bad_segment = j;
      state_.q[j] = turned_[j];
      RotateBody(state_.q[j], h * turn);
      continue;
    }
    w += h * model_.segment_inv_inertia[j].cwiseProduct(torque);
    if (!(w.squaredNorm() * h * h <= 1.0) && j < bad_segment) bad_segment = j;
    RotateBody(state_.q[j], h * w);
  }
  if (bad_segment < s) return BlowUp(-1, bad_segment);
  state_.time += h;
  return true;
}

bool Simulation::Advance(long steps) {
  for (long k = 0; k < steps; ++k)
    if (!Step()) return false;
  return true;
}

bool Simulation::Relax(double max_time, double force_tolerance, double torque_tolerance) {
  // Kinetic damping with Barnes' correction, which is written for symplectic Euler; the implicit
  // integrator resets the velocities without it (its implicit parts damp the fastest modes).
  const SimulationOptions saved = options_;
  if (options_.integrator != IntegratorType::kImplicit)
    options_.integrator = IntegratorType::kSymplecticEuler;
  options_.kinetic_damping = true;
  last_kinetic_ = 0.0;
  const double t_end = state_.time + max_time;
  bool converged = false;
  int check = 0;
  while (state_.time < t_end) {
    if (!Step()) break;
    if (++check % 16 != 0) continue;
    // The whole force, with the parts the implicit stepper solves itself.
    if (segment_force_) segment_force_->SetImplicit(false, false);
    EvaluateForces();
    if (segment_force_) segment_force_->SetImplicit(true, implicit_frames_);
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
      case EnergyKind::kElastic: energy.elastic += f->Energy(model_, state_); break;
      case EnergyKind::kPotential: energy.potential += f->Energy(model_, state_); break;
      case EnergyKind::kNone: break;
    }
  }
  return energy;
}

}  // namespace netlab::netsim
