#include "libnetsim/characterization/heavy_cantilever.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace netlab::netsim {
namespace {

// The chain's energy per unit weight and its derivatives (see the header).
struct Chain {
  double alpha, h;
  int n;

  double Weight(int k) const { return n - k - 0.5; }  // centres beyond joint k, in segments

  double Energy(const std::vector<double>& theta) const {
    double e = alpha * theta[0] * theta[0] / h;
    for (int j = 1; j < n; ++j) e += alpha * std::pow(theta[j] - theta[j - 1], 2) / (2 * h);
    for (int k = 0; k < n; ++k) e -= h * h * Weight(k) * std::sin(theta[k]);
    return e;
  }
  // Gradient g and the tridiagonal Hessian (diagonal d, off-diagonal o: o[j] couples j, j + 1).
  void Derivatives(const std::vector<double>& theta, std::vector<double>* g, std::vector<double>* d,
                   std::vector<double>* o) const {
    g->assign(n, 0.0);
    d->assign(n, 0.0);
    o->assign(std::max(n - 1, 0), -alpha / h);
    (*g)[0] = 2 * alpha * theta[0] / h;
    (*d)[0] = 2 * alpha / h;
    for (int j = 1; j < n; ++j) {
      const double bend = alpha * (theta[j] - theta[j - 1]) / h;
      (*g)[j] += bend, (*g)[j - 1] -= bend;
      (*d)[j] += alpha / h, (*d)[j - 1] += alpha / h;
    }
    for (int k = 0; k < n; ++k) {
      (*g)[k] -= h * h * Weight(k) * std::cos(theta[k]);
      (*d)[k] += h * h * Weight(k) * std::sin(theta[k]);
    }
  }
};

// Solves the symmetric tridiagonal system (d, o) x = b (Thomas); b is overwritten with x.
void SolveTridiagonal(std::vector<double> d, const std::vector<double>& o, std::vector<double>* b) {
  const int n = static_cast<int>(d.size());
  for (int i = 1; i < n; ++i) {
    const double m = o[i - 1] / d[i - 1];
    d[i] -= m * o[i - 1];
    (*b)[i] -= m * (*b)[i - 1];
  }
  (*b)[n - 1] /= d[n - 1];
  for (int i = n - 2; i >= 0; --i) (*b)[i] = ((*b)[i] - o[i] * (*b)[i + 1]) / d[i];
}

// Newton steps with backtracking on the energy, from straight.
bool Minimise(const Chain& chain, std::vector<double>* theta) {
  std::vector<double> g, d, o;
  for (int iteration = 0; iteration < 200; ++iteration) {
    chain.Derivatives(*theta, &g, &d, &o);
    // Where gravity's curvature is negative (theta > pi) the Hessian may be indefinite: keep
    // the diagonal positive so the step stays a descent direction.
    for (double& di : d) di = std::max(di, 1e-12);
    std::vector<double> step(g);
    SolveTridiagonal(d, o, &step);
    const double e0 = chain.Energy(*theta);
    // At most 0.2 rad per joint and iteration: from straight, a heavy thread's full Newton step
    // overshoots past the vertical into the other, spurious minimum (the thread hanging back up).
    double longest = 0.0;
    for (double si : step) longest = std::max(longest, std::abs(si));
    double t = std::min(1.0, 0.2 / longest), largest = 0.0;
    std::vector<double> trial(*theta);
    for (int k = 0; k < 60; ++k, t *= 0.5) {
      for (int j = 0; j < chain.n; ++j) trial[j] = (*theta)[j] - t * step[j];
      if (chain.Energy(trial) <= e0) break;
    }
    for (int j = 0; j < chain.n; ++j) largest = std::max(largest, std::abs(trial[j] - (*theta)[j]));
    *theta = trial;
    if (largest < 1e-13) return true;
  }
  return false;
}

}  // namespace

CantileverShape SolveHeavyCantilever(double length, double alpha, int segments) {
  const Chain chain{alpha, length / segments, segments};
  CantileverShape shape;
  shape.theta.assign(segments, 0.0);
  shape.converged = Minimise(chain, &shape.theta);
  shape.points.push_back(Eigen::Vector2d::Zero());
  for (int j = 0; j < segments; ++j)
    shape.points.push_back(
        shape.points.back() +
        chain.h * Eigen::Vector2d(std::cos(shape.theta[j]), -std::sin(shape.theta[j])));
  return shape;
}

CantileverMode FirstMode(const CantileverShape& shape, double length, double alpha,
                         double gravity) {
  const int n = static_cast<int>(shape.theta.size());
  const Chain chain{alpha, length / n, n};
  const double h = chain.h;
  std::vector<double> g, d, o;
  chain.Derivatives(shape.theta, &g, &d, &o);
  // Stiffness per unit weight: bending part and the whole; mass per unit linear density (the
  // centres' translations plus each segment's own rotary inertia h^3/12).
  Eigen::MatrixXd bend = Eigen::MatrixXd::Zero(n, n), stiffness = Eigen::MatrixXd::Zero(n, n),
                  mass(n, n);
  for (int j = 0; j < n; ++j) {
    stiffness(j, j) = d[j];
    bend(j, j) = d[j] - h * h * chain.Weight(j) * std::sin(shape.theta[j]);
    if (j + 1 < n)
      bend(j, j + 1) = bend(j + 1, j) = stiffness(j, j + 1) = stiffness(j + 1, j) = o[j];
    for (int k = j; k < n; ++k) {
      const double shared = (j == k) ? n - k - 0.75 : n - k - 0.5;
      mass(j, k) = mass(k, j) = h * h * h * std::cos(shape.theta[j] - shape.theta[k]) * shared;
    }
    mass(j, j) += h * h * h / 12.0;
  }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(stiffness, mass);
  const Eigen::VectorXd phi = solver.eigenvectors().col(0);
  CantileverMode mode;
  mode.omega = std::sqrt(gravity * solver.eigenvalues()[0]);
  mode.bending_fraction = phi.dot(bend * phi) / phi.dot(stiffness * phi);
  return mode;
}

double PeirceBendStiffness(double length, const Eigen::Vector2d& tip, double linear_density,
                           double gravity) {
  const double chord = std::atan2(-tip.y(), tip.x());
  return linear_density * gravity * std::pow(length, 3) * std::cos(chord / 2) /
         (8 * std::tan(chord));
}

double SignedDistanceToCurve(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity(), signed_best = 0.0;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const Eigen::Vector2d a = points[i], u = points[i + 1] - a;
    const double s = std::clamp((p - a).dot(u) / u.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector2d r = p - (a + s * u);
    if (r.norm() < best) {
      best = r.norm();
      signed_best = (u.x() * r.y() - u.y() * r.x() >= 0) ? best : -best;
    }
  }
  return signed_best;
}

}  // namespace netlab::netsim
