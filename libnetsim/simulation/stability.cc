#include "libnetsim/simulation/stability.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "libnetsim/forces/contact_force.h"

namespace netlab::netsim {

double StableStep(double stiffness, double damping, double mass) {
  const double omega2 = stiffness / mass;
  const double a = 0.5 * damping / mass;
  const double denominator = std::sqrt(omega2 + a * a) + a;
  return denominator > 0.0 ? 2.0 / denominator : std::numeric_limits<double>::infinity();
}

double TranslationalFrequency(const Model& model, const State& state,
                              const std::vector<const Force*>& forces,
                              const ContactForce* contact) {
  StiffnessBounds bounds;
  bounds.Resize(model.num_nodes(), model.num_segments());
  for (const Force* force : forces)
    if (force != contact) force->AddStiffnessBounds(model, state, bounds);
  double omega2_max = 0.0;
  for (int i = 0; i < model.num_nodes(); ++i)
    if (model.node_inv_mass[i] != 0.0)
      omega2_max = std::max(omega2_max, bounds.node_stiffness[i] / model.node_mass[i]);
  return std::sqrt(omega2_max);
}

StabilityReport PrepareStability(Model& model, const State& state,
                                 const std::vector<const Force*>& forces, ContactForce* contact,
                                 const StabilityOptions& options) {
  StabilityReport report;
  StiffnessBounds bounds;
  bounds.Resize(model.num_nodes(), model.num_segments());
  for (const Force* force : forces)
    if (force != contact) force->AddStiffnessBounds(model, state, bounds);

  // Highest translational frequency of the model without contact.
  double omega2_max = 0.0;
  for (int i = 0; i < model.num_nodes(); ++i) {
    if (model.node_inv_mass[i] == 0.0) continue;
    omega2_max = std::max(omega2_max, bounds.node_stiffness[i] / model.node_mass[i]);
  }
  if (omega2_max == 0.0 && options.fallback_dt > 0.0) {
    const double omega = 2.0 / options.fallback_dt;
    omega2_max = omega * omega;
  }
  report.omega_translation = std::sqrt(omega2_max);

  if (contact) {
    if (omega2_max == 0.0 && contact->bodies().size() > 0) {
      bool all_set = true;
      for (const RigidBody& body : contact->bodies()) all_set = all_set && body.stiffness > 0.0;
      if (!all_set)
        throw std::invalid_argument(
            "contact: the model has no elastic stiffness to scale the contact stiffness from; give "
            "each body a `stiffness` or set integrator dt");
    }
    const double omega_t = options.contact_omega_translation > 0.0
                               ? options.contact_omega_translation
                               : report.omega_translation;
    report.contact_omega = options.contact_frequency_ratio * omega_t;
    contact->SetContactFrequency(report.contact_omega);
    if (options.contact_in_limit) contact->AddStiffnessBounds(model, state, bounds);
  }

  // Rotational inertia scaling.
  if (options.scale_rotational_inertia && omega2_max > 0.0) {
    const double omega = std::sqrt(omega2_max);
    for (int j = 0; j < model.num_segments(); ++j) {
      const Vector3d physical = model.segment_inertia[j];
      // sqrt(S/I + a^2) + a <= omega_T with a = C/(2I)  <=>  I >= (S + C omega_T) / omega_T^2:
      // neither the stiffness nor the damping of the rotation then limits the step.
      const double needed =
          (bounds.segment_stiffness[j] + bounds.segment_damping[j] * omega) / omega2_max;
      Vector3d scaled = physical.cwiseMax(needed);
      if (options.implicit_frames) scaled.head<2>() = physical.head<2>();
      report.max_inertia_scale =
          std::max(report.max_inertia_scale, scaled.cwiseQuotient(physical).maxCoeff());
      model.segment_inertia[j] = scaled;
      if (model.segment_inv_inertia[j].squaredNorm() > 0.0)
        model.segment_inv_inertia[j] = scaled.cwiseInverse();
    }
  }

  // Stability limit: the smallest over all free DOFs.
  report.dt_limit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < model.num_nodes(); ++i) {
    if (model.node_inv_mass[i] == 0.0) continue;
    const double dt =
        StableStep(bounds.node_stiffness[i], bounds.node_damping[i], model.node_mass[i]);
    if (dt < report.dt_limit) {
      report.dt_limit = dt;
      report.limiting_node = i;
    }
  }
  for (int j = 0; j < model.num_segments(); ++j) {
    if (model.segment_inv_inertia[j].squaredNorm() == 0.0) continue;
    const double inertia = options.implicit_frames ? model.segment_inertia[j].z()
                                                   : model.segment_inertia[j].minCoeff();
    const double dt = StableStep(bounds.segment_stiffness[j], bounds.segment_damping[j], inertia);
    if (dt < report.dt_limit) {
      report.dt_limit = dt;
      report.limiting_node = -1;
      report.limiting_segment = j;
    }
  }
  report.bounds = std::move(bounds);
  return report;
}

}  // namespace netlab::netsim
