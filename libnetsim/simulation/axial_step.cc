#include "libnetsim/simulation/axial_step.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace netlab::netsim {

AxialStep::AxialStep(const Model& model) {
  // Rows: the segments with an axial force. Each node's rows, with the end the node is (a: -1).
  std::vector<std::vector<std::pair<int, double>>> rows_of(model.num_nodes());
  for (int j = 0; j < model.num_segments(); ++j) {
    const Segment& s = model.segments[j];
    if (s.stretch_stiffness <= 0.0 && s.stretch_damping <= 0.0) continue;
    const int row = static_cast<int>(segments_.size());
    segments_.push_back(j);
    rows_of[s.node_a].emplace_back(row, -1.0);
    rows_of[s.node_b].emplace_back(row, +1.0);
  }
  const int n = size();
  std::vector<Eigen::Triplet<double>> pattern;
  for (int r = 0; r < n; ++r) pattern.emplace_back(r, r, 1.0);
  for (int i = 0; i < model.num_nodes(); ++i) {
    if (model.node_inv_mass[i] == 0.0) continue;
    for (const auto& [r1, s1] : rows_of[i])
      for (const auto& [r2, s2] : rows_of[i])
        if (r1 > r2) pattern.emplace_back(r1, r2, 1.0);
  }
  matrix_.resize(n, n);
  matrix_.setFromTriplets(pattern.begin(), pattern.end());  // duplicates summed: pattern only
  matrix_.makeCompressed();
  auto value_index = [&](int row, int col) {
    const int* inner = matrix_.innerIndexPtr();
    const int* outer = matrix_.outerIndexPtr();
    const int* found = std::lower_bound(inner + outer[col], inner + outer[col + 1], row);
    return static_cast<int>(found - inner);
  };
  diagonal_.resize(n);
  for (int r = 0; r < n; ++r) diagonal_[r] = value_index(r, r);
  for (int i = 0; i < model.num_nodes(); ++i) {
    if (model.node_inv_mass[i] == 0.0) continue;
    for (const auto& [r1, s1] : rows_of[i])
      for (const auto& [r2, s2] : rows_of[i])
        if (r1 > r2) terms_.push_back({value_index(r1, r2), i, r1, r2, s1 * s2});
  }
  tangent_.resize(n);
  length_.resize(n);
  rhs_.resize(n);
  geometric_.assign(model.num_nodes(), 0.0);
  if (n > 0) solver_.analyzePattern(matrix_);
}

bool AxialStep::Apply(const Model& model, double h, const std::vector<Vector3d>& x,
                      std::vector<Vector3d>& v, bool end_direction) {
  const int n = size();
  if (n == 0) return true;
  double* values = matrix_.valuePtr();
  std::fill(values, values + matrix_.nonZeros(), 0.0);
  for (int r = 0; r < n; ++r) {
    const Segment& s = model.segments[segments_[r]];
    const Vector3d& va = v[s.node_a];
    const Vector3d& vb = v[s.node_b];
    const Vector3d e0 = x[s.node_b] - x[s.node_a];
    const Vector3d e = e0 + h * (vb - va);  // predicted
    const double length = e.norm();
    // The direction predicted for the end of the stage, or the stage's midpoint direction.
    const Vector3d t = end_direction ? Vector3d(e / length) : (e0 + e).normalized();
    tangent_[r] = t;
    length_[r] = length;
    const double u = t.dot(vb - va);
    const double stiff = h * s.stretch_stiffness + s.stretch_damping;  // (h EA + c), N s
    rhs_[r] = (s.stretch_stiffness * (length - s.rest_length) + s.stretch_damping * u) / stiff;
    values[diagonal_[r]] =
        model.node_inv_mass[s.node_a] + model.node_inv_mass[s.node_b] + s.rest_length / (h * stiff);
  }
  for (const Term& term : terms_)
    values[term.value] +=
        term.sign * model.node_inv_mass[term.node] * tangent_[term.row].dot(tangent_[term.col]);

  solver_.factorize(matrix_);
  if (solver_.info() != Eigen::Success) return false;
  const Eigen::VectorXd lambda = solver_.solve(rhs_);
  if (!lambda.allFinite()) return false;

  std::fill(geometric_.begin(), geometric_.end(), 0.0);
  for (int r = 0; r < n; ++r) {
    const Segment& s = model.segments[segments_[r]];
    const Vector3d impulse = lambda[r] * tangent_[r];  // pulls b towards a when in tension
    v[s.node_b] -= model.node_inv_mass[s.node_b] * impulse;
    v[s.node_a] += model.node_inv_mass[s.node_a] * impulse;
    const double k = 2.0 * std::abs(lambda[r]) / (h * length_[r]);
    geometric_[s.node_a] += k;
    geometric_[s.node_b] += k;
  }
  return true;
}

bool AxialStep::Step(const Model& model, double h, const std::vector<Vector3d>& x,
                     std::vector<Vector3d>& v, std::vector<Vector3d>& drift) {
  constexpr double g = kGamma;
  const size_t nodes = v.size();
  kicked_ = v;
  drift = v;
  if (!Apply(model, g * h, x, drift, true)) return false;  // stage 1: V1 in drift
  base_.resize(nodes);
  for (size_t i = 0; i < nodes; ++i) {
    base_[i] = x[i] + ((1.0 - g) * h) * drift[i];
    v[i] = kicked_[i] + ((1.0 - g) / g) * (drift[i] - kicked_[i]);
  }
  if (!Apply(model, g * h, base_, v, true)) return false;  // stage 2: V2 in v
  for (size_t i = 0; i < nodes; ++i) drift[i] = (1.0 - g) * drift[i] + g * v[i];
  return true;
}

}  // namespace netlab::netsim
