#include "libreconstruct/geometry/rig_refinement.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "libreconstruct/geometry/cost_functors.h"

namespace netlab::recon {
namespace {

void Progress(const SequenceOptions& options, double fraction) {
  options.progress.Report("rig stages", 2 * fraction, 2);
  options.progress.ThrowIfCancelled();
}

// One observation of a point: a residual of the rig problem.
struct Entry {
  size_t point;
  Observation observation;
};

// The sum of the squared residuals `r2` of the entries in use, and their number.
struct UsedSum {
  double ss = 0.0;
  int64_t n = 0;
};
UsedSum SumOverUsed(const std::vector<double>& r2, const std::vector<char>& use) {
  UsedSum sum;
  for (size_t e = 0; e < r2.size(); ++e) {
    if (!use[e]) continue;
    sum.ss += r2[e];
    ++sum.n;
  }
  return sum;
}

// Where the parameters of the moving cameras sit among the Jacobian's columns: first the points'
// (3 each), then per camera its rotation (3, tangent) and centre (3, or 2 on the sphere).
struct CameraColumns {
  ceres::Problem::EvaluateOptions eval;              // the parameter blocks in that order
  int points = 0;                                    // points in the problem
  int point_cols = 0;                                // 3 x points
  std::vector<int> rot_col, centre_col, centre_dim;  // per camera, -1 / 0 when not in it
  int m = 0;                                         // camera columns in all
};

// The rig adjustment's parameters and the observations they are fit to. Camera i's pose is Q(i)
// (cam_from_world rotation, Eigen order x, y, z, w) and C(i) (its centre in the world; for
// camera 1 the unit direction from camera 0's centre c0_, the distance held at baseline_).
class RigProblem {
 public:
  RigProblem(const calib::Rig& rig, const std::vector<RigPoint>& rig_points,
             const SequenceOptions& options, const TriangulationOptions& triangulation);

  size_t size() const { return entries_.size(); }
  size_t points() const { return points_.size(); }
  // Squared residual (px^2) of every entry at the current parameters; infinity where a point is
  // behind its camera.
  std::vector<double> SquaredResiduals() const;
  // Solves the poses and points on the entries in `use` (Huber-weighted when `robust`); returns
  // the problem, for the uncertainty at its solution.
  std::unique_ptr<ceres::Problem> Solve(const std::vector<char>& use, bool robust, int iterations);
  // Standard deviations of the cameras' rotation (deg) and centre (mm), into result's
  // rig_rotation_sigma_deg and rig_center_sigma_mm, for residual variance sigma2 (px^2).
  void Uncertainty(ceres::Problem& problem, double sigma2, SequenceResult* result);
  // Each camera's change from its pose in *rig into result; the new poses into *rig if `adopt`.
  void CompareAndAdopt(bool adopt, calib::Rig* rig, SequenceResult* result) const;

 private:
  MovingCameraReprojection Reprojection(const Observation& ob) const;
  CameraColumns LayOutColumns(const ceres::Problem& problem);
  static Eigen::MatrixXd ReducedCameraSystem(ceres::Problem& problem, const CameraColumns& columns);

  const calib::Rig& rig_;
  const SequenceOptions& o_;
  const TriangulationOptions& tri_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<Entry> entries_;
  Eigen::Vector3d c0_;
  double baseline_;
  // The poses in one buffer, every rotation (4 each) before every centre (3 each): the order
  // of the cameras' blocks in the solve (ceres::ParameterBlockOrdering sorts a group by address)
  // and so its rounding do not depend on where the heap puts them.
  int cams_;
  std::vector<double> poses_;
  double* Q(int i) { return poses_.data() + 4 * i; }
  double* C(int i) { return poses_.data() + 4 * cams_ + 3 * i; }
  const double* Q(int i) const { return poses_.data() + 4 * i; }
  const double* C(int i) const { return poses_.data() + 4 * cams_ + 3 * i; }
  ceres::EigenQuaternionManifold quaternion_;
  ceres::SphereManifold<3> sphere_;
};

// The entries point by point, and every camera's pose from the rig.
RigProblem::RigProblem(const calib::Rig& rig, const std::vector<RigPoint>& rig_points,
                       const SequenceOptions& options, const TriangulationOptions& triangulation)
    : rig_(rig), o_(options), tri_(triangulation) {
  for (const RigPoint& point : rig_points) {
    for (const Observation& ob : point.observations) entries_.push_back({points_.size(), ob});
    points_.push_back(point.position);
  }
  cams_ = static_cast<int>(rig_.cameras.size());
  c0_ = rig_.cameras[0].Center();
  baseline_ = (rig_.cameras[1].Center() - c0_).norm();
  poses_.resize(7 * static_cast<size_t>(cams_));
  for (int i = 0; i < cams_; ++i) {
    const Eigen::Quaterniond r = rig_.cameras[i].cam_from_world.rotation;
    Eigen::Map<Eigen::Vector4d>(Q(i)) = Eigen::Vector4d(r.x(), r.y(), r.z(), r.w());
    Eigen::Vector3d centre = rig_.cameras[i].Center();
    if (i == 1) centre = (centre - c0_) / baseline_;
    Eigen::Map<Eigen::Vector3d>(C(i)) = centre;
  }
}

MovingCameraReprojection RigProblem::Reprojection(const Observation& ob) const {
  MovingCameraReprojection f;
  f.px_ = ob.px;
  f.k_ = rig_.cameras[ob.camera].intrinsics.ToParameters();
  if (ob.camera == 1) f.scaled_ = true, f.base_ = c0_, f.length_ = baseline_;
  return f;
}

std::vector<double> RigProblem::SquaredResiduals() const {
  std::vector<double> out(entries_.size());
  for (size_t e = 0; e < entries_.size(); ++e) {
    MovingCameraReprojection f = Reprojection(entries_[e].observation);
    double r[2];
    const int cam = entries_[e].observation.camera;
    out[e] = f(Q(cam), C(cam), points_[entries_[e].point].data(), r)
                 ? r[0] * r[0] + r[1] * r[1]
                 : std::numeric_limits<double>::infinity();
  }
  return out;
}

std::unique_ptr<ceres::Problem> RigProblem::Solve(const std::vector<char>& use, bool robust,
                                                  int iterations) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  auto problem_ptr = std::make_unique<ceres::Problem>(problem_options);
  ceres::Problem& problem = *problem_ptr;
  // The residuals in use; the points eliminated first (group 0), the cameras after (Schur).
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (size_t e = 0; e < entries_.size(); ++e) {
    if (!use[e]) continue;
    const int cam = entries_[e].observation.camera;
    double* p = points_[entries_[e].point].data();
    problem.AddResidualBlock(
        MovingCameraReprojection::Create(Reprojection(entries_[e].observation)),
        robust ? new ceres::HuberLoss(tri_.huber_px) : nullptr, Q(cam), C(cam), p);
    ordering->AddElementToGroup(p, 0);
  }
  // The gauge: camera 0 held, camera 1's centre on the sphere about it.
  for (int i = 0; i < cams_; ++i) {
    if (!problem.HasParameterBlock(Q(i))) continue;
    problem.SetManifold(Q(i), &quaternion_);
    if (i == 1) problem.SetManifold(C(i), &sphere_);
    if (i == 0) {
      problem.SetParameterBlockConstant(Q(i));
      problem.SetParameterBlockConstant(C(i));
    }
    ordering->AddElementToGroup(Q(i), 1);
    ordering->AddElementToGroup(C(i), 1);
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.linear_solver_ordering.reset(ordering);
  solver.num_threads = std::max(1, o_.threads);
  solver.max_num_iterations = iterations;
  solver.function_tolerance = 1e-10;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return problem_ptr;
}

CameraColumns RigProblem::LayOutColumns(const ceres::Problem& problem) {
  CameraColumns columns;
  for (size_t i = 0; i < points_.size(); ++i)
    if (problem.HasParameterBlock(points_[i].data())) {
      columns.eval.parameter_blocks.push_back(points_[i].data());
      ++columns.points;
    }
  columns.point_cols = 3 * columns.points;
  columns.rot_col.assign(cams_, -1);
  columns.centre_col.assign(cams_, -1);
  columns.centre_dim.assign(cams_, 0);
  for (int i = 1; i < cams_; ++i) {
    if (!problem.HasParameterBlock(Q(i))) continue;
    columns.eval.parameter_blocks.push_back(Q(i));
    columns.rot_col[i] = columns.m, columns.m += 3;
    columns.eval.parameter_blocks.push_back(C(i));
    columns.centre_dim[i] = i == 1 ? 2 : 3;
    columns.centre_col[i] = columns.m, columns.m += columns.centre_dim[i];
  }
  return columns;
}

// The reduced camera system S = J_c'J_c - sum_p (J_p'J_c)' (J_p'J_p)^-1 (J_p'J_c) of the
// least-squares problem at its solution (points eliminated), m x m.
Eigen::MatrixXd RigProblem::ReducedCameraSystem(ceres::Problem& problem,
                                                const CameraColumns& columns) {
  const int m = columns.m, point_cols = columns.point_cols;
  ceres::CRSMatrix jac;
  double cost = 0.0;
  problem.Evaluate(columns.eval, &cost, nullptr, nullptr, &jac);
  // Per row of the Jacobian: its camera part into J_c'J_c, its point part into the point's
  // J_p'J_p and J_p'J_c.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, m);
  std::vector<Eigen::Matrix3d> cpp(columns.points, Eigen::Matrix3d::Zero());
  std::vector<Eigen::MatrixXd> bpc(columns.points, Eigen::MatrixXd::Zero(3, m));
  for (int row = 0; row < jac.num_rows; ++row) {
    Eigen::Vector3d jp = Eigen::Vector3d::Zero();
    Eigen::VectorXd jc = Eigen::VectorXd::Zero(m);
    int point = -1;
    for (int i = jac.rows[row]; i < jac.rows[row + 1]; ++i) {
      const int col = jac.cols[i];
      if (col < point_cols)
        point = col / 3, jp[col % 3] = jac.values[i];
      else
        jc[col - point_cols] = jac.values[i];
    }
    a += jc * jc.transpose();
    if (point < 0) continue;
    cpp[point] += jp * jp.transpose();
    bpc[point] += jp * jc.transpose();
  }
  // The points eliminated (Schur complement).
  for (size_t p = 0; p < cpp.size(); ++p) a -= bpc[p].transpose() * cpp[p].ldlt().solve(bpc[p]);
  return a;
}

// The covariance of the camera parameters is sigma2 S^-1 (S the reduced camera system).
void RigProblem::Uncertainty(ceres::Problem& problem, double sigma2, SequenceResult* result) {
  result->rig_rotation_sigma_deg.assign(cams_, 0.0);
  result->rig_center_sigma_mm.assign(cams_, 0.0);
  const CameraColumns columns = LayOutColumns(problem);
  const int m = columns.m;
  if (m == 0) return;
  const Eigen::MatrixXd a = ReducedCameraSystem(problem, columns);
  const Eigen::MatrixXd cov = sigma2 * a.ldlt().solve(Eigen::MatrixXd::Identity(m, m));
  // Per camera the root of the trace of its blocks: rotation and centre.
  const auto& rot_col = columns.rot_col;
  const auto& centre_col = columns.centre_col;
  const auto& centre_dim = columns.centre_dim;
  for (int i = 1; i < cams_; ++i) {
    if (rot_col[i] < 0) continue;
    // EigenQuaternionManifold's tangent is half the rotation vector.
    const double rot =
        2.0 * std::sqrt(std::max(0.0, cov.block<3, 3>(rot_col[i], rot_col[i]).trace()));
    const double centre = std::sqrt(std::max(
        0.0, cov.block(centre_col[i], centre_col[i], centre_dim[i], centre_dim[i]).trace()));
    result->rig_rotation_sigma_deg[i] = rot * 180.0 / M_PI;
    result->rig_center_sigma_mm[i] = 1e3 * centre * (i == 1 ? baseline_ : 1.0);
  }
}

void RigProblem::CompareAndAdopt(bool adopt, calib::Rig* rig, SequenceResult* result) const {
  for (int i = 1; i < cams_; ++i) {
    const Eigen::Quaterniond r =
        Eigen::Quaterniond(Q(i)[3], Q(i)[0], Q(i)[1], Q(i)[2]).normalized();
    Eigen::Vector3d centre(C(i)[0], C(i)[1], C(i)[2]);
    if (i == 1) centre = c0_ + baseline_ * centre;
    calib::Camera& cam = rig->cameras[i];
    result->rig_rotation_change_deg[i] =
        cam.cam_from_world.rotation.angularDistance(r) * 180.0 / M_PI;
    result->rig_center_change_mm[i] = (cam.Center() - centre).norm() * 1e3;
    if (adopt) cam.cam_from_world = calib::Rigid3d(r, -(r * centre));
  }
}

}  // namespace

void RefineRig(const std::vector<RigPoint>& points, const SequenceOptions& options,
               const TriangulationOptions& triangulation, calib::Rig* rig, SequenceResult* result) {
  const int cams = static_cast<int>(rig->cameras.size());
  if (cams < 2) return;
  RigProblem problem(*rig, points, options, triangulation);
  if (problem.size() == 0) return;
  // Stage 1: Huber-weighted, every observation.
  Progress(options, 0.0);
  std::vector<char> use(problem.size(), 1);
  const std::vector<double> before = problem.SquaredResiduals();
  problem.Solve(use, true, 10);
  Progress(options, 0.5);
  // Stage 2: least squares over the observations within the outlier threshold.
  const double threshold2 = triangulation.outlier_threshold_px * triangulation.outlier_threshold_px;
  std::vector<double> r2 = problem.SquaredResiduals();
  for (size_t e = 0; e < problem.size(); ++e) use[e] = r2[e] <= threshold2;
  const auto solved = problem.Solve(use, false, 30);
  r2 = problem.SquaredResiduals();
  // The RMS before and after, over the observations of stage 2.
  const UsedSum sum_before = SumOverUsed(before, use), sum_after = SumOverUsed(r2, use);
  const int64_t n = sum_after.n;
  result->rig_rms_before_px = std::sqrt(sum_before.ss / std::max<int64_t>(n, 1));
  result->rig_rms_after_px = std::sqrt(sum_after.ss / std::max<int64_t>(n, 1));
  result->rig_rotation_change_deg.assign(cams, 0.0);
  result->rig_center_change_mm.assign(cams, 0.0);
  // How well the sequence determines the cameras: a net at one place, or flat and small,
  // leaves a camera's position traded against its turn, and adopting such a rig would make
  // every point worse. Then the calibrated rig is kept, and said so.
  const double dof = 2.0 * static_cast<double>(n) - 3.0 * static_cast<double>(problem.points());
  const double sigma2 = dof > 0 ? sum_after.ss / dof : 1.0;
  problem.Uncertainty(*solved, sigma2, result);
  double worst_centre = 0.0, worst_rotation = 0.0;
  for (int i = 1; i < cams; ++i) {
    worst_centre = std::max(worst_centre, result->rig_center_sigma_mm[i]);
    worst_rotation = std::max(worst_rotation, result->rig_rotation_sigma_deg[i]);
  }
  result->rig_adjusted = worst_centre <= options.rig_max_center_sigma_mm &&
                         worst_rotation <= options.rig_max_rotation_sigma_deg;
  problem.CompareAndAdopt(result->rig_adjusted, rig, result);
}

}  // namespace netlab::recon
