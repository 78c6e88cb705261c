#include "libreconstruct/geometry/bundle_adjust.h"

#include <algorithm>
#include <atomic>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <thread>

#include <Eigen/Cholesky>
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "common/yaml_util.h"

namespace netlab::recon {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Runs body(i) for i in [0, n) on `threads` threads (contiguous chunks taken in turn).
void ParallelFor(int n, int threads, const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  constexpr int kChunk = 16;
  auto work = [&] {
    for (int start = next.fetch_add(kChunk); start < n; start = next.fetch_add(kChunk))
      for (int i = start; i < std::min(n, start + kChunk); ++i) body(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
}

// Reprojection residual of a world point in a camera held fixed (px).
struct FixedCameraReprojection {
  FixedCameraReprojection(const calib::Camera& camera, const Eigen::Vector2d& px) : px_(px) {
    k_ = camera.intrinsics.ToParameters();
    const Eigen::Matrix3d r = camera.cam_from_world.RotationMatrix();
    for (int i = 0; i < 9; ++i) r_[i] = r(i / 3, i % 3);
    for (int i = 0; i < 3; ++i) t_[i] = camera.cam_from_world.translation[i];
  }
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    T pc[3], k[calib::kNumIntrinsics], pixel[2];
    for (int i = 0; i < 3; ++i)
      pc[i] = T(r_[3 * i]) * p[0] + T(r_[3 * i + 1]) * p[1] + T(r_[3 * i + 2]) * p[2] + T(t_[i]);
    for (int i = 0; i < calib::kNumIntrinsics; ++i) k[i] = T(k_[i]);
    if (!calib::ProjectPoint(k, pc, pixel)) return false;
    residual[0] = pixel[0] - T(px_.x());
    residual[1] = pixel[1] - T(px_.y());
    return true;
  }
  static ceres::CostFunction* Create(const calib::Camera& camera, const Eigen::Vector2d& px) {
    return new ceres::AutoDiffCostFunction<FixedCameraReprojection, 2, 3>(
        new FixedCameraReprojection(camera, px));
  }
  Eigen::Vector2d px_;
  std::array<double, calib::kNumIntrinsics> k_;
  double r_[9], t_[3];
};

// Reprojection in a camera whose pose is adjusted: rotation q (cam_from_world, Eigen order
// x, y, z, w) and centre c in the world; p_in_cam = R (p - c). With a `base` the centre is
// base + length * u, u on the unit sphere (the scale-holding camera).
struct MovingCameraReprojection {
  template <typename T>
  bool operator()(const T* q, const T* c, const T* p, T* residual) const {
    T centre[3];
    for (int i = 0; i < 3; ++i) centre[i] = scaled_ ? T(base_[i]) + T(length_) * c[i] : c[i];
    const T d[3] = {p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]};
    const T wxyz[4] = {q[3], q[0], q[1], q[2]};
    T pc[3], k[calib::kNumIntrinsics], pixel[2];
    ceres::QuaternionRotatePoint(wxyz, d, pc);
    for (int i = 0; i < calib::kNumIntrinsics; ++i) k[i] = T(k_[i]);
    if (!calib::ProjectPoint(k, pc, pixel)) return false;
    residual[0] = pixel[0] - T(px_.x());
    residual[1] = pixel[1] - T(px_.y());
    return true;
  }
  Eigen::Vector2d px_;
  std::array<double, calib::kNumIntrinsics> k_;
  bool scaled_ = false;
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  double length_ = 0.0;
};

// (|a - b| - length) / sigma.
struct LinkLengthPrior {
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz) - T(length_)) / T(sigma_);
    return true;
  }
  double length_, sigma_;
};

// (a - 2 b + c) / sigma.
struct SmoothnessPrior {
  template <typename T>
  bool operator()(const T* a, const T* b, const T* c, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (a[i] - T(2) * b[i] + c[i]) / T(sigma_);
    return true;
  }
  double sigma_;
};

// The diagonal 3x3 blocks of H^-1 for H = blockdiag(info) + w (D2' D2 (x) I3), D2 the second
// differences of consecutive frames: the marginal covariances of one knot's run of frames under
// the smoothness prior. H is banded (scalar bandwidth 6); a banded Cholesky factor and the
// Takahashi recursion for the band of the inverse take O(n b^2) instead of a dense inverse.
std::vector<Eigen::Matrix3d> SmoothedCovariances(const std::vector<Eigen::Matrix3d>& info,
                                                 double w) {
  constexpr int kBand = 6;
  const int m = static_cast<int>(info.size()), n = 3 * m;
  // (D2' D2)_ij: sum over the second differences c = 0..m-3 with coefficients 1, -2, 1.
  auto s = [&](int i, int j) {
    static constexpr double kCoef[3] = {1.0, -2.0, 1.0};
    double v = 0.0;
    for (int c = std::max({0, i - 2, j - 2}); c <= std::min({m - 3, i, j}); ++c)
      v += kCoef[i - c] * kCoef[j - c];
    return v;
  };
  auto h = [&](int r, int c) {
    const int i = r / 3, a = r % 3, j = c / 3, b = c % 3;
    double v = i == j ? info[i](a, b) : 0.0;
    if (a == b && std::abs(i - j) <= 2) v += w * s(i, j);
    return v;
  };
  std::vector<std::array<double, kBand + 1>> l(n), z(n);  // l[r][d] = L(r, r-d); z[r][d] = Z(r, r+d)
  for (int r = 0; r < n; ++r)
    for (int c = std::max(0, r - kBand); c <= r; ++c) {
      double sum = h(r, c);
      for (int k = std::max(0, r - kBand); k < c; ++k) sum -= l[r][r - k] * l[c][c - k];
      if (c == r) l[r][0] = std::sqrt(std::max(sum, 0.0));
      else l[r][r - c] = sum / l[c][0];
    }
  auto zz = [&](int i, int j) { return i <= j ? z[i][j - i] : z[j][i - j]; };
  for (int i = n - 1; i >= 0; --i)
    for (int j = std::min(n - 1, i + kBand); j >= i; --j) {
      double sum = 0.0;
      for (int k = i + 1; k <= std::min(n - 1, i + kBand); ++k) sum += l[k][k - i] * zz(k, j);
      z[i][j - i] = ((i == j ? 1.0 / l[i][0] : 0.0) - sum) / l[i][0];
    }
  std::vector<Eigen::Matrix3d> cov(m);
  for (int t = 0; t < m; ++t)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) cov[t](a, b) = zz(3 * t + a, 3 * t + b);
  return cov;
}

// Observations of one knot-frame, camera indices into the rig.
struct KnotFrame {
  std::vector<Observation> observations;
  PointEstimate estimate;
};

class SequenceSolver {
 public:
  SequenceSolver(const calib::Rig& rig, const LabelSet& labels, const SequenceOptions& options)
      : rig_(rig), labels_(labels), o_(options), tri_(options.triangulation),
        t_(labels.frames()), k_(labels.knots()) {
    for (const std::string& name : labels.cameras) {
      const int c = rig.Find(name);
      if (c < 0)
        throw InputError("the labels use camera '" + name +
                         "', which the rig does not have (rig cameras: " + RigNames() + ")");
      camera_of_label_.push_back(c);
    }
    cells_.resize(static_cast<size_t>(t_) * k_);
  }

  SequenceResult Run() {
    SequenceResult result;
    result.rows = labels_.rows;
    result.cols = labels_.cols;
    result.frame_index = labels_.frame_index;
    const auto t0 = Clock::now();
    Gather(&result);
    // First pass with the fixed threshold; the rig (kRig) from its points; then the threshold
    // scaled to the noise (auto) and the final pass.
    TriangulateAll();
    result.triangulate_s = Since(t0);
    const auto t1 = Clock::now();
    if (o_.adjustment == Adjustment::kRig) {
      RefineRig(&result);
      if (result.rig_adjusted) TriangulateAll();
    }
    const double rig_s = Since(t1);
    const auto t2 = Clock::now();
    if (o_.auto_threshold && o_.sigma_px > 0.0) {
      ScaleThreshold(o_.sigma_px);
      TriangulateAll();
    } else if (o_.auto_threshold) {
      // A threshold below the noise truncates the residuals and biases the median low: repeat
      // until the threshold settles (two passes at low noise, three at 2 px).
      for (int pass = 0; pass < 3; ++pass) {
        const double sigma = RobustSigma();
        if (!(sigma > 0.0)) break;
        const double current = tri_.outlier_threshold_px;
        const double wanted = std::max(o_.min_threshold_px, o_.outlier_sigmas * sigma);
        if (pass > 0 && std::abs(wanted - current) < 0.1 * current) break;
        result.robust_sigma_px = sigma;
        ScaleThreshold(sigma);
        TriangulateAll();
      }
    }
    result.outlier_threshold_px = tri_.outlier_threshold_px;
    result.triangulate_s += Since(t2);
    const auto t3 = Clock::now();
    result.rig = rig_;
    positions_.assign(cells_.size(), Eigen::Vector3d::Constant(kNaN));
    valid_.assign(cells_.size(), 0);
    for (size_t i = 0; i < cells_.size(); ++i)
      if (cells_[i].estimate.valid) positions_[i] = cells_[i].estimate.position, valid_[i] = 1;
    EstimateSigma(&result);
    if (o_.adjustment != Adjustment::kNone) ApplyPriors(&result);
    result.adjust_s = rig_s + Since(t3);
    Finish(&result);
    return result;
  }

 private:
  std::string RigNames() const {
    std::string s;
    for (const auto& c : rig_.cameras) {
      if (!s.empty()) s += ", ";
      s += c.name;
    }
    return s;
  }
  size_t Cell(int t, int k) const { return static_cast<size_t>(t) * k_ + k; }
  void Progress(const std::string& stage, double f) const {
    if (o_.progress) o_.progress(stage, f);
  }

  void Gather(SequenceResult* result) {
    for (int t = 0; t < t_; ++t)
      for (int k = 0; k < k_; ++k)
        for (size_t c = 0; c < labels_.cameras.size(); ++c) {
          const Label& l = labels_.at(static_cast<int>(c), t, k);
          if (!l.present()) continue;
          if (l.state == LabelState::kNeedsReview && !o_.use_unreviewed) {
            ++result->unreviewed_skipped;
            continue;
          }
          cells_[Cell(t, k)].observations.push_back({camera_of_label_[c], l.px});
        }
  }

  void ScaleThreshold(double sigma) {
    tri_.outlier_threshold_px = std::max(o_.min_threshold_px, o_.outlier_sigmas * sigma);
    tri_.huber_px = std::max(2.0 * sigma, 0.4 * o_.min_threshold_px);
  }

  // The labelling noise from the residuals of every triangulated point: the residual norm of a
  // view is Rayleigh-distributed with median 1.1774 sigma, shrunk by sqrt((2n - 3) / 2n) by the
  // fit of 3 coordinates to 2n residuals; the median keeps the outliers that slipped through
  // from mattering. 0 when nothing was triangulated.
  double RobustSigma() const {
    std::vector<double> scaled;
    for (const KnotFrame& cell : cells_) {
      if (!cell.estimate.valid) continue;
      const double n = static_cast<double>(cell.estimate.inliers.size());
      const double shrink = std::sqrt((2.0 * n - 3.0) / (2.0 * n));
      for (int i : cell.estimate.inliers) scaled.push_back(cell.estimate.residual_px[i] / shrink);
    }
    if (scaled.empty()) return 0.0;
    auto mid = scaled.begin() + static_cast<long>(scaled.size() / 2);
    std::nth_element(scaled.begin(), mid, scaled.end());
    return *mid / 1.1774;
  }

  void TriangulateAll() {
    const int n = static_cast<int>(cells_.size());
    std::atomic<int> done{0};
    ParallelFor(n, o_.threads, [&](int i) {
      KnotFrame& cell = cells_[i];
      cell.estimate = TriangulatePoint(rig_, cell.observations, tri_);
      const int d = ++done;
      if (d % 20000 == 0) Progress("triangulate", static_cast<double>(d) / n);
    });
  }

  // One pose per camera for the sequence, on frames spread over it; reference camera and the
  // distance to the second camera held (the gauge). Two stages: Huber-weighted over every
  // observation (a camera knocked out of place has all its observations rejected as outliers by
  // the first triangulation, so inliers alone would never move it), a few iterations; then plain
  // least squares over the observations within the outlier threshold of that solution (Huber's
  // linear region made the first stage converge only linearly: 50 iterations instead of 5).
  void RefineRig(SequenceResult* result) {
    const int cams = static_cast<int>(rig_.cameras.size());
    if (cams < 2) return;
    std::vector<int> frames;
    for (int t = 0; t < t_; ++t) {
      int valid = 0;
      for (int k = 0; k < k_; ++k) valid += cells_[Cell(t, k)].estimate.valid;
      if (valid > 0) frames.push_back(t);
    }
    if (static_cast<int>(frames.size()) > o_.rig_frames) {
      std::vector<int> picked;
      for (int i = 0; i < o_.rig_frames; ++i)
        picked.push_back(frames[static_cast<size_t>(i) * frames.size() / o_.rig_frames]);
      frames = picked;
    }
    result->rig_frames_used = static_cast<int>(frames.size());
    struct Entry {
      size_t point;
      Observation observation;
    };
    std::vector<Eigen::Vector3d> points;
    std::vector<Entry> entries;
    for (int t : frames)
      for (int k = 0; k < k_; ++k) {
        const KnotFrame& cell = cells_[Cell(t, k)];
        if (!cell.estimate.valid) continue;
        for (const Observation& ob : cell.observations)
          entries.push_back({points.size(), ob});
        points.push_back(cell.estimate.position);
      }
    if (entries.empty()) return;
    const Eigen::Vector3d c0 = rig_.cameras[0].Center();
    const double baseline = (rig_.cameras[1].Center() - c0).norm();
    std::vector<std::array<double, 4>> q(cams);
    std::vector<std::array<double, 3>> c(cams);
    for (int i = 0; i < cams; ++i) {
      const Eigen::Quaterniond r = rig_.cameras[i].cam_from_world.rotation;
      q[i] = {r.x(), r.y(), r.z(), r.w()};
      Eigen::Vector3d centre = rig_.cameras[i].Center();
      if (i == 1) centre = (centre - c0) / baseline;
      c[i] = {centre.x(), centre.y(), centre.z()};
    }
    ceres::EigenQuaternionManifold quaternion;
    ceres::SphereManifold<3> sphere;
    // Squared residuals of the entries at the current parameters.
    auto residuals = [&] {
      std::vector<double> out(entries.size());
      for (size_t e = 0; e < entries.size(); ++e) {
        MovingCameraReprojection f = Reprojection(entries[e].observation, c0, baseline);
        double r[2];
        const int cam = entries[e].observation.camera;
        out[e] = f(q[cam].data(), c[cam].data(), points[entries[e].point].data(), r)
                     ? r[0] * r[0] + r[1] * r[1]
                     : std::numeric_limits<double>::infinity();
      }
      return out;
    };
    auto solve = [&](const std::vector<char>& use, bool robust, int iterations) {
      ceres::Problem::Options problem_options;
      problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      auto problem_ptr = std::make_unique<ceres::Problem>(problem_options);
      ceres::Problem& problem = *problem_ptr;
      auto* ordering = new ceres::ParameterBlockOrdering;
      for (size_t e = 0; e < entries.size(); ++e) {
        if (!use[e]) continue;
        const int cam = entries[e].observation.camera;
        double* p = points[entries[e].point].data();
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<MovingCameraReprojection, 2, 4, 3, 3>(
                new MovingCameraReprojection(Reprojection(entries[e].observation, c0, baseline))),
            robust ? new ceres::HuberLoss(tri_.huber_px) : nullptr, q[cam].data(),
            c[cam].data(), p);
        ordering->AddElementToGroup(p, 0);
      }
      for (int i = 0; i < cams; ++i) {
        if (!problem.HasParameterBlock(q[i].data())) continue;
        problem.SetManifold(q[i].data(), &quaternion);
        if (i == 1) problem.SetManifold(c[i].data(), &sphere);
        if (i == 0) {
          problem.SetParameterBlockConstant(q[i].data());
          problem.SetParameterBlockConstant(c[i].data());
        }
        ordering->AddElementToGroup(q[i].data(), 1);
        ordering->AddElementToGroup(c[i].data(), 1);
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
    };
    Progress("rig", 0.0);
    std::vector<char> use(entries.size(), 1);
    const std::vector<double> before = residuals();
    solve(use, true, 10);
    Progress("rig", 0.5);
    const double threshold2 = tri_.outlier_threshold_px * tri_.outlier_threshold_px;
    std::vector<double> r2 = residuals();
    for (size_t e = 0; e < entries.size(); ++e) use[e] = r2[e] <= threshold2;
    const auto problem = solve(use, false, 30);
    r2 = residuals();
    double ss_before = 0.0, ss_after = 0.0;
    int64_t n = 0;
    for (size_t e = 0; e < entries.size(); ++e) {
      if (!use[e]) continue;
      ss_before += before[e];
      ss_after += r2[e];
      ++n;
    }
    result->rig_rms_before_px = std::sqrt(ss_before / std::max<int64_t>(n, 1));
    result->rig_rms_after_px = std::sqrt(ss_after / std::max<int64_t>(n, 1));
    result->rig_rotation_change_deg.assign(cams, 0.0);
    result->rig_center_change_mm.assign(cams, 0.0);
    // How well the sequence determines the cameras: a net at one place, or flat and small,
    // leaves a camera's position traded against its turn, and adopting such a rig would make
    // every point worse. Then the calibrated rig is kept, and said so.
    const double dof = 2.0 * static_cast<double>(n) - 3.0 * static_cast<double>(points.size());
    const double sigma2 = dof > 0 ? ss_after / dof : 1.0;
    RigUncertainty(*problem, points, q, c, sigma2, baseline, result);
    double worst_centre = 0.0, worst_rotation = 0.0;
    for (int i = 1; i < cams; ++i) {
      worst_centre = std::max(worst_centre, result->rig_center_sigma_mm[i]);
      worst_rotation = std::max(worst_rotation, result->rig_rotation_sigma_deg[i]);
    }
    result->rig_adjusted = worst_centre <= o_.rig_max_center_sigma_mm &&
                           worst_rotation <= o_.rig_max_rotation_sigma_deg;
    for (int i = 1; i < cams; ++i) {
      const Eigen::Quaterniond r = Eigen::Quaterniond(q[i][3], q[i][0], q[i][1], q[i][2]).normalized();
      Eigen::Vector3d centre(c[i][0], c[i][1], c[i][2]);
      if (i == 1) centre = c0 + baseline * centre;
      calib::Camera& cam = rig_.cameras[i];
      result->rig_rotation_change_deg[i] =
          cam.cam_from_world.rotation.angularDistance(r) * 180.0 / M_PI;
      result->rig_center_change_mm[i] = (cam.Center() - centre).norm() * 1e3;
      if (result->rig_adjusted) cam.cam_from_world = calib::Rigid3d(r, -(r * centre));
    }
  }

  // Standard deviations of the cameras' rotation (deg) and centre (mm) from the reduced camera
  // system S = J_c'J_c - sum_p (J_p'J_c)' (J_p'J_p)^-1 (J_p'J_c) of the least-squares problem at
  // its solution (points eliminated), times the residual variance.
  static void RigUncertainty(ceres::Problem& problem, std::vector<Eigen::Vector3d>& points,
                             std::vector<std::array<double, 4>>& q,
                             std::vector<std::array<double, 3>>& c, double sigma2,
                             double baseline, SequenceResult* result) {
    const int cams = static_cast<int>(q.size());
    result->rig_rotation_sigma_deg.assign(cams, 0.0);
    result->rig_center_sigma_mm.assign(cams, 0.0);
    ceres::Problem::EvaluateOptions eval;
    std::vector<int> point_of_block;
    for (size_t i = 0; i < points.size(); ++i)
      if (problem.HasParameterBlock(points[i].data())) {
        eval.parameter_blocks.push_back(points[i].data());
        point_of_block.push_back(static_cast<int>(i));
      }
    const int point_cols = 3 * static_cast<int>(point_of_block.size());
    // Camera columns: per camera its rotation (3, tangent) and centre (3, or 2 on the sphere).
    std::vector<int> rot_col(cams, -1), centre_col(cams, -1), centre_dim(cams, 0);
    int m = 0;
    for (int i = 1; i < cams; ++i) {
      if (!problem.HasParameterBlock(q[i].data())) continue;
      eval.parameter_blocks.push_back(q[i].data());
      rot_col[i] = m, m += 3;
      eval.parameter_blocks.push_back(c[i].data());
      centre_dim[i] = i == 1 ? 2 : 3;
      centre_col[i] = m, m += centre_dim[i];
    }
    if (m == 0) return;
    ceres::CRSMatrix jac;
    double cost = 0.0;
    problem.Evaluate(eval, &cost, nullptr, nullptr, &jac);
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, m);
    std::vector<Eigen::Matrix3d> cpp(point_of_block.size(), Eigen::Matrix3d::Zero());
    std::vector<Eigen::MatrixXd> bpc(point_of_block.size(), Eigen::MatrixXd::Zero(3, m));
    for (int row = 0; row < jac.num_rows; ++row) {
      Eigen::Vector3d jp = Eigen::Vector3d::Zero();
      Eigen::VectorXd jc = Eigen::VectorXd::Zero(m);
      int point = -1;
      for (int i = jac.rows[row]; i < jac.rows[row + 1]; ++i) {
        const int col = jac.cols[i];
        if (col < point_cols) point = col / 3, jp[col % 3] = jac.values[i];
        else jc[col - point_cols] = jac.values[i];
      }
      a += jc * jc.transpose();
      if (point < 0) continue;
      cpp[point] += jp * jp.transpose();
      bpc[point] += jp * jc.transpose();
    }
    for (size_t p = 0; p < cpp.size(); ++p)
      a -= bpc[p].transpose() * cpp[p].ldlt().solve(bpc[p]);
    const Eigen::MatrixXd cov = sigma2 * a.ldlt().solve(Eigen::MatrixXd::Identity(m, m));
    for (int i = 1; i < cams; ++i) {
      if (rot_col[i] < 0) continue;
      // EigenQuaternionManifold's tangent is half the rotation vector.
      const double rot = 2.0 * std::sqrt(std::max(0.0, cov.block<3, 3>(rot_col[i], rot_col[i]).trace()));
      const double centre = std::sqrt(std::max(
          0.0, cov.block(centre_col[i], centre_col[i], centre_dim[i], centre_dim[i]).trace()));
      result->rig_rotation_sigma_deg[i] = rot * 180.0 / M_PI;
      result->rig_center_sigma_mm[i] = 1e3 * centre * (i == 1 ? baseline : 1.0);
    }
  }

  MovingCameraReprojection Reprojection(const Observation& ob, const Eigen::Vector3d& c0,
                                        double baseline) const {
    MovingCameraReprojection f;
    f.px_ = ob.px;
    f.k_ = rig_.cameras[ob.camera].intrinsics.ToParameters();
    if (ob.camera == 1) f.scaled_ = true, f.base_ = c0, f.length_ = baseline;
    return f;
  }

  void EstimateSigma(SequenceResult* result) {
    double ss = 0.0;
    int64_t dof = 0;
    for (const KnotFrame& cell : cells_) {
      if (!cell.estimate.valid) continue;
      ss += cell.estimate.sum_squares_px2;
      dof += 2 * static_cast<int64_t>(cell.estimate.inliers.size()) - 3;
    }
    if (o_.sigma_px > 0.0) {
      result->sigma_px = o_.sigma_px;
    } else if (dof >= 10) {
      result->sigma_px = std::sqrt(ss / static_cast<double>(dof));
      result->sigma_estimated = true;
    } else {
      result->sigma_px = 1.0;  // too few redundant observations to tell; said in the summary
      result->sigma_estimated = false;
    }
  }

  // The data term of one point: its inlier observations, cameras fixed.
  void AddData(ceres::Problem* problem, size_t cell, double* p) const {
    const KnotFrame& kf = cells_[cell];
    for (int i : kf.estimate.inliers) {
      const Observation& ob = kf.observations[i];
      problem->AddResidualBlock(FixedCameraReprojection::Create(rig_.cameras[ob.camera], ob.px),
                                nullptr, p);
    }
  }
  std::vector<int> GridNeighbours(int k) const {
    const int r = k / labels_.cols, col = k % labels_.cols;
    std::vector<int> out;
    if (col + 1 < labels_.cols) out.push_back(k + 1);
    if (col > 0) out.push_back(k - 1);
    if (r + 1 < labels_.rows) out.push_back(k + labels_.cols);
    if (r > 0) out.push_back(k - labels_.cols);
    return out;
  }

  // Solves frame t's points with the link prior (and, when `smooth`, the smoothness terms with
  // the other frames held at `prev`), writing them into `out`. Each call reads `prev` only and
  // writes its own frame of `out`, so frames can be solved in parallel.
  void SolveFrame(int t, bool link, bool smooth, const std::vector<Eigen::Vector3d>& prev,
                  std::vector<Eigen::Vector3d>* out) const {
    ceres::Problem problem;
    std::deque<Eigen::Vector3d> held;  // other frames' points, constant (stable addresses)
    auto hold = [&](size_t cell) {
      held.push_back(prev[cell]);
      problem.AddParameterBlock(held.back().data(), 3);
      problem.SetParameterBlockConstant(held.back().data());
      return held.back().data();
    };
    for (int k = 0; k < k_; ++k) {
      const size_t cell = Cell(t, k);
      if (!valid_[cell]) continue;
      AddData(&problem, cell, (*out)[cell].data());
      if (link)
        for (int n : GridNeighbours(k))
          if (n > k && valid_[Cell(t, n)])
            problem.AddResidualBlock(
                new ceres::AutoDiffCostFunction<LinkLengthPrior, 1, 3, 3>(
                    new LinkLengthPrior{o_.link_length_m, o_.link_sigma_m}),
                nullptr, (*out)[cell].data(), (*out)[Cell(t, n)].data());
      if (smooth)
        for (int centre = t - 1; centre <= t + 1; ++centre) {
          if (centre - 1 < 0 || centre + 1 >= t_) continue;
          double* blocks[3] = {nullptr, nullptr, nullptr};
          bool ok = true;
          for (int j = 0; j < 3; ++j) {
            const int tj = centre - 1 + j;
            const size_t cj = Cell(tj, k);
            if (!valid_[cj]) ok = false;
            else blocks[j] = tj == t ? (*out)[cj].data() : hold(cj);
          }
          if (!ok) continue;
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SmoothnessPrior, 3, 3, 3, 3>(
                                       new SmoothnessPrior{o_.smoothness_sigma_m}),
                                   nullptr, blocks[0], blocks[1], blocks[2]);
        }
    }
    if (problem.NumResidualBlocks() > 0) Solve(&problem, ceres::SPARSE_NORMAL_CHOLESKY);
  }

  // Solves knot k's points over the sequence with the smoothness prior (and, when `link`, the
  // link terms with the neighbouring knots held at `prev`), writing them into `out`.
  void SolveKnot(int k, bool smooth, bool link, const std::vector<Eigen::Vector3d>& prev,
                 std::vector<Eigen::Vector3d>* out) const {
    ceres::Problem problem;
    std::deque<Eigen::Vector3d> held;
    for (int t = 0; t < t_; ++t) {
      const size_t cell = Cell(t, k);
      if (!valid_[cell]) continue;
      double* p = (*out)[cell].data();
      AddData(&problem, cell, p);
      if (smooth && t + 2 < t_ && valid_[Cell(t + 1, k)] && valid_[Cell(t + 2, k)])
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SmoothnessPrior, 3, 3, 3, 3>(
                                     new SmoothnessPrior{o_.smoothness_sigma_m}),
                                 nullptr, p, (*out)[Cell(t + 1, k)].data(),
                                 (*out)[Cell(t + 2, k)].data());
      if (link)
        for (int n : GridNeighbours(k)) {
          if (!valid_[Cell(t, n)]) continue;
          held.push_back(prev[Cell(t, n)]);
          problem.AddParameterBlock(held.back().data(), 3);
          problem.SetParameterBlockConstant(held.back().data());
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LinkLengthPrior, 1, 3, 3>(
                                       new LinkLengthPrior{o_.link_length_m, o_.link_sigma_m}),
                                   nullptr, p, held.back().data());
        }
    }
    if (problem.NumResidualBlocks() > 0) Solve(&problem, ceres::SPARSE_NORMAL_CHOLESKY);
  }

  static void Solve(ceres::Problem* problem, ceres::LinearSolverType type) {
    ceres::Solver::Options solver;
    solver.linear_solver_type = type;
    if (type == ceres::SPARSE_NORMAL_CHOLESKY &&
        !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE))
      solver.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
    solver.num_threads = 1;  // the callers run one problem per thread
    solver.max_num_iterations = 20;
    solver.function_tolerance = 1e-8;
    solver.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, problem, &summary);
  }

  // One sweep: every frame (or knot) solved from `prev`, Jacobi style (see SolveFrame).
  std::vector<Eigen::Vector3d> SweepFrames(const std::vector<Eigen::Vector3d>& prev, bool link,
                                           bool smooth) const {
    std::vector<Eigen::Vector3d> out = prev;
    ParallelFor(t_, o_.threads, [&](int t) { SolveFrame(t, link, smooth, prev, &out); });
    return out;
  }
  std::vector<Eigen::Vector3d> SweepKnots(const std::vector<Eigen::Vector3d>& prev, bool smooth,
                                          bool link) const {
    std::vector<Eigen::Vector3d> out = prev;
    ParallelFor(k_, o_.threads, [&](int k) { SolveKnot(k, smooth, link, prev, &out); });
    return out;
  }

  void Shift(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
             double* rms, double* max) const {
    double ss = 0.0;
    int64_t n = 0;
    *max = 0.0;
    for (size_t i = 0; i < from.size(); ++i) {
      if (!valid_[i]) continue;
      const double d = (to[i] - from[i]).norm();
      ss += d * d;
      *max = std::max(*max, d);
      ++n;
    }
    *rms = n > 0 ? std::sqrt(ss / static_cast<double>(n)) : 0.0;
  }

  void ApplyPriors(SequenceResult* result) {
    const bool link = o_.link_length_m > 0.0, smooth = o_.smoothness_sigma_m > 0.0;
    if (!link && !smooth) return;
    const std::vector<Eigen::Vector3d> start = positions_;
    std::vector<Eigen::Vector3d> link_only, smooth_only;
    if (smooth) {
      Progress("smoothness prior", 0.0);
      smooth_only = SweepKnots(start, true, false);
      // A wrong point drags its neighbours in time along: drop only the worst of each knot's
      // track per round, and solve that knot again.
      for (int round = 0; round < 5; ++round) {
        positions_ = smooth_only;
        const std::vector<int> knots = CheckAgainstTracks(result);
        if (knots.empty()) break;
        ParallelFor(static_cast<int>(knots.size()), o_.threads,
                    [&](int i) { SolveKnot(knots[i], true, false, start, &smooth_only); });
      }
      Shift(start, smooth_only, &result->smoothness_shift_rms_m,
            &result->smoothness_shift_max_m);
    }
    if (link) {
      Progress("link prior", 0.0);
      link_only = SweepFrames(start, true, false);
      Shift(start, link_only, &result->link_shift_rms_m, &result->link_shift_max_m);
    }
    if (link && smooth) {
      // From the smoothness solution (the prior that moves the points most), alternating.
      std::vector<Eigen::Vector3d> pos = smooth_only;
      for (int sweep = 0; sweep < o_.prior_sweeps; ++sweep) {
        Progress("both priors", static_cast<double>(sweep) / o_.prior_sweeps);
        std::vector<Eigen::Vector3d> next = SweepKnots(SweepFrames(pos, true, true), true, true);
        double change_max = 0.0;
        Shift(pos, next, &result->prior_sweep_change_rms_m, &change_max);
        pos = std::move(next);
        result->prior_sweeps_done = sweep + 1;
        if (result->prior_sweep_change_rms_m < o_.prior_tolerance_m) break;
      }
      positions_ = pos;
    } else {
      positions_ = link ? link_only : smooth_only;
    }
  }

  // A two-view point that the smoothness prior pulls away from its own labels (a residual
  // beyond the outlier threshold) is at odds with its track: most likely two views agreeing on a
  // mislabel along their epipolar line, which geometry alone cannot see. The worst such point of
  // each knot is left out and its views reported. Points seen three or more times were checked
  // geometrically: they stay, and are counted as disagreeing with the prior (its sigma may be
  // too small for the motion). Returns the knots that lost a point.
  std::vector<int> CheckAgainstTracks(SequenceResult* result) {
    std::vector<int64_t> dropped(k_, 0), disagreeing(k_, 0);
    ParallelFor(k_, o_.threads, [&](int k) {
      int worst_t = -1;
      double worst_ratio = 1.0;
      for (int t = 0; t < t_; ++t) {
        const size_t cell = Cell(t, k);
        if (!valid_[cell]) continue;
        const PointEstimate& est = cells_[cell].estimate;
        double worst = 0.0;
        for (int i : est.inliers)
          worst = std::max(worst, ReprojectionResidual(rig_, cells_[cell].observations[i],
                                                       positions_[cell]));
        const double ratio = worst / tri_.outlier_threshold_px;
        if (ratio <= 1.0) continue;
        if (est.inliers.size() > 2) {
          ++disagreeing[k];
        } else if (ratio > worst_ratio) {
          worst_ratio = ratio;
          worst_t = t;
        }
      }
      if (worst_t < 0) return;
      const size_t cell = Cell(worst_t, k);
      PointEstimate& est = cells_[cell].estimate;
      for (int i : est.inliers)
        est.residual_px[i] =
            ReprojectionResidual(rig_, cells_[cell].observations[i], positions_[cell]);
      est.outliers = est.inliers;
      est.inliers.clear();
      est.valid = false;
      est.why = "two views at odds with the knot's track (smoothness prior)";
      valid_[cell] = 0;
      dropped[k] = 1;
    });
    std::vector<int> knots;
    result->prior_disagreements = 0;
    for (int k = 0; k < k_; ++k) {
      if (dropped[k]) knots.push_back(k);
      result->prior_disagreements += disagreeing[k];
    }
    result->track_outliers += static_cast<int64_t>(knots.size());
    return knots;
  }

  // Per point: residuals and covariance at the final position (priors' terms with the
  // neighbours held), outliers, totals.
  void Finish(SequenceResult* result) {
    const size_t n = cells_.size();
    result->position = positions_;
    result->valid = valid_;
    result->covariance.assign(n, Eigen::Matrix3d::Constant(kNaN));
    result->rms_px.assign(n, kNaN);
    const bool link = o_.adjustment != Adjustment::kNone && o_.link_length_m > 0.0;
    const bool smooth = o_.adjustment != Adjustment::kNone && o_.smoothness_sigma_m > 0.0;
    const double s2 = result->sigma_px * result->sigma_px;
    double ss = 0.0;
    int64_t count = 0;
    for (int t = 0; t < t_; ++t)
      for (int k = 0; k < k_; ++k) {
        const size_t cell = Cell(t, k);
        const KnotFrame& kf = cells_[cell];
        if (kf.observations.size() == 1) ++result->single_view;
        if (kf.observations.size() >= 2) ++result->candidates;
        for (int i : kf.estimate.outliers)
          result->outliers.push_back({labels_.frame_index[t], k, kf.observations[i].camera,
                                      kf.estimate.residual_px.empty()
                                          ? kNaN
                                          : kf.estimate.residual_px[i]});
        if (!valid_[cell]) continue;
        ++result->triangulated;
        result->two_view += kf.estimate.inliers.size() == 2;
        const Eigen::Vector3d& p = positions_[cell];
        double point_ss = 0.0;
        std::vector<int> cams;
        for (int i : kf.estimate.inliers) {
          const double r = ReprojectionResidual(rig_, kf.observations[i], p);
          point_ss += r * r;
          cams.push_back(kf.observations[i].camera);
        }
        ss += point_ss;
        count += static_cast<int64_t>(kf.estimate.inliers.size());
        result->rms_px[cell] = std::sqrt(point_ss / kf.estimate.inliers.size());
        Eigen::Matrix3d info = PointInformation(rig_, cams, p) / s2;
        if (link)
          for (int nb : GridNeighbours(k)) {
            if (!valid_[Cell(t, nb)]) continue;
            const Eigen::Vector3d u = (p - positions_[Cell(t, nb)]).normalized();
            info += u * u.transpose() / (o_.link_sigma_m * o_.link_sigma_m);
          }
        result->covariance[cell] = info;  // information for now; inverted below
      }
    result->reprojection_rms_px = count > 0 ? std::sqrt(ss / static_cast<double>(count)) : 0.0;
    // Covariances: the smoothness prior ties a knot's consecutive frames, so its marginal
    // covariance comes from the whole run of frames (holding the neighbours fixed understated it
    // 20-fold: most points' errors were beyond 6 of their sigmas); the link terms stay
    // conditional (neighbouring knots held), a mild understatement.
    const double w = smooth ? 1.0 / (o_.smoothness_sigma_m * o_.smoothness_sigma_m) : 0.0;
    ParallelFor(k_, o_.threads, [&](int k) {
      for (int t = 0; t < t_;) {
        if (!valid_[Cell(t, k)]) {
          ++t;
          continue;
        }
        std::vector<Eigen::Matrix3d> run;
        const int first = t;
        for (; t < t_ && valid_[Cell(t, k)]; ++t) run.push_back(result->covariance[Cell(t, k)]);
        const std::vector<Eigen::Matrix3d> cov =
            smooth ? SmoothedCovariances(run, w) : std::vector<Eigen::Matrix3d>{};
        for (size_t i = 0; i < run.size(); ++i)
          result->covariance[Cell(first + static_cast<int>(i), k)] =
              smooth ? cov[i] : Eigen::Matrix3d(run[i].ldlt().solve(Eigen::Matrix3d::Identity()));
      }
    });
  }

  calib::Rig rig_;
  const LabelSet& labels_;
  const SequenceOptions& o_;
  TriangulationOptions tri_;  // o_.triangulation, thresholds scaled to the noise (auto)
  int t_, k_;
  std::vector<int> camera_of_label_;
  std::vector<KnotFrame> cells_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<uint8_t> valid_;
};

}  // namespace

bool ParseAdjustment(const std::string& name, Adjustment* mode) {
  if (name == "none") *mode = Adjustment::kNone;
  else if (name == "points") *mode = Adjustment::kPoints;
  else if (name == "rig") *mode = Adjustment::kRig;
  else return false;
  return true;
}

SequenceResult ReconstructSequence(const calib::Rig& rig, const LabelSet& labels,
                                   const SequenceOptions& options) {
  SequenceSolver solver(rig, labels, options);
  return solver.Run();
}

}  // namespace netlab::recon
