#pragma once
// The explicit stability limit, and the treatment of thin stiff threads.
//
// Limit: for symplectic Euler (and velocity Verlet) on x'' = -omega^2 x - 2 a x', a = c / (2 m),
// the step is stable iff dt <= 2 / (sqrt(omega^2 + a^2) + a) (from the trace and determinant of
// the one-step matrix; 2/omega without damping). Every translational and rotational DOF gets an
// upper bound on its omega^2 and a from the Gershgorin row sums of the linearised stiffness and
// damping (forces/force.h: StiffnessBounds), so the smallest limit over all DOFs is a safe
// estimate of the system's limit.
//
// Thin threads: a 1 mm thread has a cross-section inertia mu r^2 / 4 per metre, ~1e4 times smaller
// than the (mu l^2 / 12) of its segments, so the rotational modes, above all the one in which d3
// swings against the tangent through the coupling penalty, are much stiffer than stretching: with
// the physical inertia they would set dt 10-100 times smaller than the stretching wave does. The
// treatment (rotational inertia scaling, a form of selective mass scaling): each segment's
// rotational inertia is raised to I_j = max(I_phys, (S_j + C_j omega_T) / omega_T^2), S_j and C_j
// its rotational stiffness and damping bounds and omega_T the highest translational frequency of
// the model, so no rotation, damped or not, has a smaller stable step than the fastest stretching
// mode and dt is set by the stretching wave alone. The added inertia is
// rotary inertia of the cross-section, whose effect on bending waves of wavenumber k is of relative
// order (k r_g)^2 with r_g the scaled radius of gyration (a few thread radii): far below the
// discretisation error for every wave the mesh resolves. docs/simulator.md gives the measured
// error; `rotational_inertia: physical` turns the scaling off.

#include <vector>

#include "libnetsim/forces/force.h"

namespace netlab::netsim {

class ContactForce;

struct StabilityOptions {
  bool scale_rotational_inertia = true;
  double contact_frequency_ratio = 0.3;  // automatic contact stiffness at omega_c = ratio * omega_T
  double fallback_dt = 0.0;              // s; sets omega_T when the model has no elastic stiffness
  // When > 0 (rad/s), omega_c = contact_frequency_ratio * this instead of omega_T: the implicit
  // integrator keeps the contact as stiff as the explicit step would make it.
  double contact_omega_translation = 0.0;
  // False: the contact's bounds are left out of dt_limit and the inertia scaling (and out of
  // node_bounds); the implicit integrator adds them for the nodes about to touch, step by step.
  bool contact_in_limit = true;
  // True under the implicit integrator: the coupling's torque on the frame's x and y axes is
  // implicit, which keeps those rotations stable whatever their inertia, so only the twist (z)
  // inertia is scaled and only the twist limits the step.
  bool implicit_frames = false;
};

struct StabilityReport {
  double omega_translation = 0.0;  // rad/s, highest translational frequency bound (no contact)
  double dt_limit = 0.0;           // s, estimated stability limit of the whole model
  int limiting_node = -1;          // DOF that sets dt_limit: a node, or
  int limiting_segment = -1;       // a segment's rotation
  double max_inertia_scale = 1.0;  // largest I_scaled / I_physical over segments
  double contact_omega = 0.0;      // rad/s, omega_c given to the contact force (0: none)
  StiffnessBounds bounds;          // the bounds the limit was taken from
};

// The highest translational frequency bound (rad/s) of `forces` but `contact` at `state`.
double TranslationalFrequency(const Model& model, const State& state,
                              const std::vector<const Force*>& forces, const ContactForce* contact);

// Computes the stiffness bounds of `forces` at `state`, configures the contact force (may be
// null), scales the rotational inertia of `model` when asked, and returns the stability limit.
StabilityReport PrepareStability(Model& model, const State& state,
                                 const std::vector<const Force*>& forces, ContactForce* contact,
                                 const StabilityOptions& options);

// The stable-step bound of one DOF: 2 / (sqrt(omega^2 + a^2) + a), with omega^2 = stiffness / mass
// and a = damping / (2 mass). Infinite when both are 0.
double StableStep(double stiffness, double damping, double mass);

}  // namespace netlab::netsim
