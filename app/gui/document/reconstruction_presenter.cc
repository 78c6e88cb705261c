#include "app/gui/document/reconstruction_presenter.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>

#include "app/gui/document/project.h"
#include "app/gui/document/session.h"
#include "common/errors.h"
#include "common/files.h"
#include "libreconstruct/geometry/camera_offsets.h"
#include "libreconstruct/geometry/track_export.h"
#include "libreconstruct/recording/experiment.h"

namespace netlab::gui {

ReconstructionPresenter::ReconstructionPresenter(const Session* session) : session_(session) {}

TriangulationJob ReconstructionPresenter::MakeJob(const TriangulationOptions& options) const {
  if (options.adjustment == recon::Adjustment::kNone &&
      (options.link_length_m > 0 || options.smooth_sigma_m > 0))
    throw std::invalid_argument(
        "the priors (link length, smoothing) need bundle adjustment of the points or the rig");
  const Session& s = *session_;
  TriangulationJob job;
  job.rig = s.rig();
  job.labels = s.document().labels();
  job.rows = s.project().rows;
  job.cols = s.project().cols;
  recon::SequenceOptions& o = job.options;
  o.adjustment = options.adjustment;
  o.sigma_px = options.sigma_px;
  o.link_length_m = options.link_length_m;
  o.smoothness_sigma_m = options.smooth_sigma_m;
  o.use_unreviewed = options.use_unreviewed;
  o.threads = 2;  // as netlab triangulate
  // The frames' times: the cameras' timestamps where the recording has them (--experiment).
  const recon::Experiment& experiment = s.sequence().experiment();
  std::vector<std::string> names;
  std::vector<std::map<int, double>> timestamps(job.rig.cameras.size());
  std::vector<std::string> where(job.rig.cameras.size());
  for (size_t c = 0; c < job.rig.cameras.size(); ++c) {
    names.push_back(job.rig.cameras[c].name);
    const int e = experiment.Find(job.rig.cameras[c].name);
    if (e < 0 || experiment.cameras[e].timestamps.empty()) continue;
    where[c] = experiment.cameras[e].timestamps;
    timestamps[c] = recon::ReadTimestamps(where[c]);
  }
  job.time_s =
      recon::FrameTimesFromTimestamps(job.labels.frame_index, s.fps(), names, timestamps, where)
          .time_s;
  return job;
}

TriangulationRun ReconstructionPresenter::Triangulate(const TriangulationJob& job,
                                                      const ProgressReporter& progress) {
  const auto start = std::chrono::steady_clock::now();
  TriangulationRun run;
  if (progress.cancelled()) {
    run.cancelled = true;
    return run;
  }
  try {
    recon::SequenceOptions options = job.options;
    options.progress = progress;
    recon::SequenceResult result = recon::ReconstructSequence(job.rig, job.labels, options);
    if (progress.cancelled()) {
      run.cancelled = true;
    } else if (result.candidates == 0) {
      run.error = "no knot is labeled in two cameras in any frame: nothing to triangulate" +
                  std::string(job.options.use_unreviewed
                                  ? ""
                                  : " (labels still marked for review are left out)");
    } else if (result.triangulated == 0) {
      run.error = "none of the " + std::to_string(result.candidates) +
                  " knot-frames labeled in two or more cameras could be triangulated (every one "
                  "rejected as an outlier: do the labels belong to this rig?)";
    } else {
      run.tracks = recon::TracksFromSequence(result, job.time_s, "netlab gui");
      run.warnings = recon::SequenceWarnings(result);
      run.result = std::move(result);
    }
  } catch (const Cancelled&) {
    run.cancelled = true;
  } catch (const std::exception& e) {
    run.error = e.what();
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

void ReconstructionPresenter::SetRun(TriangulationRun run) {
  if (run.cancelled) return;  // the tracks before it stay
  run_ = std::move(run);
  tracks_path_.clear();
  updated_rows_.clear();
}

int ReconstructionPresenter::UpdateRows(const std::vector<int>& rows) {
  if (tracks() == nullptr) return 0;
  KnotTracks& tracks = run_->tracks;
  // The labels' sigma: the run's, else the tracks' median reprojection RMS.
  double sigma = run_->result ? run_->result->sigma_px : 0.0;
  if (!(sigma > 0)) {
    std::vector<double> rms;
    for (double v : tracks.reprojection_error_px)
      if (std::isfinite(v) && v > 0) rms.push_back(v);
    if (!rms.empty()) {
      std::nth_element(rms.begin(), rms.begin() + rms.size() / 2, rms.end());
      sigma = rms[rms.size() / 2];
    }
  }
  const int knots = tracks.knots();
  int changed = 0;
  for (int t : rows) {
    const int row = TrackRow(t);
    if (row < 0) continue;
    updated_rows_.insert(t);
    for (int k = 0; k < knots; ++k) {
      const recon::PointEstimate p = session_->Triangulate(t, k);
      const size_t i = static_cast<size_t>(row) * knots + k;
      const bool was = tracks.valid[i] != 0;
      if (p.valid == was && (!was || (tracks.position[i] - p.position).norm() < 1e-12)) continue;
      ++changed;
      tracks.valid[i] = p.valid ? 1 : 0;
      if (!tracks.degenerate.empty()) tracks.degenerate[i] = 0;
      if (!p.valid) continue;
      tracks.position[i] = p.position;
      if (!tracks.covariance.empty()) tracks.covariance[i] = sigma * sigma * p.unit_covariance;
      if (!tracks.reprojection_error_px.empty()) tracks.reprojection_error_px[i] = p.rms_px;
    }
  }
  return changed;
}

void ReconstructionPresenter::LoadTracks(const std::string& path) {
  updated_rows_.clear();
  KnotTracks tracks = ReadKnotTracks(path);
  const int rows = session_->project().rows, cols = session_->project().cols;
  if (tracks.knots() != rows * cols)
    throw InputError(path + ": " + std::to_string(tracks.knots()) + " knots, the project's net " +
                     std::to_string(rows) + "x" + std::to_string(cols) + " has " +
                     std::to_string(rows * cols));
  TriangulationRun run;
  run.tracks = std::move(tracks);
  run_ = std::move(run);
  tracks_path_ = path;
}

const KnotTracks* ReconstructionPresenter::tracks() const {
  return run_ && (run_->result || !run_->tracks.time.empty()) ? &run_->tracks : nullptr;
}

void ReconstructionPresenter::SaveToProject(std::string path) {
  Project project = LoadProject(session_->project().path);
  if (path.empty())
    path = !project.tracks.empty()
               ? project.tracks
               : (std::filesystem::path(project.path).parent_path() / "tracks.h5").string();
  Export(path, "");
  project.tracks = path;
  SaveProject(project, project.path);
  tracks_path_ = path;
}

int ReconstructionPresenter::TrackRow(int t) const {
  const KnotTracks* tracks = this->tracks();
  if (tracks == nullptr || t < 0 || t >= session_->frames()) return -1;
  const int number = session_->frame_number(t);
  const std::vector<int>& index = tracks->frame_index;
  for (size_t i = 0; i < index.size(); ++i)
    if (index[i] == number) return static_cast<int>(i);
  return -1;
}

QString ReconstructionPresenter::FrameStatus(int t) const {
  if (t < 0 || t >= session_->frames()) return "";
  return QString("frame %1 (%2 of %3) · t = %4 s")
      .arg(session_->frame_number(t))
      .arg(t + 1)
      .arg(session_->frames())
      .arg(session_->frame_number(t) / session_->fps(), 0, 'f', 4);
}

QString ReconstructionPresenter::Summary() const {
  if (!run_) return "Not triangulated yet.";
  if (!run_->result && run_->error.empty())
    return QString(
               "Tracks read from %1: %2 frames x %3 knots (triangulate to renew them from "
               "the labels).")
        .arg(QString::fromStdString(tracks_path_))
        .arg(run_->tracks.frames())
        .arg(run_->tracks.knots());
  if (!run_->result) return "Triangulation failed: " + QString::fromStdString(run_->error);
  const recon::SequenceResult& r = *run_->result;
  QString text = QString(
                     "%1 knot-frames triangulated of %2 seen twice or more (%3 degenerate), %4 "
                     "seen once; reprojection RMS %5 px; %6 outlier observations (threshold %7 "
                     "px); sigma %8 px%9; %10 s")
                     .arg(r.triangulated)
                     .arg(r.candidates)
                     .arg(r.degenerate_points.size())
                     .arg(r.single_view)
                     .arg(r.reprojection_rms_px, 0, 'f', 3)
                     .arg(r.outliers.size())
                     .arg(r.outlier_threshold_px, 0, 'f', 2)
                     .arg(r.sigma_px, 0, 'f', 3)
                     .arg(r.sigma_estimated ? " (estimated)" : "")
                     .arg(run_->wall_s, 0, 'f', 1);
  for (const std::string& w : run_->warnings) text += "\nwarning: " + QString::fromStdString(w);
  return text;
}

void ReconstructionPresenter::Export(const std::string& tracks_path,
                                     const std::string& csv_prefix) const {
  const KnotTracks* tracks = this->tracks();
  if (tracks == nullptr) throw std::logic_error("no tracks to export: triangulate first");
  const int rows = session_->project().rows, cols = session_->project().cols;
  const std::string pts = csv_prefix.empty() ? "" : csv_prefix + "xyzpts.csv";
  const std::string res = csv_prefix.empty() ? "" : csv_prefix + "xyzres.csv";
  OutputSet outputs({tracks_path, pts, res});
  WriteKnotTracks(tracks_path, *tracks);
  if (!pts.empty()) {
    recon::WriteXyzPts(pts, *tracks, rows, cols);
    recon::WriteXyzRes(res, *tracks, rows, cols);
  }
  outputs.Commit();
}

void KnotErrorModel::Set(const KnotTracks* tracks, int row, Filter filter) {
  beginResetModel();
  rows_.clear();
  filter_ = filter;
  if (tracks != nullptr && row >= 0 && row < tracks->frames()) {
    const int knots = tracks->knots();
    cameras_ = tracks->camera_names;
    cols_ = 1;
    for (const auto& g : tracks->grid) cols_ = std::max(cols_, g[1] + 1);
    const int frame = tracks->frame_index.empty() ? row : tracks->frame_index[row];
    std::vector<std::vector<const KnotTracks::Outlier*>> outliers(knots);  // this frame's, by knot
    for (const KnotTracks::Outlier& o : tracks->outliers)
      if (o.frame == frame && o.knot >= 0 && o.knot < knots) outliers[o.knot].push_back(&o);
    for (int k = 0; k < knots; ++k) {
      const size_t i = static_cast<size_t>(row) * knots + k;
      Row r;
      r.knot = tracks->grid[k][0] * cols_ + tracks->grid[k][1];
      r.valid = tracks->valid[i] != 0;
      r.degenerate = !tracks->degenerate.empty() && tracks->degenerate[i] != 0;
      r.residual_px = r.valid && !tracks->reprojection_error_px.empty()
                          ? tracks->reprojection_error_px[i]
                          : std::numeric_limits<double>::quiet_NaN();
      r.sigma_mm = std::numeric_limits<double>::quiet_NaN();
      if ((r.valid || r.degenerate) && !tracks->covariance.empty()) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(tracks->covariance[i],
                                                                   Eigen::EigenvaluesOnly);
        r.sigma_mm = std::sqrt(std::max(eigen.eigenvalues().maxCoeff(), 0.0)) * 1e3;
      }
      for (const KnotTracks::Outlier* o : outliers[k]) {
        r.outlier_cameras.push_back(o->camera);
        r.outlier_px.push_back(o->residual_px);
      }
      if (filter == Filter::kOutliers && r.outlier_cameras.empty()) continue;
      if (filter == Filter::kDegenerate && !r.degenerate) continue;
      rows_.push_back(std::move(r));
    }
  }
  endResetModel();
  if (sort_column_ >= 0) sort(sort_column_, sort_order_);
}

std::string KnotErrorModel::camera_name(int camera) const {
  return camera >= 0 && camera < static_cast<int>(cameras_.size()) ? cameras_[camera] : "";
}

int KnotErrorModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(rows_.size());
}

int KnotErrorModel::columnCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : kColumns;
}

double KnotErrorModel::Key(const Row& r, int column) const {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  switch (column) {
    case kKnot: return r.knot;
    case kStatus: return r.degenerate ? 3 : !r.outlier_cameras.empty() ? 2 : r.valid ? 0 : 1;
    case kResidual: return std::isnan(r.residual_px) ? kNone : r.residual_px;
    case kSigma: return std::isnan(r.sigma_mm) ? kNone : r.sigma_mm;
    case kOutliers: {
      double worst = r.outlier_cameras.empty() ? -1.0 : 0.0;
      for (double px : r.outlier_px) worst = std::max(worst, std::isnan(px) ? kNone : px);
      return worst;
    }
    default: return 0.0;
  }
}

QVariant KnotErrorModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount() || index.column() >= kColumns) return {};
  const Row& r = rows_[index.row()];
  if (role == Qt::UserRole) return Key(r, index.column());
  if (role == Qt::TextAlignmentRole && index.column() >= kResidual && index.column() <= kSigma)
    return QVariant::fromValue(Qt::AlignRight | Qt::AlignVCenter);
  if (role != Qt::DisplayRole && role != Qt::ToolTipRole) return {};
  switch (index.column()) {
    case kKnot: return QString("(%1,%2)").arg(r.knot / cols_).arg(r.knot % cols_);
    case kStatus:
      if (r.degenerate) return QString("degenerate");
      if (!r.outlier_cameras.empty()) return QString("outlier view");
      return r.valid ? QString("ok") : QString("no point");
    case kResidual:
      return std::isnan(r.residual_px) ? QString("—") : QString::number(r.residual_px, 'f', 3);
    case kSigma: return std::isnan(r.sigma_mm) ? QString("—") : QString::number(r.sigma_mm, 'f', 3);
    case kOutliers: {
      QString outliers;
      for (size_t j = 0; j < r.outlier_cameras.size(); ++j)
        outliers += QString("%1%2 %3")
                        .arg(j ? ", " : "")
                        .arg(QString::fromStdString(camera_name(r.outlier_cameras[j])))
                        .arg(std::isnan(r.outlier_px[j])
                                 ? QString("(no point)")
                                 : QString("%1 px").arg(r.outlier_px[j], 0, 'f', 2));
      return outliers;
    }
    default: return {};
  }
}

QVariant KnotErrorModel::headerData(int section, Qt::Orientation orientation, int role) const {
  if (orientation != Qt::Horizontal || section < 0 || section >= kColumns) return {};
  if (role == Qt::DisplayRole) {
    static const char* const kNames[] = {"Knot", "Status", "Residual px", "σ mm", "Outlier views"};
    return QString(kNames[section]);
  }
  if (role == Qt::ToolTipRole) {
    static const char* const kTips[] = {
        "The knot (row, col)", "A point; degenerate (left out); with an outlier view; no point",
        "The RMS reprojection residual over the point's inlier views",
        "The 3D standard deviation along the point's least certain axis",
        "The views left out as outliers, with their residual"};
    return QString(kTips[section]);
  }
  return {};
}

void KnotErrorModel::sort(int column, Qt::SortOrder order) {
  if (column < 0 || column >= kColumns) return;
  sort_column_ = column;
  sort_order_ = order;
  emit layoutAboutToBeChanged({}, QAbstractItemModel::VerticalSortHint);
  const QModelIndexList before = persistentIndexList();
  std::vector<int> knots_before;
  for (const QModelIndex& i : before) knots_before.push_back(rows_[i.row()].knot);
  std::stable_sort(rows_.begin(), rows_.end(), [&](const Row& a, const Row& b) {
    const double ka = Key(a, column), kb = Key(b, column);
    if (ka == kb) return a.knot < b.knot;
    return order == Qt::AscendingOrder ? ka < kb : ka > kb;
  });
  QModelIndexList after;
  for (qsizetype j = 0; j < before.size(); ++j) {
    int row = 0;
    while (rows_[row].knot != knots_before[static_cast<size_t>(j)]) ++row;
    after.push_back(index(row, before[j].column()));
  }
  changePersistentIndexList(before, after);
  emit layoutChanged({}, QAbstractItemModel::VerticalSortHint);
}

}  // namespace netlab::gui
