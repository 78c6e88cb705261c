#pragma once
// The calibration room: the project's rig as CalibrationPresenter (document/
// calibration_presenter.h) describes it. A line of summary with the baselines, one table row per
// camera, and a 3D sketch of the rig (cameras as frusta, the world frame's axes), rotated by
// dragging with the mouse.

#include <QPointF>
#include <QWidget>

#include "app/gui/document/calibration_presenter.h"

class QLabel;
class QTableWidget;

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

class CalibrationRoom : public QWidget {
  Q_OBJECT

 public:
  explicit CalibrationRoom(QWidget* parent = nullptr);
  // Shows `presenter`'s rig (null: nothing open).
  void Show(const CalibrationPresenter* presenter);
  QTableWidget* table() const { return table_; }
  RigSketch* sketch() const { return sketch_; }

 private:
  QLabel* summary_ = nullptr;
  QTableWidget* table_ = nullptr;
  RigSketch* sketch_ = nullptr;
};

}  // namespace netlab::gui
