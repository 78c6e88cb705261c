#pragma once
// The reconstruction without a window: the session's labels triangulated into 3D knot tracks
// with `netlab triangulate`'s engine (recon::ReconstructSequence and recon::TracksFromSequence,
// docs/triangulation.md) and its options, on a worker; the tracks as the CLI writes them.
//
// The frames' times are the CLI's with --experiment: the mean of the cameras' timestamps where
// the recording has them, else frame / fps.
//
//   ReconstructionPresenter reconstruction(&session);
//   TriangulationOptions options;                          // --ba points, sigma from residuals
//   reconstruction.SetRun(ReconstructionPresenter::Triangulate(reconstruction.MakeJob(options),
//                                                              cancel));
//   const KnotTracks* tracks = reconstruction.tracks();
//   reconstruction.Export("tracks.h5", "out/");            // tracks.h5, out/xyzpts.csv, ...

#include <QAbstractTableModel>
#include <QString>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "common/progress.h"
#include "common/tracks/track_file.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {

class Session;

// The options a person chooses, as `netlab triangulate` names them.
struct TriangulationOptions {
  recon::Adjustment adjustment = recon::Adjustment::kPoints;  // --ba none | points | rig
  double sigma_px = 0.0;        // --sigma-px: the labels' noise; 0: from the residuals
  double link_length_m = 0.0;   // --link-length; 0: off
  double smooth_sigma_m = 0.0;  // --smooth-sigma; 0: off
  bool use_unreviewed = false;  // --use-unreviewed
};

// What a triangulation needs (copied: it runs on a worker) and what it answers.
struct TriangulationJob {
  calib::Rig rig;
  recon::LabelSet labels;
  std::vector<double> time_s;  // [labels.frames()]
  recon::SequenceOptions options;
  int rows = 0, cols = 0;
};
struct TriangulationRun {
  std::optional<recon::SequenceResult> result;
  KnotTracks tracks;                  // valid with a result
  std::vector<std::string> warnings;  // recon::SequenceWarnings
  std::string error;                  // why there is no result
  bool cancelled = false;
  double wall_s = 0.0;
};

class ReconstructionPresenter {
 public:
  // `session` must outlive the presenter.
  explicit ReconstructionPresenter(const Session* session);

  // The job for the current labels (GUI thread). InputError naming the timestamps file when the
  // recording's times cannot be used (as netlab triangulate --experiment), std::invalid_argument
  // naming the option for a prior without adjustment.
  TriangulationJob MakeJob(const TriangulationOptions& options) const;
  // Any thread, reporting as ReconstructSequence does (SequenceOptions::progress, from the
  // engine's threads). A cancel of the reporter's token stops the engine within a chunk of its
  // work: the answer then says cancelled and holds nothing.
  static TriangulationRun Triangulate(const TriangulationJob& job,
                                      const ProgressReporter& progress = {});
  void SetRun(TriangulationRun run);
  const TriangulationRun* run() const { return run_ ? &*run_ : nullptr; }
  // Tracks written before (netlab triangulate --out, or the project's `tracks`) in place of a
  // run; the error names the file, or a net other than the project's.
  void LoadTracks(const std::string& path);
  // The tracks of the last run or file (null: none yet).
  const KnotTracks* tracks() const;
  // Where they were read from or last saved ("" : not saved).
  const std::string& tracks_path() const { return tracks_path_; }
  // Writes them to `path` (as Export, without the CSV files; "": the project's `tracks`, else
  // tracks.h5 beside the project) and names it in the project file as its `tracks`.
  // std::runtime_error naming the file that cannot be written.
  void SaveToProject(std::string path = "");
  // The run in a few lines (counts, reprojection RMS, outliers, degenerate points, warnings).
  QString Summary() const;
  // The tracks' row of frame row t of the session (-1: none).
  int TrackRow(int t) const;
  // Frame row t in words, as the status bar and the rooms' sliders say it: "frame 212 (21 of
  // 27) · t = 1.1844 s" (the recording's frame number, the row counted from 1, frame / fps).
  QString FrameStatus(int t) const;

  // After an edit of the labels: the tracks of these frame rows triangulated again from the
  // current labels, knot by knot (Session::Triangulate: the accepted labels of two views or more,
  // no adjustment, no priors), their covariance for the run's labels' sigma. What an edit changes
  // shows at once; Triangulate renews the whole shot with its options. Returns the knot-frames
  // whose point changed (0 without tracks).
  int UpdateRows(const std::vector<int>& rows);
  // The frame rows updated so since the tracks were made or read.
  const std::set<int>& updated_rows() const { return updated_rows_; }

  // Writes the tracks as netlab triangulate --out does, and with a non-empty `csv_prefix`
  // PREFIXxyzpts.csv and PREFIXxyzres.csv as its --csv (all put in place together).
  // std::logic_error without tracks, std::runtime_error naming a file that cannot be written.
  void Export(const std::string& tracks_path, const std::string& csv_prefix) const;

  const Session& session() const { return *session_; }
  std::weak_ptr<const int> lifetime() const { return alive_; }

 private:
  const Session* session_;
  std::optional<TriangulationRun> run_;
  std::string tracks_path_;
  std::set<int> updated_rows_;
  std::shared_ptr<const int> alive_ = std::make_shared<const int>(0);
};

// The knots at one frame of the tracks, a row each: the knot (row, col), its status (a point;
// degenerate; with outlier views, named; no point), its reprojection residual (px: the RMS over
// its inlier views), its 3D sigma (mm: the square root of its covariance's largest eigenvalue)
// and its outlier views' residuals. Filtered to every knot, the knots with an outlier view or the
// degenerate points; sortable by any column (Qt::UserRole holds the number sorted on; a missing
// value sorts after every number).
class KnotErrorModel : public QAbstractTableModel {
 public:
  enum Column { kKnot, kStatus, kResidual, kSigma, kOutliers, kColumns };
  enum class Filter { kAll, kOutliers, kDegenerate };
  struct Row {
    int knot = 0;
    bool valid = false, degenerate = false;
    double residual_px = 0.0, sigma_mm = 0.0;  // NaN: none
    std::vector<int> outlier_cameras;          // the tracks' camera_names indices
    std::vector<double> outlier_px;            // [outlier_cameras.size()]
  };

  using QAbstractTableModel::QAbstractTableModel;
  // The knots of `tracks` (null: none) at its row `row` (-1: none), as `filter` keeps them.
  void Set(const KnotTracks* tracks, int row, Filter filter);
  Filter filter() const { return filter_; }
  const Row& row(int i) const { return rows_.at(i); }
  // The name of the tracks' camera `camera` ("" when the tracks name none).
  std::string camera_name(int camera) const;

  int rowCount(const QModelIndex& parent = {}) const override;
  int columnCount(const QModelIndex& parent = {}) const override;
  QVariant data(const QModelIndex& index, int role = Qt::DisplayRole) const override;
  QVariant headerData(int section, Qt::Orientation orientation,
                      int role = Qt::DisplayRole) const override;
  void sort(int column, Qt::SortOrder order = Qt::AscendingOrder) override;

 private:
  double Key(const Row& r, int column) const;
  std::vector<Row> rows_;
  std::vector<std::string> cameras_;
  int cols_ = 1;
  Filter filter_ = Filter::kAll;
  int sort_column_ = -1;
  Qt::SortOrder sort_order_ = Qt::AscendingOrder;
};

}  // namespace netlab::gui
