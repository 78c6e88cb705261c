#pragma once
// The calibration room: from the target's images to a saved rig.yaml, as CalibrationPresenter
// (document/calibration_presenter.h) says. Along the top the inputs, as `netlab calibrate` takes
// them: the target (a spec or a board/foil/marker-map YAML) and each camera's images (NAME and
// GLOB; "Images folder…" fills them from a folder of camN/ sub-folders and its target file), then
// Detect (progress, Cancel), Calibrate and Save rig…. Below, left to right: the images (used,
// RMS, points, status; a click on the "Used" cell excludes or includes the image and re-runs,
// Ctrl+Z undoes), the selected image with its detected corners, its residual vectors (scaled, the
// scale written) and the coverage heat map of its camera, and the results: the calibration's text
// (RMS, baselines, metric check, warnings), a row per camera, the rig's table and its 3D sketch
// (cameras as frusta, the world frame's axes), rotated by dragging with the mouse.

#include <QImage>
#include <QPointF>
#include <QWidget>
#include <memory>
#include <optional>

#include "app/gui/document/calibration_presenter.h"
#include "app/gui/document/latest_request.h"

class QCheckBox;
class QLabel;
class QLineEdit;
class QProgressBar;
class QPushButton;
class QTableWidget;
class QTimer;

namespace netlab::gui {

// The rig seen from a direction the person turns (orthographic): frusta, names, world axes.
class RigSketch : public QWidget {
  Q_OBJECT

 public:
  explicit RigSketch(QWidget* parent = nullptr);
  void SetPresenter(const CalibrationPresenter* presenter);
  // The view direction: azimuth about world z and elevation above the xy plane (rad).
  void SetView(double azimuth, double elevation);
  double azimuth() const { return azimuth_; }
  double elevation() const { return elevation_; }
  QSize sizeHint() const override { return {600, 420}; }
  // Where a world point (m) is drawn in the widget, for the current view and size (the rig, the
  // frusta and the axes fitted into it).
  QPointF ToScreen(const Eigen::Vector3d& p_in_world) const;

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;

 private:
  // The screen's right and up in the world, the fitted scale (px/m) and centre, for this view.
  struct Fit {
    Eigen::Vector3d right, up;
    double scale = 1.0, mx = 0.0, my = 0.0;
    QPointF middle;
  };
  Fit MakeFit() const;
  static QPointF Place(const Fit& fit, const Eigen::Vector3d& p_in_world);

  const CalibrationPresenter* presenter_ = nullptr;
  double azimuth_ = -0.6, elevation_ = 0.45;
  QPointF last_;
};

// One calibration image fitted into the widget, with its detected corners (green), its residual
// vectors (red, scaled: the scale written in the corner) and its camera's coverage heat map.
class CalibrationImageView : public QWidget {
  Q_OBJECT

 public:
  explicit CalibrationImageView(QWidget* parent = nullptr);
  // `image` may be null (not loaded yet); the presenter's detections, residuals and coverage of
  // `key` are drawn over it.
  void Set(const CalibrationPresenter* presenter, std::optional<ImageKey> key, QImage image);
  void SetLayers(bool corners, bool residuals, bool coverage);
  // The residuals' drawing scale (a 1 px residual is drawn this many image px long); 0 without.
  double residual_scale() const { return residual_scale_; }
  // Where an image pixel is drawn.
  QPointF ToScreen(const Eigen::Vector2d& pixel) const;
  QSize sizeHint() const override { return {520, 520}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  QRectF ImageRect() const;
  const CalibrationPresenter* presenter_ = nullptr;
  std::optional<ImageKey> key_;
  QImage image_;
  bool corners_ = true, residuals_ = true, coverage_ = false;
  double residual_scale_ = 0.0;
};

class CalibrationRoom : public QWidget {
  Q_OBJECT

 public:
  explicit CalibrationRoom(QWidget* parent = nullptr);
  ~CalibrationRoom() override;
  // Shows `presenter` (null: nothing open); a new presenter drops the old one's work.
  void Show(CalibrationPresenter* presenter);

  // The parts a person (and a test) works with.
  QLineEdit* target_edit() const { return target_edit_; }
  QTableWidget* globs_table() const { return globs_; }
  QPushButton* folder_button() const { return folder_button_; }
  QPushButton* detect_button() const { return detect_button_; }
  QPushButton* cancel_button() const { return cancel_button_; }
  QPushButton* calibrate_button() const { return calibrate_button_; }
  QPushButton* save_button() const { return save_button_; }
  QProgressBar* progress() const { return progress_; }
  QTableWidget* images_table() const { return images_; }
  QTableWidget* cameras_table() const { return cameras_; }
  QLabel* status_label() const { return status_; }
  QLabel* results_label() const { return results_; }
  QLabel* summary_label() const { return summary_; }
  CalibrationImageView* image_view() const { return view_; }
  QTableWidget* table() const { return table_; }
  RigSketch* sketch() const { return sketch_; }
  // The images table's column a click on excludes or includes the row's image.
  static constexpr int kUsedColumn = 2;
  // Detection, calibration or an image load is under way.
  bool busy() const;
  // Fills the inputs from a folder (GlobsInFolder), as "Images folder…" does after its dialog.
  void FillFromFolder(const QString& folder);
  // Save rig… without its dialog.
  bool SaveTo(const QString& path);

 signals:
  // Save wrote the rig and the project now names it.
  void rigSaved(const QString& path);

 private:
  bool ApplyInputs();  // the inputs into the presenter; false (said) when they are wrong
  void Detect();
  void Calibrate();
  void Rerun();    // when the excluded set has no result yet
  void Refresh();  // every part from the presenter
  void RefreshImages();
  void SelectImage(int row);
  void ShowError(const QString& text);
  bool Alive() const;

  CalibrationPresenter* presenter_ = nullptr;
  std::weak_ptr<const int> alive_;
  QLineEdit* target_edit_ = nullptr;
  QTableWidget* globs_ = nullptr;
  QPushButton *folder_button_ = nullptr, *target_button_ = nullptr, *detect_button_ = nullptr,
              *cancel_button_ = nullptr, *calibrate_button_ = nullptr, *save_button_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QLabel* status_ = nullptr;
  QTableWidget* images_ = nullptr;
  QCheckBox *show_corners_ = nullptr, *show_residuals_ = nullptr, *show_coverage_ = nullptr;
  CalibrationImageView* view_ = nullptr;
  QLabel* view_caption_ = nullptr;
  QLabel* results_ = nullptr;
  QTableWidget* cameras_ = nullptr;
  QLabel* summary_ = nullptr;
  QTableWidget* table_ = nullptr;
  RigSketch* sketch_ = nullptr;
  QTimer* progress_timer_ = nullptr;
  std::optional<ImageKey> selected_;
  std::optional<std::set<ImageKey>> requested_;  // the excluded set of the calibration asked for
  std::shared_ptr<std::atomic<int>> done_ = std::make_shared<std::atomic<int>>(0);
  std::shared_ptr<std::atomic<int>> total_ = std::make_shared<std::atomic<int>>(0);
  struct Loaded {
    ImageKey key;
    QImage image;
  };
  LatestRequest<DetectionAnswer> detector_;
  LatestRequest<CalibrationRun> calibrator_;
  LatestRequest<Loaded> loader_;
};

}  // namespace netlab::gui
