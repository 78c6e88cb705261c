#include "libreconstruct/geometry/bundle_adjust.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <limits>
#include <thread>

#include "common/errors.h"
#include "libreconstruct/geometry/camera_offsets.h"
#include "libreconstruct/geometry/cost_functors.h"
#include "libreconstruct/geometry/rig_refinement.h"

namespace netlab::recon {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Runs body(i) for i in [0, n) on `threads` threads (contiguous chunks taken in turn); a cancel
// stops them between chunks and throws Cancelled.
void ParallelFor(int n, int threads, const ProgressReporter& progress,
                 const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  constexpr int kChunk = 16;
  auto work = [&] {
    for (int start = next.fetch_add(kChunk); start < n && !progress.cancelled();
         start = next.fetch_add(kChunk))
      for (int i = start; i < std::min(n, start + kChunk); ++i) body(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  progress.ThrowIfCancelled();
}

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
  std::vector<std::array<double, kBand + 1>> l(n),
      z(n);  // l[r][d] = L(r, r-d); z[r][d] = Z(r, r+d)
  for (int r = 0; r < n; ++r)
    for (int c = std::max(0, r - kBand); c <= r; ++c) {
      double sum = h(r, c);
      for (int k = std::max(0, r - kBand); k < c; ++k) sum -= l[r][r - k] * l[c][c - k];
      if (c == r)
        l[r][0] = std::sqrt(std::max(sum, 0.0));
      else
        l[r][r - c] = sum / l[c][0];
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

// The reconstruction of one sequence, stage by stage (Run). The knot-frames are cells of a
// frame-major grid: cell t * K + k is knot k in frame row t.
class SequenceSolver {
 public:
  SequenceSolver(const calib::Rig& rig, const LabelSet& labels, const SequenceOptions& options);

  // Gather, triangulate, adjust the rig (kRig), triangulate again with the threshold scaled to
  // the noise, estimate the noise, apply the priors, sum up.
  SequenceResult Run();

 private:
  std::string RigNames() const;
  size_t Cell(int t, int k) const { return static_cast<size_t>(t) * k_ + k; }
  void Progress(const std::string& stage, double done, double total) const {
    o_.progress.Report(stage, done, total);
  }
  std::vector<int> GridNeighbours(int k) const;

  // Triangulation.
  void Gather(SequenceResult* result);
  void TriangulateAll();
  void ScaleThreshold(double sigma);
  void AdaptThreshold(SequenceResult* result);
  double RobustSigma() const;
  void AdjustRig(SequenceResult* result);
  std::vector<int> RigFrames() const;
  std::vector<RigPoint> RigPoints(const std::vector<int>& frames) const;
  void CollectPositions();
  void EstimateSigma(SequenceResult* result);

  // Priors.
  void AddData(ceres::Problem* problem, size_t cell, double* p) const;
  void SolveFrame(int t, bool link, bool smooth, const std::vector<Eigen::Vector3d>& prev,
                  std::vector<Eigen::Vector3d>* out) const;
  void SolveKnot(int k, bool smooth, bool link, const std::vector<Eigen::Vector3d>& prev,
                 std::vector<Eigen::Vector3d>* out) const;
  static void Solve(ceres::Problem* problem, ceres::LinearSolverType type);
  std::vector<Eigen::Vector3d> SweepFrames(const std::vector<Eigen::Vector3d>& prev, bool link,
                                           bool smooth) const;
  std::vector<Eigen::Vector3d> SweepKnots(const std::vector<Eigen::Vector3d>& prev, bool smooth,
                                          bool link) const;
  void Shift(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
             double* rms, double* max) const;
  void ApplyPriors(SequenceResult* result);
  std::vector<Eigen::Vector3d> SolveSmoothness(const std::vector<Eigen::Vector3d>& start,
                                               SequenceResult* result);
  std::vector<Eigen::Vector3d> AlternatePriors(std::vector<Eigen::Vector3d> pos,
                                               SequenceResult* result) const;
  std::vector<int> CheckAgainstTracks(SequenceResult* result);
  int WorstTwoViewPoint(int k, int64_t* disagreeing) const;
  void LeaveOut(size_t cell);

  // Summing up.
  void Finish(SequenceResult* result);
  void FlagDegenerate(SequenceResult* result);
  std::string DegenerateReason(size_t cell, double sigma, double bound, double* angle_deg) const;
  void SumUpPoints(SequenceResult* result) const;
  void InvertInformation(int k, SequenceResult* result) const;

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

SequenceSolver::SequenceSolver(const calib::Rig& rig, const LabelSet& labels,
                               const SequenceOptions& options)
    : rig_(rig),
      labels_(labels),
      o_(options),
      tri_(options.triangulation),
      t_(labels.frames()),
      k_(labels.knots()) {
  for (const std::string& name : labels.cameras) {
    const int c = rig.Find(name);
    if (c < 0)
      throw InputError("the labels use camera '" + name +
                       "', which the rig does not have (rig cameras: " + RigNames() + ")");
    camera_of_label_.push_back(c);
  }
  cells_.resize(static_cast<size_t>(t_) * k_);
}

SequenceResult SequenceSolver::Run() {
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
    AdjustRig(&result);
    if (result.rig_adjusted) TriangulateAll();
  }
  const double rig_s = Since(t1);
  const auto t2 = Clock::now();
  AdaptThreshold(&result);
  result.outlier_threshold_px = tri_.outlier_threshold_px;
  result.triangulate_s += Since(t2);
  // The points as triangulated, the noise, the priors; per point its residuals and covariance.
  const auto t3 = Clock::now();
  result.rig = rig_;
  CollectPositions();
  EstimateSigma(&result);
  if (o_.adjustment != Adjustment::kNone) ApplyPriors(&result);
  result.adjust_s = rig_s + Since(t3);
  Finish(&result);
  return result;
}

std::string SequenceSolver::RigNames() const {
  std::string s;
  for (const auto& c : rig_.cameras) {
    if (!s.empty()) s += ", ";
    s += c.name;
  }
  return s;
}

std::vector<int> SequenceSolver::GridNeighbours(int k) const {
  const int r = k / labels_.cols, col = k % labels_.cols;
  std::vector<int> out;
  if (col + 1 < labels_.cols) out.push_back(k + 1);
  if (col > 0) out.push_back(k - 1);
  if (r + 1 < labels_.rows) out.push_back(k + labels_.cols);
  if (r > 0) out.push_back(k - labels_.cols);
  return out;
}

// Every label present into its knot-frame's observations; unreviewed ones only if asked for;
// none placed from the other views (LabelSource::kProjected). A camera with a clock offset has
// its labels moved to the frame time along their own track (camera_offsets.h); one that cannot
// be moved (no label of the knot in a neighbouring frame) is left out.
void SequenceSolver::Gather(SequenceResult* result) {
  const std::vector<std::vector<uint8_t>> usable = UsableLabels(labels_, o_);
  for (int t = 0; t < t_; ++t)
    for (int k = 0; k < k_; ++k)
      for (size_t c = 0; c < labels_.cameras.size(); ++c) {
        const Label& l = labels_.at(static_cast<int>(c), t, k);
        if (!l.present()) continue;
        if (l.state == LabelState::kNeedsReview && !o_.use_unreviewed) {
          ++result->unreviewed_skipped;
          continue;
        }
        if (l.source == LabelSource::kProjected) {
          ++result->projected_skipped;
          continue;
        }
        const int camera = camera_of_label_[c];
        const double offset = static_cast<size_t>(camera) < o_.camera_offset_frames.size()
                                  ? o_.camera_offset_frames[camera]
                                  : 0.0;
        Eigen::Vector2d px = l.px;
        if (offset != 0.0 &&
            !LabelAtFrameTime(labels_, static_cast<int>(c), t, k, offset, usable[c], &px)) {
          ++result->offset_unshifted;
          continue;
        }
        cells_[Cell(t, k)].observations.push_back({camera, px});
      }
}

void SequenceSolver::TriangulateAll() {
  const int n = static_cast<int>(cells_.size());
  std::atomic<int> done{0};
  ParallelFor(n, o_.threads, o_.progress, [&](int i) {
    KnotFrame& cell = cells_[i];
    cell.estimate = TriangulatePoint(rig_, cell.observations, tri_);
    const int d = ++done;
    if (d % 20000 == 0) Progress("knot-frames triangulated", d, n);
  });
}

void SequenceSolver::ScaleThreshold(double sigma) {
  const TriangulationOptions scaled = TriangulationForNoise(o_, sigma);
  tri_.outlier_threshold_px = scaled.outlier_threshold_px;
  tri_.huber_px = scaled.huber_px;
}

// With auto_threshold: the threshold scaled to the given noise, or to the one estimated from the
// residuals, and the points triangulated again with it.
void SequenceSolver::AdaptThreshold(SequenceResult* result) {
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
      result->robust_sigma_px = sigma;
      ScaleThreshold(sigma);
      TriangulateAll();
    }
  }
}

// The labelling noise from the residuals of every triangulated point: the residual norm of a
// view is Rayleigh-distributed with median 1.1774 sigma, shrunk by sqrt((2n - 3) / 2n) by the
// fit of 3 coordinates to 2n residuals; the median keeps the outliers that slipped through
// from mattering. 0 when nothing was triangulated.
double SequenceSolver::RobustSigma() const {
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

// One pose per camera for the sequence (rig_refinement.h), from the points of up to rig_frames
// frames spread over it.
void SequenceSolver::AdjustRig(SequenceResult* result) {
  if (rig_.cameras.size() < 2) return;
  const std::vector<int> frames = RigFrames();
  result->rig_frames_used = static_cast<int>(frames.size());
  RefineRig(RigPoints(frames), o_, tri_, &rig_, result);
}

// The frames with a triangulated point; at most rig_frames of them, evenly spread.
std::vector<int> SequenceSolver::RigFrames() const {
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
  return frames;
}

// The triangulated points of those frames with all their views, frame by frame.
std::vector<RigPoint> SequenceSolver::RigPoints(const std::vector<int>& frames) const {
  std::vector<RigPoint> points;
  for (int t : frames)
    for (int k = 0; k < k_; ++k) {
      const KnotFrame& cell = cells_[Cell(t, k)];
      if (!cell.estimate.valid) continue;
      points.push_back({cell.estimate.position, cell.observations});
    }
  return points;
}

// The triangulated points into positions_ and valid_ (NaN and 0 elsewhere).
void SequenceSolver::CollectPositions() {
  positions_.assign(cells_.size(), Eigen::Vector3d::Constant(kNaN));
  valid_.assign(cells_.size(), 0);
  for (size_t i = 0; i < cells_.size(); ++i)
    if (cells_[i].estimate.valid) positions_[i] = cells_[i].estimate.position, valid_[i] = 1;
}

void SequenceSolver::EstimateSigma(SequenceResult* result) {
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
void SequenceSolver::AddData(ceres::Problem* problem, size_t cell, double* p) const {
  const KnotFrame& kf = cells_[cell];
  for (int i : kf.estimate.inliers) {
    const Observation& ob = kf.observations[i];
    problem->AddResidualBlock(FixedCameraReprojection::Create(rig_.cameras[ob.camera], ob.px),
                              nullptr, p);
  }
}

// Solves frame t's points with the link prior (and, when `smooth`, the smoothness terms with
// the other frames held at `prev`), writing them into `out`. Each call reads `prev` only and
// writes its own frame of `out`, so frames can be solved in parallel.
void SequenceSolver::SolveFrame(int t, bool link, bool smooth,
                                const std::vector<Eigen::Vector3d>& prev,
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
          problem.AddResidualBlock(LinkLengthPrior::Create(o_.link_length_m, o_.link_sigma_m),
                                   nullptr, (*out)[cell].data(), (*out)[Cell(t, n)].data());
    if (smooth)
      for (int centre = t - 1; centre <= t + 1; ++centre) {
        if (centre - 1 < 0 || centre + 1 >= t_) continue;
        double* blocks[3] = {nullptr, nullptr, nullptr};
        bool ok = true;
        for (int j = 0; j < 3; ++j) {
          const int tj = centre - 1 + j;
          const size_t cj = Cell(tj, k);
          if (!valid_[cj])
            ok = false;
          else
            blocks[j] = tj == t ? (*out)[cj].data() : hold(cj);
        }
        if (!ok) continue;
        problem.AddResidualBlock(SmoothnessPrior::Create(o_.smoothness_sigma_m), nullptr, blocks[0],
                                 blocks[1], blocks[2]);
      }
  }
  if (problem.NumResidualBlocks() > 0) Solve(&problem, ceres::SPARSE_NORMAL_CHOLESKY);
}

// Solves knot k's points over the sequence with the smoothness prior (and, when `link`, the
// link terms with the neighbouring knots held at `prev`), writing them into `out`.
void SequenceSolver::SolveKnot(int k, bool smooth, bool link,
                               const std::vector<Eigen::Vector3d>& prev,
                               std::vector<Eigen::Vector3d>* out) const {
  ceres::Problem problem;
  std::deque<Eigen::Vector3d> held;
  for (int t = 0; t < t_; ++t) {
    const size_t cell = Cell(t, k);
    if (!valid_[cell]) continue;
    double* p = (*out)[cell].data();
    AddData(&problem, cell, p);
    if (smooth && t + 2 < t_ && valid_[Cell(t + 1, k)] && valid_[Cell(t + 2, k)])
      problem.AddResidualBlock(SmoothnessPrior::Create(o_.smoothness_sigma_m), nullptr, p,
                               (*out)[Cell(t + 1, k)].data(), (*out)[Cell(t + 2, k)].data());
    if (link)
      for (int n : GridNeighbours(k)) {
        if (!valid_[Cell(t, n)]) continue;
        held.push_back(prev[Cell(t, n)]);
        problem.AddParameterBlock(held.back().data(), 3);
        problem.SetParameterBlockConstant(held.back().data());
        problem.AddResidualBlock(LinkLengthPrior::Create(o_.link_length_m, o_.link_sigma_m),
                                 nullptr, p, held.back().data());
      }
  }
  if (problem.NumResidualBlocks() > 0) Solve(&problem, ceres::SPARSE_NORMAL_CHOLESKY);
}

void SequenceSolver::Solve(ceres::Problem* problem, ceres::LinearSolverType type) {
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
std::vector<Eigen::Vector3d> SequenceSolver::SweepFrames(const std::vector<Eigen::Vector3d>& prev,
                                                         bool link, bool smooth) const {
  std::vector<Eigen::Vector3d> out = prev;
  ParallelFor(t_, o_.threads, o_.progress, [&](int t) { SolveFrame(t, link, smooth, prev, &out); });
  return out;
}
std::vector<Eigen::Vector3d> SequenceSolver::SweepKnots(const std::vector<Eigen::Vector3d>& prev,
                                                        bool smooth, bool link) const {
  std::vector<Eigen::Vector3d> out = prev;
  ParallelFor(k_, o_.threads, o_.progress, [&](int k) { SolveKnot(k, smooth, link, prev, &out); });
  return out;
}

// How far the valid points moved from `from` to `to`: RMS and max (m).
void SequenceSolver::Shift(const std::vector<Eigen::Vector3d>& from,
                           const std::vector<Eigen::Vector3d>& to, double* rms, double* max) const {
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

// Each prior on its own from the triangulated points (to report how far it moves them), then
// with both the two alternated; the result into positions_.
void SequenceSolver::ApplyPriors(SequenceResult* result) {
  const bool link = o_.link_length_m > 0.0, smooth = o_.smoothness_sigma_m > 0.0;
  if (!link && !smooth) return;
  const std::vector<Eigen::Vector3d> start = positions_;
  std::vector<Eigen::Vector3d> link_only, smooth_only;
  if (smooth) {
    smooth_only = SolveSmoothness(start, result);
    Shift(start, smooth_only, &result->smoothness_shift_rms_m, &result->smoothness_shift_max_m);
  }
  if (link) {
    Progress("link prior", 0, 0);
    link_only = SweepFrames(start, true, false);
    Shift(start, link_only, &result->link_shift_rms_m, &result->link_shift_max_m);
  }
  if (link && smooth) {
    // From the smoothness solution (the prior that moves the points most), alternating.
    positions_ = AlternatePriors(smooth_only, result);
  } else {
    positions_ = link ? link_only : smooth_only;
  }
}

// The smoothness prior alone, knot by knot, with the two-view points at odds with their tracks
// left out (CheckAgainstTracks).
std::vector<Eigen::Vector3d> SequenceSolver::SolveSmoothness(
    const std::vector<Eigen::Vector3d>& start, SequenceResult* result) {
  Progress("smoothness prior", 0, 0);
  std::vector<Eigen::Vector3d> smooth_only = SweepKnots(start, true, false);
  // A wrong point drags its neighbours in time along: drop only the worst of each knot's
  // track per round, and solve that knot again.
  for (int round = 0; round < 5; ++round) {
    positions_ = smooth_only;
    const std::vector<int> knots = CheckAgainstTracks(result);
    if (knots.empty()) break;
    ParallelFor(static_cast<int>(knots.size()), o_.threads, o_.progress,
                [&](int i) { SolveKnot(knots[i], true, false, start, &smooth_only); });
  }
  return smooth_only;
}

// Both priors by block coordinate descent from `pos`: frames, then knots, each holding the other
// prior's neighbours, until a sweep moves the points less than prior_tolerance_m RMS or after
// prior_sweeps.
std::vector<Eigen::Vector3d> SequenceSolver::AlternatePriors(std::vector<Eigen::Vector3d> pos,
                                                             SequenceResult* result) const {
  for (int sweep = 0; sweep < o_.prior_sweeps; ++sweep) {
    Progress("sweeps of both priors", sweep, o_.prior_sweeps);
    std::vector<Eigen::Vector3d> next = SweepKnots(SweepFrames(pos, true, true), true, true);
    double change_max = 0.0;
    Shift(pos, next, &result->prior_sweep_change_rms_m, &change_max);
    pos = std::move(next);
    result->prior_sweeps_done = sweep + 1;
    if (result->prior_sweep_change_rms_m < o_.prior_tolerance_m) break;
  }
  return pos;
}

// A two-view point that the smoothness prior pulls away from its own labels (a residual
// beyond the outlier threshold) is at odds with its track: most likely two views agreeing on a
// mislabel along their epipolar line, which geometry alone cannot see. The worst such point of
// each knot is left out and its views reported. Points seen three or more times were checked
// geometrically: they stay, and are counted as disagreeing with the prior (its sigma may be
// too small for the motion). Returns the knots that lost a point.
std::vector<int> SequenceSolver::CheckAgainstTracks(SequenceResult* result) {
  std::vector<int64_t> dropped(k_, 0), disagreeing(k_, 0);
  ParallelFor(k_, o_.threads, o_.progress, [&](int k) {
    const int worst_t = WorstTwoViewPoint(k, &disagreeing[k]);
    if (worst_t < 0) return;
    LeaveOut(Cell(worst_t, k));
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

// Knot k's frame whose two-view point is worst beyond the outlier threshold at positions_
// (largest ratio of its worst inlier residual to the threshold), or -1; the points of three or
// more views beyond it counted into *disagreeing.
int SequenceSolver::WorstTwoViewPoint(int k, int64_t* disagreeing) const {
  int worst_t = -1;
  double worst_ratio = 1.0;
  for (int t = 0; t < t_; ++t) {
    const size_t cell = Cell(t, k);
    if (!valid_[cell]) continue;
    const PointEstimate& est = cells_[cell].estimate;
    double worst = 0.0;
    for (int i : est.inliers)
      worst = std::max(worst,
                       ReprojectionResidual(rig_, cells_[cell].observations[i], positions_[cell]));
    const double ratio = worst / tri_.outlier_threshold_px;
    if (ratio <= 1.0) continue;
    if (est.inliers.size() > 2) {
      ++*disagreeing;
    } else if (ratio > worst_ratio) {
      worst_ratio = ratio;
      worst_t = t;
    }
  }
  return worst_t;
}

// A point left out: every view an outlier, with its residual at positions_.
void SequenceSolver::LeaveOut(size_t cell) {
  PointEstimate& est = cells_[cell].estimate;
  for (int i : est.inliers)
    est.residual_px[i] = ReprojectionResidual(rig_, cells_[cell].observations[i], positions_[cell]);
  est.outliers = est.inliers;
  est.inliers.clear();
  est.valid = false;
  est.why = "two views at odds with the knot's track (smoothness prior)";
  valid_[cell] = 0;
}

// Per point: residuals and covariance at the final position (priors' terms with the
// neighbours held), outliers, totals.
void SequenceSolver::Finish(SequenceResult* result) {
  const size_t n = cells_.size();
  result->position = positions_;
  result->valid = valid_;
  result->covariance.assign(n, Eigen::Matrix3d::Constant(kNaN));
  result->rms_px.assign(n, kNaN);
  SumUpPoints(result);
  ParallelFor(k_, o_.threads, o_.progress, [&](int k) { InvertInformation(k, result); });
  FlagDegenerate(result);
}

// The points whose largest sigma exceeds the bound (given, or a multiple of the sequence's
// median): valid 0, flagged, each with its reason; their views are not outliers.
void SequenceSolver::FlagDegenerate(SequenceResult* result) {
  const size_t n = cells_.size();
  result->degenerate.assign(n, 0);
  std::vector<double> sigma(n, kNaN), all;
  for (size_t i = 0; i < n; ++i) {
    if (!result->valid[i]) continue;
    const Eigen::Matrix3d& cov = result->covariance[i];
    const double largest =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov, Eigen::EigenvaluesOnly)
            .eigenvalues()[2];
    sigma[i] = std::sqrt(std::max(largest, 0.0));
    all.push_back(sigma[i]);
  }
  if (all.empty()) return;
  auto mid = all.begin() + static_cast<long>(all.size() / 2);
  std::nth_element(all.begin(), mid, all.end());
  result->median_sigma_m = *mid;
  char text[96];
  if (o_.max_sigma_m > 0.0) {
    result->max_sigma_m = o_.max_sigma_m;
    result->max_sigma_from = "given";
  } else {
    result->max_sigma_m = o_.degenerate_sigma_factor * result->median_sigma_m;
    std::snprintf(text, sizeof text, "%g x the median sigma (%.3f mm)", o_.degenerate_sigma_factor,
                  result->median_sigma_m * 1e3);
    result->max_sigma_from = text;
  }
  for (int t = 0; t < t_; ++t)
    for (int k = 0; k < k_; ++k) {
      const size_t i = Cell(t, k);
      if (!result->valid[i] || !(sigma[i] > result->max_sigma_m)) continue;
      DegeneratePoint d;
      d.frame = labels_.frame_index[t];
      d.knot = k;
      d.sigma_m = sigma[i];
      d.reason = DegenerateReason(i, sigma[i], result->max_sigma_m, &d.ray_angle_deg);
      result->degenerate_points.push_back(d);
      result->degenerate[i] = 1;
      result->valid[i] = 0;
      result->rms_px[i] = kNaN;
      --result->triangulated;
      result->two_view -= cells_[i].estimate.inliers.size() == 2;
    }
}

// Why a point is degenerate: the pair of its cameras whose rays meet at the widest angle, that
// angle (near 0: parallel; near 180: head-on), and its sigma against the bound.
std::string SequenceSolver::DegenerateReason(size_t cell, double sigma, double bound,
                                             double* angle_deg) const {
  const KnotFrame& kf = cells_[cell];
  const Eigen::Vector3d& p = positions_[cell];
  double best_sin = -1.0;
  int best_a = -1, best_b = -1;
  const std::vector<int>& in = kf.estimate.inliers;
  for (size_t a = 0; a < in.size(); ++a)
    for (size_t b = a + 1; b < in.size(); ++b) {
      const int ca = kf.observations[in[a]].camera, cb = kf.observations[in[b]].camera;
      const Eigen::Vector3d ra = (p - rig_.cameras[ca].Center()).normalized();
      const Eigen::Vector3d rb = (p - rig_.cameras[cb].Center()).normalized();
      const double s = ra.cross(rb).norm();
      if (s > best_sin) {
        best_sin = s;
        best_a = ca, best_b = cb;
        // The angle between the rays as they arrive at the point from the two cameras.
        *angle_deg = std::atan2(s, ra.dot(rb)) * 180.0 / M_PI;
      }
    }
  char text[256];
  if (best_a < 0) {
    *angle_deg = 0.0;
    std::snprintf(text, sizeof text, "sigma %.1f mm, over the bound %.2f mm", sigma * 1e3,
                  bound * 1e3);
    return text;
  }
  std::snprintf(text, sizeof text,
                "the rays of %s and %s meet at %.2f deg (nearly %s): sigma %.1f mm, over the "
                "bound %.2f mm",
                rig_.cameras[best_a].name.c_str(), rig_.cameras[best_b].name.c_str(), *angle_deg,
                *angle_deg > 90.0 ? "head-on" : "parallel", sigma * 1e3, bound * 1e3);
  return text;
}

// Counts, outliers and residuals of every knot-frame, and each valid point's information (data
// and link terms) into result->covariance for InvertInformation.
void SequenceSolver::SumUpPoints(SequenceResult* result) const {
  const bool link = o_.adjustment != Adjustment::kNone && o_.link_length_m > 0.0;
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
        result->outliers.push_back(
            {labels_.frame_index[t], k, kf.observations[i].camera,
             kf.estimate.residual_px.empty() ? kNaN : kf.estimate.residual_px[i]});
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
}

// Knot k's covariances from the information SumUpPoints left in result->covariance. The
// smoothness prior ties a knot's consecutive frames, so its marginal covariance comes from the
// whole run of frames (holding the neighbours fixed understated it 20-fold: most points' errors
// were beyond 6 of their sigmas); the link terms stay conditional (neighbouring knots held), a
// mild understatement.
void SequenceSolver::InvertInformation(int k, SequenceResult* result) const {
  const bool smooth = o_.adjustment != Adjustment::kNone && o_.smoothness_sigma_m > 0.0;
  const double w = smooth ? 1.0 / (o_.smoothness_sigma_m * o_.smoothness_sigma_m) : 0.0;
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
}

}  // namespace

TriangulationOptions TriangulationForNoise(const SequenceOptions& options, double sigma_px) {
  TriangulationOptions t = options.triangulation;
  t.outlier_threshold_px = std::max(options.min_threshold_px, options.outlier_sigmas * sigma_px);
  t.huber_px = std::max(2.0 * sigma_px, 0.4 * options.min_threshold_px);
  return t;
}

bool ParseAdjustment(const std::string& name, Adjustment* mode) {
  if (name == "none")
    *mode = Adjustment::kNone;
  else if (name == "points")
    *mode = Adjustment::kPoints;
  else if (name == "rig")
    *mode = Adjustment::kRig;
  else
    return false;
  return true;
}

SequenceResult ReconstructSequence(const calib::Rig& rig, const LabelSet& labels,
                                   const SequenceOptions& options) {
  SequenceSolver solver(rig, labels, options);
  return solver.Run();
}

std::vector<std::string> SequenceWarnings(const SequenceResult& result) {
  std::vector<std::string> warnings;
  if (result.sigma_estimated && 4.0 * result.sigma_px > result.outlier_threshold_px) {
    char sigma[32];
    std::snprintf(sigma, sizeof sigma, "%.2f", result.sigma_px);
    warnings.push_back(std::string("the labelling noise (") + sigma +
                       " px) is more than a quarter of --outlier-px: good labels are being "
                       "rejected; raise --outlier-px to ~5x the noise");
  }
  if (result.prior_disagreements > 0)
    warnings.push_back(std::to_string(result.prior_disagreements) +
                       " points seen by three or more cameras are pulled beyond the outlier "
                       "threshold by the smoothness prior: --smooth-sigma may be too small for "
                       "this motion");
  if (result.candidates > 0 && result.triangulated < 0.9 * result.candidates)
    warnings.push_back(std::to_string(result.candidates - result.triangulated) + " of " +
                       std::to_string(result.candidates) +
                       " knot-frames seen twice or more were not triangulated (see /outliers)");
  return warnings;
}

}  // namespace netlab::recon
