#include "libreconstruct/geometry/point_motion.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

#include "calibration/ray.h"

namespace netlab::recon {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// The path (place at `time`, velocity) from the views' rays, each equation of the linear
// triangulation (RayEquations, scaled to unit norm) written for the place a + (s - time) v.
bool LinearPath(const calib::Rig& rig, const std::vector<TimedObservation>& views, double time,
                Vector6d* path) {
  Eigen::Matrix<double, Eigen::Dynamic, 6> a(2 * views.size(), 6);
  Eigen::VectorXd b(2 * views.size());
  int rows = 0;
  for (const TimedObservation& o : views) {
    Eigen::Matrix<double, 2, 4> ray;
    if (!calib::RayEquations(rig.cameras[o.view.camera], o.view.px, &ray)) continue;
    const double d = o.time - time;
    for (int j = 0; j < 2; ++j) {
      const Eigen::RowVector4d row = ray.row(j);
      const double norm = row.head<3>().norm();
      if (!(norm > 0)) continue;
      a.row(rows) << row.head<3>() / norm, d * row.head<3>() / norm;
      b[rows++] = -row[3] / norm;
    }
  }
  if (rows < 6) return false;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a.topRows(rows),
                                              Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  if (!(s[5] > 1e-9 * s[0])) return false;
  *path = svd.solve(b.head(rows));
  return path->allFinite();
}

// The normal equations of the pixel residuals at `path`: J^T J and J^T r; false behind a
// camera.
bool Normal(const calib::Rig& rig, const std::vector<TimedObservation>& views, double time,
            const Vector6d& path, Matrix6d* jtj, Vector6d* jtr) {
  jtj->setZero();
  jtr->setZero();
  for (const TimedObservation& o : views) {
    const double d = o.time - time;
    Eigen::Vector2d px;
    Eigen::Matrix<double, 2, 3> j3;
    if (!PixelAndJacobian(rig.cameras[o.view.camera], path.head<3>() + d * path.tail<3>(), &px,
                          &j3))
      return false;
    Eigen::Matrix<double, 2, 6> j;
    j << j3, d * j3;
    *jtj += j.transpose() * j;
    *jtr += j.transpose() * (px - o.view.px);
  }
  return true;
}

}  // namespace

PointEstimate FitConstantVelocity(const calib::Rig& rig, const std::vector<TimedObservation>& views,
                                  double time) {
  PointEstimate est;
  est.residual_px.assign(views.size(), std::nan(""));
  Vector6d path;
  if (views.size() < 3 || !LinearPath(rig, views, time, &path)) {
    est.why = "the views do not fix a straight path";
    return est;
  }
  Matrix6d jtj;
  Vector6d jtr;
  for (int iteration = 0; iteration < 10; ++iteration) {
    if (!Normal(rig, views, time, path, &jtj, &jtr)) {
      est.why = "the path passes behind a camera";
      return est;
    }
    const Vector6d step = -jtj.ldlt().solve(jtr);
    if (!step.allFinite()) break;
    path += step;
    if (step.head<3>().norm() <= 1e-12 * (1.0 + path.head<3>().norm())) break;
  }
  if (!Normal(rig, views, time, path, &jtj, &jtr)) {
    est.why = "the path passes behind a camera";
    return est;
  }
  // A direction the views do not see (one camera: how far along its rays) leaves the path
  // undetermined, whatever the solver returned.
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(jtj);
  const Vector6d lambda = eig.eigenvalues();  // ascending
  if (!(lambda[0] > 1e-10 * lambda[5])) {
    est.why = "the views do not fix a straight path";
    return est;
  }
  const Matrix6d covariance =
      eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  est.valid = true;
  est.position = path.head<3>();
  est.unit_covariance = covariance.topLeftCorner<3, 3>();
  for (size_t i = 0; i < views.size(); ++i) {
    const Observation at{views[i].view.camera, views[i].view.px};
    est.residual_px[i] =
        ReprojectionResidual(rig, at, path.head<3>() + (views[i].time - time) * path.tail<3>());
    est.inliers.push_back(static_cast<int>(i));
    est.sum_squares_px2 += est.residual_px[i] * est.residual_px[i];
  }
  est.rms_px = std::sqrt(est.sum_squares_px2 / static_cast<double>(views.size()));
  return est;
}

}  // namespace netlab::recon
