#pragma once
// The time stepper: a fixed Model, a changing State, a set of forces and an integrator.
//
//   Simulation sim(std::move(model), std::move(state), std::move(forces), options);
//   while (sim.state().time < t_end)
//     if (!sim.Step()) { report(sim.failure()->message); break; }
//
// Integrators (chosen by SimulationOptions::integrator, tested by one parameterised suite):
//   explicit  symplectic Euler, the paper's explicit scheme: v += dt a(x, v); x += dt v.
//             First order; one force evaluation per step.
//   verlet    velocity Verlet (kick-drift-kick). Second order for conservative forces; damping
//             forces are evaluated with the half-step velocity, so they keep first order.
//   implicit  symplectic Euler for the nodes, with stretching (axial force and damping) solved
//             linearly implicitly (axial_step.h: backward Euler, or with the drift in two
//             stages of an L-stable SDIRK, SimulationOptions::stretching); then each frame turned
//             exactly onto its
//             segment's new tangent and by the small turn that balances bending and twist there,
//             the coupling's torque implicit in it. The thread bends as a Kirchhoff rod and the
//             step is set by bending through the nodes (16 EI / l^3 per node), not by the axial
//             wave or the coupling: 35x explicit's on the flights. A step splits into
//             substeps while the tension's string stiffness or a contact needs it. First order
//             (the split). Backward Euler damps every mode the step resolves (ratio omega h / 2:
//             an axial damping of h EA); the two-stage step keeps them (~0.004 (omega h)^3), and
//             both damp away the axial waves the step does not resolve.
// Rotations follow the same schemes with the body-frame Euler equation
// I dw/dt = tau - w x (I w) and q <- q Exp(w dt).
//
// A bad number is never carried on: after each step every velocity is checked (NaN, or a node
// faster than max_speed, or a segment turning by more than 1 rad in one step) and the run stops
// with a Failure naming the time, the node or segment and the quantity.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "libnetsim/forces/force.h"
#include "libnetsim/model/model.h"
#include "libnetsim/simulation/stability.h"

namespace netlab::netsim {

class AxialStep;
class BendTwistForce;
class ContactForce;
class SegmentForce;

enum class IntegratorType { kSymplecticEuler, kVelocityVerlet, kImplicit };
// The implicit integrator's stretching step (axial_step.h).
enum class StretchingScheme { kBackwardEuler, kSdirk2 };

// "explicit" / "verlet" / "implicit".
std::string IntegratorName(IntegratorType type);
// Parses "explicit" (also "symplectic_euler"), "verlet" or "implicit"; false on anything else.
bool ParseIntegratorType(const std::string& text, IntegratorType* type);
// "backward_euler" / "sdirk2", and back; false on anything else.
std::string StretchingName(StretchingScheme scheme);
bool ParseStretchingScheme(const std::string& text, StretchingScheme* scheme);

struct SimulationOptions {
  IntegratorType integrator = IntegratorType::kSymplecticEuler;
  // Time step, s. 0 chooses safety * (estimated stability limit) automatically.
  double dt = 0.0;
  // Fraction of the estimated stability limit used when dt is automatic; the estimate is an upper
  // bound on every frequency, so values up to 1 are stable for the initial configuration. 0: the
  // integrator's own, 0.9, or 0.6 for implicit, whose estimate bounds stability but not accuracy:
  // at 0.9 of it a mode near the limit, barely damped, drifted Net B's knots 2.8 mm in 1 s of
  // flight, at 0.6 0.43 mm (docs/benchmarks.md).
  double safety = 0.0;
  double EffectiveSafety() const {
    return safety > 0.0 ? safety : integrator == IntegratorType::kImplicit ? 0.6 : 0.9;
  }
  // When > 0 (s), an automatic dt is lowered so that this interval is a whole number of steps
  // (output frames land exactly on multiples of it).
  double align_interval = 0.0;
  bool scale_rotational_inertia = true;  // stability.h
  // The implicit integrator's stretching step. backward_euler damps the modes the step resolves
  // (Net A's response to a 4x bending stiffness: 0.92 relative error against the explicit
  // step); sdirk2 keeps them there (0.04) at 1.3x the CPU time, but not everywhere: the
  // tension's substeps switch on and off with the vibration it keeps, so a run is not smooth in
  // its parameters (the fit's 5 x 5 twin: the drag's cost rough, the fit fails), and a 5 x 5 net
  // flying as the flights do strays from the explicit step's response after 0.4 s.
  // docs/simulator.md.
  StretchingScheme stretching = StretchingScheme::kBackwardEuler;
  double contact_frequency_ratio = 0.3;  // contact_force.h
  // Implicit integrator: the contact's penalty is taken implicitly, node by node, within the whole
  // step; false: the whole net takes the substeps that resolve it as the explicit step does
  // (slower, for comparison). docs/simulator.md.
  bool implicit_contact = true;
  // Reset all velocities whenever the kinetic energy falls (dynamic relaxation to a static
  // equilibrium, with Barnes' correction of the positions to the energy peak). Changes the
  // dynamics: only for statics. Needs the explicit or the implicit integrator.
  bool kinetic_damping = false;
  double max_speed = 1e3;  // m/s: a node faster than this stops the run as a blow-up
  // Threads the forces that loop over segments and joints use (Force::SetThreads): the same bits
  // for any count. Worth it for the large nets only (docs/benchmarks.md).
  int threads = 1;

  // True if the options are usable; otherwise false with the offending field named in *error.
  bool IsValid(std::string* error) const;
};

struct Energy {
  double kinetic = 0.0;    // J, translation and rotation
  double elastic = 0.0;    // J, stretching, bending, torsion and the coupling penalty
  double potential = 0.0;  // J, gravity, centrifugal, point forces and contact penalty
  double total() const { return kinetic + elastic + potential; }
};

// Why a run stopped early.
struct Failure {
  double time = 0.0;     // s, the time of the state that holds the bad value
  int node = -1;         // the node, or -1
  int segment = -1;      // the segment, or -1
  std::string quantity;  // "velocity", "angular velocity"
  std::string message;   // all of the above in one sentence, for the user
};

class Simulation {
 public:
  // Takes ownership of everything. Prepares the stability estimate (and scales rotational inertia
  // when asked). Throws std::invalid_argument on invalid options or an unusable model.
  Simulation(Model model, State state, std::vector<std::unique_ptr<Force>> forces,
             const SimulationOptions& options);
  ~Simulation();
  Simulation(Simulation&&) noexcept;

  const Model& model() const { return model_; }
  const State& state() const { return state_; }
  // The state may be edited between steps (tests, interactive tools).
  State& mutable_state() {
    forces_current_ = false;
    return state_;
  }
  const SimulationOptions& options() const { return options_; }

  double dt() const { return dt_; }
  const StabilityReport& stability() const { return stability_; }
  // Names of the forces in use, in evaluation order.
  std::vector<std::string> active_forces() const;

  // One step; false when the step produced a NaN or blow-up (see failure()).
  bool Step();
  // Up to `steps` steps; false on failure.
  bool Advance(long steps);
  // Runs with kinetic damping until every node force is below `force_tolerance` (N) and every
  // segment torque below `torque_tolerance` (N m), or until `max_time` (s) of pseudo-time has
  // passed. True when converged. Velocities are zero afterwards. Kinetic damping needs
  // conservative loads: a dead moment in 3D is not, and needs damped dynamics instead. Steps with
  // symplectic Euler (or, with the implicit integrator, its own step, resetting the velocities
  // without the peak correction).
  bool Relax(double max_time, double force_tolerance, double torque_tolerance);

  const std::optional<Failure>& failure() const { return failure_; }
  long steps_taken() const { return steps_; }
  // The implicit integrator splits a step into substeps while the tension (or, without
  // implicit_contact, a contact) needs a smaller one (the others: substeps == steps). Total and
  // largest count per step.
  long substeps_taken() const { return substeps_total_; }
  int max_substeps() const { return max_substeps_; }
  Energy ComputeEnergy() const;

  // Deepest contact penetration seen so far (m) and its node (-1: no contact yet).
  double max_penetration() const { return max_penetration_; }
  int max_penetration_node() const { return max_penetration_node_; }
  // Forces of the last evaluation.
  const ForceBuffers& forces() const { return buffers_; }
  // Evaluates all forces at the current state into forces(). Under the implicit integrator these
  // leave out what the stepper solves itself: the axial force and the coupling's torque.
  void EvaluateForces();

 private:
  // v += h a, then x += drift v (drift 0: velocities only); returns false (and records the
  // failure) on a bad velocity.
  bool Kick(double h, double drift);
  // Records the failure of a bad node or segment (-1: none) and returns false.
  bool BlowUp(int bad_node, int bad_segment);
  // q <- q Exp(h w) for every segment, and x += h v when `nodes`; advances the time by h.
  void Drift(double h, bool nodes);
  double KineticEnergy() const;
  // The implicit integrator: substeps the next step needs (>= 1), from the static bounds plus the
  // tension's geometric stiffness (and, without implicit_contact, the contact of the nodes about
  // to touch); one substep of h.
  int ImplicitSubsteps();
  bool ImplicitSubstep(double h);
  // The implicit integrator's first step: the velocities set half a step back (see .cc).
  void StaggerVelocities();
  // SimulationOptions::implicit_contact: every node's contact over a substep of length h.
  void ImplicitContact(double h);

  Model model_;
  State state_;
  std::vector<std::unique_ptr<Force>> forces_;
  std::unique_ptr<AxialStep> axial_;       // the implicit integrator's stretching; else null
  SegmentForce* segment_force_ = nullptr;  // implicit: the force whose stretching, coupling
                                           // torque the stepper solves
  bool implicit_frames_ = false;           // implicit with coupling: frames follow (see .cc)
  BendTwistForce* joints_ = nullptr;       // implicit frames: evaluated on the turned frames
  bool skip_joints_ = false;
  bool skip_contact_ = false;          // implicit contact: resolved by the stepper, not in the kick
  std::vector<Quaterniond> turned_;    // scratch: frames turned to the new tangents
  std::vector<Vector3d> drift_;        // implicit: each node's mean velocity over the step
  std::vector<double> node_step_;      // implicit: per node, min(dt, its static stable step)
  std::vector<double> frame_damping_;  // per segment, its joints' bending damping, N m s
  std::vector<double> frame_twist_;    // ... their twist stiffness, N m
  std::vector<double> frame_twist_damping_;  // ... their twist damping, N m s
  ContactForce* contact_ = nullptr;
  SimulationOptions options_;
  StabilityReport stability_;
  double dt_ = 0.0;
  double step_ = 0.0;  // the (sub)step being taken, s
  long substeps_total_ = 0;
  int max_substeps_ = 0;
  bool gyroscopic_ = false;  // any segment with unequal principal inertias
  bool forces_current_ = false;
  ForceBuffers buffers_;
  std::optional<Failure> failure_;
  long steps_ = 0;
  double max_penetration_ = 0.0;
  int max_penetration_node_ = -1;
  double last_kinetic_ = 0.0;
};

}  // namespace netlab::netsim
