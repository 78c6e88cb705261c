#pragma once
// The implicit half of the `implicit` integrator: stretching (and its damping) along each segment,
// solved as one sparse linear system per step, so the axial wave (c = sqrt(EA / mu) ~ 1300 m/s in
// Nylon, a period of ~20 us in a 2 cm segment) no longer limits the step.
//
// The step (after the explicit kick v* = v- + h M^-1 f, f without the axial force, v- the velocity
// before it): the tension is taken at the Newmark average of the positions (beta, gamma below),
//   x^ = beta x_{n+1} + (1/2 + gamma - 2 beta) x_n + (1/2 - gamma + beta) x_{n-1}
//      = x_n + h (P v+ - Q v-),   P = beta, Q = beta - gamma + 1/2
// (x_{n+1} = x_n + h v+, x_{n-1} = x_n - h v-); per segment its length |e~| there, predicted with
// v* (e~ = e0 + h (P (v*_b - v*_a) - Q (v-_b - v-_a))) and linearised about it, along the
// segment's direction at the start of the step, t = e0 / |e0|:
//   relative axial speed u_j = t_j . (v_b - v_a)   (J v, J the s x 3n matrix of these rows),
//     N_j = (EA_j / l_j) (|e~_j| - l_j + P h (u_j - u*_j)) + (c_j / l_j) u_j,
//   impulses lambda = h N on the new velocities  v+ = v* - M^-1 J^T lambda.
// Eliminating v+ leaves, with a_j = h (P h EA_j + c_j) / l_j and W = J M^-1 J^T (s x s, a segment
// coupled to the segments sharing its nodes),
//     (diag(1 / a) + W) lambda = (EA_j (|e~_j| - l_j) + c_j u*_j) / (P h EA_j + c_j),
// symmetric positive definite; its pattern is fixed, so the ordering and symbolic factorisation are
// done once and each step only refactors numerically.
//
// Why Newmark and not backward Euler (P = 1, Q = 0, the tension at the end of the step): on a
// spring of frequency omega the step's one-step matrix has determinant (1 + Q a) / (1 + P a),
// a = (omega h)^2, so a mode the step resolves loses (P - Q) (omega h)^2 / 2 of its amplitude per
// step, a damping ratio (P - Q) omega h / 2: backward Euler gave the thread an axial damping of
// h EA (0.9 N s at the flight nets' step, 1200 times the Nylon's own), and that damping took 90 %
// of the knots' response to a 4x bending stiffness (and 70 % of that to EA / 2) on Net A
// (docs/simulator.md). With gamma = 0.52 the resolved modes keep 50 times more (damping ratio
// 0.01 omega h); the axial waves the step does not resolve (omega h >> 1) still lose
// 1 - sqrt(Q / P) = 3.4 % of their amplitude per step, and P + Q >= 1/2 keeps every mode stable
// (P = Q = 1/4, no damping at all, let a flight blow up). The tension acts along the start
// direction (as SHAKE's constraint force does): a segment turning rigidly keeps its speed, and a
// taut thread's transverse vibration is the explicit step's, undamped, its string stiffness kept
// stable by the substeps (Simulation::ImplicitSubsteps). Along the Newmark point's direction the
// damping ratio of that vibration was (P - Q) omega h / 2 (a taut 10 cm link lost 36 % of its
// amplitude in 0.2 s), along the midpoint of the drift omega h / 4 (all of it).

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "libnetsim/model/model.h"

namespace netlab::netsim {

class AxialStep {
 public:
  // Newmark's parameters of the tension's point (above).
  static constexpr double kBeta = 0.3;
  static constexpr double kGamma = 0.52;

  // Prepares the pattern of the system for `model`'s segments that have axial stiffness or damping.
  explicit AxialStep(const Model& model);

  // Applies the axial impulses of one step of length h to `v` (the velocities after the explicit
  // kick), given the positions x at the start of the step and the velocities v_before the kick.
  // False when the system could not be factorised or its solution is not finite (a state already
  // blown up).
  bool Apply(const Model& model, double h, const std::vector<Vector3d>& x,
             const std::vector<Vector3d>& v_before, std::vector<Vector3d>& v);

  // Segments solved (those with EA or c_s > 0).
  int size() const { return static_cast<int>(segments_.size()); }

  // Per node, the geometric (string) stiffness of the last step's tensions, sum of 2 |N| / |e| over
  // its segments (N/m): the transverse stiffness the tension gives the explicit part of the step.
  const std::vector<double>& geometric_stiffness() const { return geometric_; }

 private:
  // One term of W: inv_m * sign * (t_row . t_col) added to values[value].
  struct Term {
    int value;     // index into the sparse matrix's value array
    int node;      // the shared node
    int row, col;  // rows of the system (indices into segments_)
    double sign;   // +1 when the node is the same end of both segments, else -1
  };

  std::vector<int> segments_;  // model segment of each row
  std::vector<int> diagonal_;  // value index of each row's diagonal entry
  std::vector<Term> terms_;
  Eigen::SparseMatrix<double> matrix_;  // lower triangle
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver_;
  // Per row, per step: the predicted tangent, and the right-hand side.
  std::vector<Vector3d> tangent_;
  std::vector<double> length_;
  Eigen::VectorXd rhs_;
  std::vector<double> geometric_;  // per node
};

}  // namespace netlab::netsim
