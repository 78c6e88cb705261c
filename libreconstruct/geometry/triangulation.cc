#include "libreconstruct/geometry/triangulation.h"

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration/ray.h"

namespace netlab::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Huber's rho of a squared residual norm s, and its weight rho'(s).
double HuberRho(double s, double h) { return s <= h * h ? s : 2.0 * h * std::sqrt(s) - h * h; }
double HuberWeight(double s, double h) { return s <= h * h ? 1.0 : h / std::sqrt(s); }

// Robust cost at `position`; +inf behind any camera.
double RobustCost(const calib::Rig& rig, const std::vector<Observation>& obs, double huber_px,
                  const Eigen::Vector3d& position) {
  double cost = 0.0;
  for (const Observation& o : obs) {
    Eigen::Vector2d px;
    if (!PixelAndJacobian(rig.cameras[o.camera], position, &px, nullptr))
      return std::numeric_limits<double>::infinity();
    cost += HuberRho((px - o.px).squaredNorm(), huber_px);
  }
  return cost;
}

std::vector<Observation> Subset(const std::vector<Observation>& obs, const std::vector<int>& idx) {
  std::vector<Observation> out;
  out.reserve(idx.size());
  for (int i : idx) out.push_back(obs[i]);
  return out;
}

// Refined point from the observations `idx`, with every observation's residual; false when the
// subset does not triangulate.
bool FitSubset(const calib::Rig& rig, const std::vector<Observation>& obs,
               const std::vector<int>& idx, const TriangulationOptions& options,
               Eigen::Vector3d* position, std::vector<double>* residual) {
  const std::vector<Observation> sub = Subset(obs, idx);
  if (!TriangulateLinear(rig, sub, position)) return false;
  if (!RefinePoint(rig, sub, options, position)) return false;
  residual->resize(obs.size());
  for (size_t i = 0; i < obs.size(); ++i)
    (*residual)[i] = ReprojectionResidual(rig, obs[i], *position);
  return true;
}

}  // namespace

bool PixelAndJacobian(const calib::Camera& camera, const Eigen::Vector3d& p_in_world,
                      Eigen::Vector2d* pixel, Eigen::Matrix<double, 2, 3>* wrt_world) {
  const Eigen::Matrix3d r = camera.cam_from_world.RotationMatrix();
  const Eigen::Vector3d p = r * p_in_world + camera.cam_from_world.translation;
  // Derivatives with respect to the camera-frame point only: three jet components instead of
  // the fifteen of calib::ProjectWithJacobian (intrinsics are constants here).
  using Jet = ceres::Jet<double, 3>;
  const auto params = camera.intrinsics.ToParameters();
  Jet k[calib::kNumIntrinsics], point[3], out[2];
  for (int i = 0; i < calib::kNumIntrinsics; ++i) k[i] = Jet(params[i]);
  for (int i = 0; i < 3; ++i) point[i] = Jet(p[i], i);
  if (!calib::ProjectPoint(k, point, out)) return false;
  Eigen::Matrix<double, 2, 3> wrt_cam;
  for (int row = 0; row < 2; ++row) {
    (*pixel)[row] = out[row].a;
    wrt_cam.row(row) = out[row].v.transpose();
  }
  if (wrt_world) *wrt_world = wrt_cam * r;
  return true;
}

std::optional<ProjectedPoint> ProjectAgreeingViews(const calib::Rig& rig, int camera,
                                                   const std::vector<Observation>& views,
                                                   const TriangulationOptions& options) {
  const PointEstimate e = TriangulatePoint(rig, views, options);
  if (!e.outliers.empty() || !UsableGeometry(e)) return std::nullopt;
  return ProjectEstimate(rig, camera, e);
}

double LargestSigmaM(const PointEstimate& estimate, double label_sigma_px) {
  if (!estimate.valid) return std::numeric_limits<double>::infinity();
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(estimate.unit_covariance,
                                                                        Eigen::EigenvaluesOnly)
                             .eigenvalues()[2];
  if (!std::isfinite(largest)) return std::numeric_limits<double>::infinity();
  return label_sigma_px * std::sqrt(std::max(largest, 0.0));
}

bool UsableGeometry(const PointEstimate& estimate, double max_unit_sigma_m) {
  return LargestSigmaM(estimate) <= max_unit_sigma_m;
}

std::optional<ProjectedPoint> ProjectEstimate(const calib::Rig& rig, int camera,
                                              const PointEstimate& estimate) {
  if (!estimate.valid) return std::nullopt;
  ProjectedPoint p;
  Eigen::Matrix<double, 2, 3> j;
  if (!PixelAndJacobian(rig.cameras[camera], estimate.position, &p.px, &j) || !p.px.allFinite())
    return std::nullopt;
  p.unit_covariance = j * estimate.unit_covariance * j.transpose();
  return p;
}

double ReprojectionResidual(const calib::Rig& rig, const Observation& observation,
                            const Eigen::Vector3d& position) {
  Eigen::Vector2d px;
  if (!PixelAndJacobian(rig.cameras[observation.camera], position, &px, nullptr)) return kNaN;
  return (px - observation.px).norm();
}

bool TriangulateLinear(const calib::Rig& rig, const std::vector<Observation>& observations,
                       Eigen::Vector3d* position) {
  // Each view's RayEquations, in normalised undistorted coordinates (so every view weighs alike
  // whatever its focal length), each scaled to unit norm.
  Eigen::Matrix<double, Eigen::Dynamic, 4> a(2 * observations.size(), 4);
  int rows = 0;
  for (const Observation& o : observations) {
    Eigen::Matrix<double, 2, 4> ray;
    if (!calib::RayEquations(rig.cameras[o.camera], o.px, &ray)) continue;
    for (int j = 0; j < 2; ++j) {
      const Eigen::RowVector4d row = ray.row(j);
      const double norm = row.norm();
      if (!(norm > 0)) continue;
      a.row(rows++) = row / norm;
    }
  }
  if (rows < 4) return false;
  // The world origin may be metres from the point; conditioning is fine for nets a few metres
  // across (normalised image coordinates are O(1) and translations O(m)).
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a.topRows(rows), Eigen::ComputeFullV);
  const Eigen::Vector4d x = svd.matrixV().col(3);
  if (!(std::abs(x[3]) > 1e-12 * x.head<3>().norm())) return false;  // at infinity
  *position = x.head<3>() / x[3];
  return position->allFinite();
}

bool RefinePoint(const calib::Rig& rig, const std::vector<Observation>& observations,
                 const TriangulationOptions& options, Eigen::Vector3d* position) {
  const double h = options.huber_px;
  Eigen::Vector3d p = *position;
  double cost = RobustCost(rig, observations, h, p);
  if (!std::isfinite(cost)) return false;
  double lambda = 1e-6;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const Observation& o : observations) {
      Eigen::Vector2d px;
      Eigen::Matrix<double, 2, 3> j;
      if (!PixelAndJacobian(rig.cameras[o.camera], p, &px, &j)) return false;
      const Eigen::Vector2d r = px - o.px;
      const double w = HuberWeight(r.squaredNorm(), h);
      jtj += w * j.transpose() * j;
      jtr += w * j.transpose() * r;
    }
    // Levenberg-Marquardt on the iteratively reweighted normal equations.
    bool improved = false;
    for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
      Eigen::Matrix3d damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::Vector3d step = -damped.ldlt().solve(jtr);
      if (!step.allFinite()) return false;
      const Eigen::Vector3d trial = p + step;
      const double trial_cost = RobustCost(rig, observations, h, trial);
      if (trial_cost <= cost) {
        const bool converged =
            step.norm() <= 1e-12 * (1.0 + p.norm()) || cost - trial_cost <= 1e-14 * (1.0 + cost);
        p = trial;
        cost = trial_cost;
        lambda = std::max(lambda * 0.1, 1e-12);
        improved = true;
        if (converged) {
          *position = p;
          return true;
        }
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;  // at a minimum to the precision of the cost
  }
  *position = p;
  return p.allFinite();
}

Eigen::Matrix3d PointInformation(const calib::Rig& rig, const std::vector<int>& cameras,
                                 const Eigen::Vector3d& position) {
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  for (int c : cameras) {
    Eigen::Vector2d px;
    Eigen::Matrix<double, 2, 3> j;
    if (PixelAndJacobian(rig.cameras[c], position, &px, &j)) info += j.transpose() * j;
  }
  return info;
}

PointEstimate TriangulatePoint(const calib::Rig& rig, const std::vector<Observation>& observations,
                               const TriangulationOptions& options) {
  PointEstimate est;
  const int n = static_cast<int>(observations.size());
  if (n < 2) {
    est.why = "fewer than two views";
    est.residual_px.assign(observations.size(), kNaN);
    return est;
  }
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  Eigen::Vector3d p;
  std::vector<double> residual;
  const double threshold = options.outlier_threshold_px;
  auto within = [&](const std::vector<double>& r) {
    std::vector<int> in;
    for (int i = 0; i < n; ++i)
      if (r[i] <= threshold) in.push_back(i);
    return in;
  };
  const bool fits_all = FitSubset(rig, observations, all, options, &p, &residual);
  std::vector<int> inliers = fits_all ? within(residual) : std::vector<int>{};
  if (static_cast<int>(inliers.size()) < n) {
    if (n == 2) {
      est.why = fits_all ? "the two views disagree (cannot tell which is wrong)"
                         : "the two views do not triangulate";
      est.outliers = all;
      est.residual_px = fits_all ? residual : std::vector<double>(n, kNaN);
      return est;
    }
    // Consensus of pairs: the set of views that the most pairs' points explain. It must be the
    // only largest one: a mislabel that happens to lie on the epipolar line of one good view
    // forms a consistent pair too, and then nothing says which pair is right.
    std::vector<std::vector<int>> largest;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b) {
        Eigen::Vector3d q;
        std::vector<double> r;
        if (!FitSubset(rig, observations, {a, b}, options, &q, &r)) continue;
        const std::vector<int> in = within(r);
        if (in.size() < 2) continue;
        if (!largest.empty() && in.size() < largest[0].size()) continue;
        if (!largest.empty() && in.size() > largest[0].size()) largest.clear();
        if (std::find(largest.begin(), largest.end(), in) == largest.end()) largest.push_back(in);
      }
    if (largest.empty()) {
      est.why = "no two views agree within the outlier threshold";
      est.outliers = all;
      est.residual_px.assign(n, kNaN);
      return est;
    }
    if (largest.size() > 1) {
      // Report every view that some largest set leaves out: one of them is wrong.
      est.why = "ambiguous: " + std::to_string(largest.size()) + " sets of " +
                std::to_string(largest[0].size()) +
                " views agree with each other but not "
                "together (cannot tell which view is wrong)";
      for (int i = 0; i < n; ++i)
        for (const auto& set : largest)
          if (std::find(set.begin(), set.end(), i) == set.end()) {
            est.outliers.push_back(i);
            break;
          }
      est.residual_px.assign(n, kNaN);
      return est;
    }
    inliers = largest[0];
    // Refit on the consensus, then take every view the refit explains.
    if (!FitSubset(rig, observations, inliers, options, &p, &residual)) {
      est.why = "the agreeing views do not triangulate";
      est.outliers = all;
      est.residual_px.assign(n, kNaN);
      return est;
    }
    const std::vector<int> refit_in = within(residual);
    if (refit_in.size() > inliers.size() &&
        FitSubset(rig, observations, refit_in, options, &p, &residual))
      inliers = within(residual);
    if (inliers.size() < 2) {
      est.why = "no two views agree within the outlier threshold";
      est.outliers = all;
      est.residual_px = residual;
      return est;
    }
  }
  est.valid = true;
  est.position = p;
  est.inliers = inliers;
  for (int i = 0; i < n; ++i)
    if (std::find(inliers.begin(), inliers.end(), i) == inliers.end()) est.outliers.push_back(i);
  est.residual_px = residual;
  std::vector<int> cameras;
  for (int i : inliers) {
    cameras.push_back(observations[i].camera);
    est.sum_squares_px2 += residual[i] * residual[i];
  }
  est.rms_px = std::sqrt(est.sum_squares_px2 / static_cast<double>(inliers.size()));
  // Rays that do not cross (one centre seen twice, or a point on the baseline) leave a direction
  // without information: the point is not determined, whatever the solver returned.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(PointInformation(rig, cameras, p));
  const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
  if (!(lambda[0] > 1e-10 * lambda[2])) {
    est.valid = false;
    est.why = "degenerate view geometry (the rays do not cross)";
    return est;
  }
  est.unit_covariance =
      eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return est;
}

}  // namespace netlab::recon
