#pragma once
// The implicit half of the `implicit` integrator: stretching (and its damping) along each segment,
// solved as one sparse linear system per step, so the axial wave (c = sqrt(EA / mu) ~ 1300 m/s in
// Nylon, a period of ~20 us in a 2 cm segment) no longer limits the step.
//
// One stage (Apply), after the explicit kick v* = v + h M^-1 f (f without the axial force):
//   predicted positions  x~ = x + h v*,   per segment  e~ = x~_b - x~_a,
//   t = the direction of e0 + e~ (the stage's midpoint, e0 = x_b - x_a), or under Step e~ / |e~|
//   (the direction predicted for the end of the stage),
//   relative axial speed u_j = t_j . (v_b - v_a)   (J v, J the s x 3n matrix of these rows),
//   tension at the end of the stage, linearised about the prediction (one Newton step of backward
//   Euler from the explicit predictor):
//     N_j = (EA_j / l_j) (|e~_j| - l_j + h (u_j - u*_j)) + (c_j / l_j) u_j,
//   impulses lambda = h N on the new velocities  v+ = v* - M^-1 J^T lambda.
// Eliminating v+ leaves, with a_j = h (h EA_j + c_j) / l_j and W = J M^-1 J^T (s x s, a segment
// coupled to the segments sharing its nodes),
//     (diag(1 / a) + W) lambda = (EA_j (|e~_j| - l_j) + c_j u*_j) / (h EA_j + c_j),
// symmetric positive definite; its pattern is fixed, so the ordering and symbolic factorisation are
// done once and each stage only refactors numerically. Linearising about the prediction keeps the
// lengthening of a turning segment (second order in its rotation per step) in |e~|, so a spinning
// thread is not stretched by the linearisation.
//
// The step (Step): the stretching and the drift x' = v, M v' = -J^T N over h, from the kicked
// velocities, by the two-stage singly diagonally implicit Runge-Kutta method (Alexander's SDIRK2,
// gamma = 1 - 1/sqrt(2)), each stage one Apply of length gamma h:
//   V1 = v* - gamma h M^-1 J^T N(x + gamma h V1, V1)
//   V2 = v* + (1 - gamma) h A1 - gamma h M^-1 J^T N(x + (1 - gamma) h V1 + gamma h V2, V2),
//        A1 = (V1 - v*) / (gamma h)
//   v+ = V2,  x+ = x + h ((1 - gamma) V1 + gamma V2).
// Second order and L-stable. On a spring of frequency omega the step keeps a mode it resolves: its
// damping ratio is about 0.004 (omega h)^3 (3e-5 at omega h = 0.2, the corner masses bouncing on
// the flight nets' thread), where backward Euler's is omega h / 2 (0.1: an axial damping of
// h EA, ~1200 times the Nylon's own, that took 90 % of Net A's response to a 4x bending
// stiffness, docs/simulator.md). The axial waves it does not resolve (omega h >> 1) lose their
// amplitude within a step or two, as under backward Euler: a step that keeps them (Newmark,
// gamma 0.52: 3.4 % per step) let a 5 x 5 net at 2 segments per link and a 2.8 ms step store
// 0.095 J of elastic energy where the explicit step stores at most 2e-4 J.
// The tension acts along the segment's direction predicted for the end of each stage, so a taut
// thread's lateral (string) vibration is implicit in each stage as well: along the midpoint of the
// stage instead, the paper's net dropped onto a sphere at 5 m/s blew up (implicit_test), and a
// flying 5 x 5 net strayed 5.1 mm from the explicit step's paths in 0.2 s (1.2 mm along the end).

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

#include "libnetsim/model/model.h"

namespace netlab::netsim {

class AxialStep {
 public:
  // Prepares the pattern of the system for `model`'s segments that have axial stiffness or damping.
  explicit AxialStep(const Model& model);

  // gamma of the two-stage step.
  static constexpr double kGamma = 0.29289321881345248;  // 1 - 1/sqrt(2)

  // One step of length h (above): x the positions at its start, v the velocities after the
  // explicit kick, replaced by those at its end; drift receives the mean velocity over the step
  // (the positions at its end are x + h drift). False as Apply.
  bool Step(const Model& model, double h, const std::vector<Vector3d>& x, std::vector<Vector3d>& v,
            std::vector<Vector3d>& drift);

  // One backward Euler stage of length h (above): the axial impulses applied to `v` (the
  // velocities after the explicit kick), given the positions x at its start, along each segment's
  // midpoint direction or (end_direction) its predicted end direction. False when the system
  // could not be factorised or its solution is not finite (a state already blown up).
  bool Apply(const Model& model, double h, const std::vector<Vector3d>& x, std::vector<Vector3d>& v,
             bool end_direction = false);

  // Segments solved (those with EA or c_s > 0).
  int size() const { return static_cast<int>(segments_.size()); }

  // Per node, the geometric (string) stiffness of the last stage's tensions, sum of 2 |N| / |e|
  // over its segments (N/m): the transverse stiffness the tension gives the explicit part of the
  // step.
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
  std::vector<double> geometric_;        // per node
  std::vector<Vector3d> kicked_, base_;  // Step's scratch: v*, and the second stage's start
};

}  // namespace netlab::netsim
