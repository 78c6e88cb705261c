#pragma once
// The implicit half of the `implicit` integrator: stretching (and its damping) along each segment,
// solved as one sparse linear system per step, so the axial wave (c = sqrt(EA / mu) ~ 1300 m/s in
// Nylon, a period of ~20 us in a 2 cm segment) no longer limits the step.
//
// The step (after the explicit kick v* = v + h M^-1 f, f without the axial force):
//   predicted positions  x~ = x + h v*,   per segment  e~ = x~_b - x~_a,  t~ = e~ / |e~|,
//   relative axial speed u_j = t~_j . (v_b - v_a)   (J v, J the s x 3n matrix of these rows),
//   tension at the end of the step, linearised about the prediction (one Newton step of backward
//   Euler from the explicit predictor):
//     N_j = (EA_j / l_j) (|e~_j| - l_j + h (u_j - u*_j)) + (c_j / l_j) u_j,
//   impulses lambda = h N on the new velocities  v+ = v* - M^-1 J^T lambda.
// Eliminating v+ leaves, with a_j = h (h EA_j + c_j) / l_j and W = J M^-1 J^T (s x s, a segment
// coupled to the segments sharing its nodes),
//     (diag(1 / a) + W) lambda = (EA_j (|e~_j| - l_j) + c_j u*_j) / (h EA_j + c_j),
// symmetric positive definite; its pattern is fixed, so the ordering and symbolic factorisation are
// done once and each step only refactors numerically. Linearising about the prediction keeps the
// lengthening of a turning segment (second order in its rotation per step) in |e~|, so a spinning
// thread is not stretched by the linearisation.
//
// Backward Euler damps what the step does not resolve: an axial mode of frequency omega loses
// a fraction ~ omega^2 h^2 / 2 of its amplitude per step (all of it for omega h >> 1), the modes
// slow enough to be seen keep theirs to within omega^2 h / 2 per second. The axial waves are not
// what the cameras see: docs/simulator.md gives the measured error on the flight cases.

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "libnetsim/model/model.h"

namespace netlab::netsim {

class AxialStep {
 public:
  // Prepares the pattern of the system for `model`'s segments that have axial stiffness or damping.
  explicit AxialStep(const Model& model);

  // Applies the axial impulses of one step of length h to `v` (the velocities after the explicit
  // kick), given the positions x at the start of the step. False when the system could not be
  // factorised or its solution is not finite (a state already blown up).
  bool Apply(const Model& model, double h, const std::vector<Vector3d>& x,
             std::vector<Vector3d>& v);

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
