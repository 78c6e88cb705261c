#pragma once
// The calibration room without a window: from a target's images to a saved rig, and the rig as
// the room shows it.
//
// The work, as `netlab calibrate` does it (docs/calibration.md): the target (a chessboard or
// ChArUco spec, or a board, double-sided foil or marker map YAML: `--board`), each camera's
// images (NAME=GLOB: `--images`, sorted, the index is the frame); detection in every image (on a
// worker, with progress and a cancel flag; per image the points found, or why not); the
// calibration (calib::CalibrateRig with the CLI's options, on a worker); per camera and per image
// the RMS, the residual vectors and the coverage of the image by the target's points; the
// baselines, the metric check and the warnings. Excluding an image (or including it again) and
// re-running is one step on an undo stack of the excluded set; a result already computed for a
// set comes back at once. Save writes rig.yaml with calib::WriteRig (the CLI's writer, through
// "<path>.partial" and a rename) and points the project's `rig` at it.
//
// The rig shown (table, baselines, frusta of the 3D sketch) is the calibration's once there is
// one for the current excluded set, else the project's.
//
//   CalibrationPresenter calibration(&session.rig(), "rig.yaml", "project.yaml");
//   calibration.SetTarget("foil.yaml");
//   calibration.SetImages({{"cam0", "calib/cam0/*.png"}, {"cam1", "calib/cam1/*.png"}});
//   calibration.SetDetections(CalibrationPresenter::Detect(calibration.DetectionJob(), cancel));
//   calibration.SetCalibration(CalibrationPresenter::Calibrate(calibration.CalibrationJob()));
//   calibration.ToggleExcluded(calibration.WorstImage());   // undoable; NeedsCalibration()
//   calibration.Save("rig.yaml");

#include <Eigen/Core>
#include <QString>
#include <array>
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/rig.h"
#include "common/progress.h"

class QUndoStack;

namespace netlab::gui {

struct RigCameraRow {
  std::string name;
  int width = 0, height = 0;                             // px
  double fx = 0, fy = 0, cx = 0, cy = 0;                 // px
  double k1 = 0, k2 = 0;                                 // the first radial distortion terms
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();      // world, m
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // optical axis, world, unit
};

struct Baseline {
  int a = 0, b = 0;       // rig cameras
  double length_m = 0.0;  // between their centres
};

// One image of one camera: (camera, frame) in the order of the images given.
using ImageKey = std::pair<int, int>;

struct CalibrationImage {
  int camera = 0, frame = 0;
  std::string path;
  enum class Status { kNotDetected, kFound, kFailed };
  Status status = Status::kNotDetected;
  std::string why;                // kFailed: why (unreadable, wrong size, target not found)
  calib::PatternDetection found;  // kFound: the target's points
  int width = 0, height = 0;      // px, once read
};

// What detection needs (copied, so that it runs on a worker) and what it answers.
struct DetectionJob {
  calib::CalibrationTarget target;
  std::vector<CalibrationImage> images;
  int threads = 2;  // as `netlab calibrate`
};
struct DetectionAnswer {
  std::vector<CalibrationImage> images;
  bool cancelled = false;
  double wall_s = 0.0;
};

// What the calibration needs and what it answers.
struct CalibrationJob {
  calib::CalibrationTarget target;
  calib::CalibrationInput input;
  calib::CalibrationOptions options;
  std::set<ImageKey> excluded;
};
struct CalibrationRun {
  std::set<ImageKey> excluded;
  std::optional<calib::CalibrationResult> result;
  std::string error;  // why CalibrateRig refused (no result)
  double wall_s = 0.0;
};

// A point's residual: where it was detected and observed minus predicted (px).
struct PointResidual {
  Eigen::Vector2d pixel;
  Eigen::Vector2d residual;
};

// How many of the target's points fall in each cell of a camera's image (the images used).
struct CoverageGrid {
  int cols = 0, rows = 0;
  std::vector<int> counts;  // row-major
  int max() const;
  int at(int col, int row) const { return counts[row * cols + col]; }
};

class CalibrationPresenter {
 public:
  // `rig` (may be null: no rig yet) must outlive the presenter; `rig_path` is shown as where it
  // comes from; `project_path` (may be "") is the project whose `rig` Save points at the file.
  CalibrationPresenter(const calib::Rig* rig, std::string rig_path, std::string project_path = "");
  ~CalibrationPresenter();
  CalibrationPresenter(const CalibrationPresenter&) = delete;
  CalibrationPresenter& operator=(const CalibrationPresenter&) = delete;

  // ---- The rig shown.
  const calib::Rig& rig() const;
  std::vector<RigCameraRow> Cameras() const;
  // Every pair of cameras, nearest first.
  std::vector<Baseline> Baselines() const;
  // Camera c's centre followed by its four image corners' rays at `depth_m` in front (world, m;
  // a pinhole: the lens distortion left out of a sketch).
  std::array<Eigen::Vector3d, 5> Frustum(int c, double depth_m) const;
  // The line above the table: the file (or "calibrated, not saved"), the cameras, the baselines.
  QString Summary() const;

  // ---- The inputs. Each resets what was detected and calibrated from the old ones.
  // `spec` as `netlab calibrate --board` takes it; std::invalid_argument or InputError naming
  // the spec or the file (line, key) when it cannot be read.
  void SetTarget(const std::string& spec);
  const std::string& target_spec() const { return target_spec_; }
  bool has_target() const { return target_.has_value(); }
  const calib::CalibrationTarget* target() const { return target_ ? &*target_ : nullptr; }
  // NAME=GLOB per camera, as `--images` (the files sorted: the index is the frame).
  // std::runtime_error naming the camera or the pattern: a name empty or given twice, a pattern
  // that matches no file, cameras with unequal numbers of images.
  void SetImages(const std::vector<std::pair<std::string, std::string>>& globs);
  const std::vector<std::pair<std::string, std::string>>& globs() const { return globs_; }
  // NAME=GLOB for every sub-folder of `folder` holding PNG, JPEG or TIFF images (the rendered
  // twin's calibration/camN/), and the target file beside them (a .yaml naming a board type;
  // "" when none): what the room proposes when a folder is chosen.
  static std::vector<std::pair<std::string, std::string>> GlobsInFolder(const std::string& folder,
                                                                        std::string* target);
  // Where a project's calibration images likely are: the folder "calibration" beside its
  // experiment (the rendered twin's layout), when it exists; else "".
  std::string SuggestedImagesFolder() const;
  int cameras() const { return static_cast<int>(globs_.size()); }
  int frames() const;
  const std::string& camera_name(int c) const { return globs_[c].first; }

  // ---- Detection.
  DetectionJob MakeDetectionJob() const;  // std::logic_error without a target or images
  // Reads and searches every image (any thread; `threads` of its own). Progress: stage
  // "images searched", from the threads doing it (one at a time); a cancel of the
  // reporter's token stops at the next image (the answer says so).
  static DetectionAnswer Detect(const DetectionJob& job, const ProgressReporter& progress = {});
  // The answer (GUI thread); a cancelled one is kept for the images it reached.
  void SetDetections(DetectionAnswer answer);
  const std::vector<CalibrationImage>& images() const { return images_; }
  const CalibrationImage& image(ImageKey key) const;
  bool detected() const;  // every image was searched
  // "36 of 40 images: the target found in 34, 2 failed (…)"; the time.
  QString DetectionSummary() const;

  // ---- Calibration.
  // The input DetectInImages would give for these images, minus the excluded ones; the CLI's
  // options. std::logic_error before detection.
  CalibrationJob MakeCalibrationJob() const;
  static CalibrationRun Calibrate(const CalibrationJob& job);
  void SetCalibration(CalibrationRun run);
  // The run for the current excluded set (null: none yet, or another set is being computed).
  const CalibrationRun* run() const;
  const calib::CalibrationResult* result() const;
  // Calibrate has been asked for once, and the current excluded set has no run yet.
  bool NeedsCalibration() const;
  // RMS, points, outliers; baselines; the metric check; the warnings (several lines, plain text).
  QString CalibrationText() const;
  // The RMS of an image in the current result (nullopt: not used, or no result).
  std::optional<double> ImageRms(ImageKey key) const;
  // The used image with the largest RMS (nullopt: no result).
  std::optional<ImageKey> WorstImage() const;
  // Each detected point of the image with its residual (observed minus the calibrated rig's
  // projection of the target at the frame's pose); empty without a result or for an image not
  // used.
  std::vector<PointResidual> Residuals(ImageKey key) const;
  // The points of camera c's used images in cols x rows cells of its image.
  CoverageGrid Coverage(int c, int cols = 16, int rows = 16) const;

  // ---- Excluding images: one undoable step each (the stack's commands change the excluded set;
  // the caller re-runs when NeedsCalibration()).
  void ToggleExcluded(ImageKey key);
  const std::set<ImageKey>& excluded() const { return excluded_; }
  bool is_excluded(ImageKey key) const { return excluded_.count(key) != 0; }
  QUndoStack* undo_stack() const { return undo_.get(); }

  // ---- Save: the current result's rig to `path` (std::runtime_error naming the file when it
  // cannot be written, std::logic_error without a result); the project's `rig` then names it
  // (written through its own ".partial").
  void Save(const std::string& path);
  const std::string& rig_path() const { return rig_path_; }
  // The project's rig is now `rig` (a project opened again, e.g. after Save); the work stays.
  void SetProjectRig(const calib::Rig* rig, std::string rig_path);
  bool has_project() const { return !project_path_.empty(); }
  bool saved() const { return saved_; }
  // Expires with the presenter: a worker's answer checks it before it is delivered.
  std::weak_ptr<const int> lifetime() const { return alive_; }

 private:
  friend class ExcludeCommand;
  void SetExcluded(std::set<ImageKey> excluded);
  void ResetDetections();

  const calib::Rig* rig_;
  std::string rig_path_, project_path_;
  std::string target_spec_;
  std::optional<calib::CalibrationTarget> target_;
  std::vector<std::pair<std::string, std::string>> globs_;
  std::vector<std::vector<std::string>> files_;  // [camera][frame]
  std::vector<CalibrationImage> images_;         // camera-major
  double detection_wall_s_ = 0.0;
  bool detection_cancelled_ = false;
  bool calibrate_asked_ = false;
  bool saved_ = false;
  std::set<ImageKey> excluded_;
  std::map<std::set<ImageKey>, CalibrationRun> runs_;
  std::unique_ptr<QUndoStack> undo_;
  std::shared_ptr<const int> alive_ = std::make_shared<const int>(0);
};

}  // namespace netlab::gui
