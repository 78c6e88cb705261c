#pragma once
// The large-deflection equilibrium of a clamped thread under its own weight (the heavy elastica)
// and its first small oscillation about it: the model the cantilever test is fitted with.
//
// The thread (length L, inextensible, unshearable: the Kirchhoff rod the simulator converges to)
// is a planar chain of n rigid segments of length h = L/n at angles theta_j below the horizontal,
// its mass at the segments' centres, bending concentrated at the joints as in the simulator
// (docs/simulator.md: the clamp's joint over half a segment). Per unit weight mu g its energy is
//
//   V / (mu g) = alpha [theta_0^2 / h + sum_j (theta_j - theta_{j-1})^2 / (2h)] + sum_j h y_j
//
// with y_j the centres' heights and alpha = EI / (mu g) (m^3) the one parameter of the shape:
// the equilibrium depends on EI, mu and g only through it. The minimum (Newton with a
// backtracking line search; the Hessian is tridiagonal and positive definite for 0 <= theta < pi)
// converges to the elastica as O(1/n^2).
//
// Peirce's closed form (the textbook cantilever formula, 1930), EI = mu g L^3 cos(theta/2) /
// (8 tan theta) with theta the chord's angle below the horizontal, is what the test replaces:
// at a 1 mm Nylon thread's deflections it is off by tens of per cent (Lammens et al. 2014).

#include <Eigen/Core>
#include <vector>

namespace netlab::netsim {

struct CantileverShape {
  std::vector<double> theta;            // per segment, rad below the horizontal
  std::vector<Eigen::Vector2d> points;  // the n + 1 joints from the clamp (0, 0), x out, y up, m
  bool converged = false;
};

// The equilibrium for alpha = EI / (mu g) (m^3), length L (m), `segments` segments.
CantileverShape SolveHeavyCantilever(double length, double alpha, int segments = 200);

// The first mode of small oscillation about an equilibrium: omega (rad/s) and the fraction of
// its stiffness that is bending, beta = phi^T K_bend phi / phi^T K phi (the rest is gravity's).
// A Kelvin-Voigt bending damping c_b damps it at the rate sigma = (c_b / EI) beta omega^2 / 2
// (its damping matrix is (c_b/EI) K_bend); the inverse maps a measured decay to c_b.
struct CantileverMode {
  double omega = 0;
  double bending_fraction = 0;
};
CantileverMode FirstMode(const CantileverShape& shape, double length, double alpha, double gravity);

// Peirce's bending stiffness EI (N m^2) from the tip's position (m, from the clamp, y up).
double PeirceBendStiffness(double length, const Eigen::Vector2d& tip, double linear_density,
                           double gravity);

// Signed distance (m) of a point to the polyline `points` (positive above it, on the left going
// from the clamp out).
double SignedDistanceToCurve(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& p);

}  // namespace netlab::netsim
