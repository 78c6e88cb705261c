#include "app/gui/calibration_room.h"

#include <QHeaderView>
#include <QLabel>
#include <QMouseEvent>
#include <QPainter>
#include <QTableWidget>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace netlab::gui {
namespace {

constexpr double kFrustumDepthM = 0.4;  // how deep a camera's frustum is drawn
constexpr double kAxisM = 0.5;          // the world axes' length

QColor CameraColour(int i) {
  static const QColor colours[] = {QColor(31, 119, 180), QColor(255, 127, 14),
                                   QColor(44, 160, 44), QColor(214, 39, 40)};
  return colours[i % 4];
}

}  // namespace

RigSketch::RigSketch(QWidget* parent) : QWidget(parent) {
  setMinimumSize(300, 260);
  setAutoFillBackground(true);
  QPalette p = palette();
  p.setColor(QPalette::Window, QColor(250, 250, 250));
  setPalette(p);
  setToolTip("Drag to turn the rig");
}

void RigSketch::SetPresenter(const CalibrationPresenter* presenter) {
  presenter_ = presenter;
  update();
}

void RigSketch::SetView(double azimuth, double elevation) {
  azimuth_ = azimuth;
  elevation_ = std::clamp(elevation, -1.5, 1.5);
  update();
}

void RigSketch::mousePressEvent(QMouseEvent* event) { last_ = event->position(); }

void RigSketch::mouseMoveEvent(QMouseEvent* event) {
  const QPointF d = event->position() - last_;
  last_ = event->position();
  SetView(azimuth_ - d.x() * 0.01, elevation_ + d.y() * 0.01);
}

RigSketch::Fit RigSketch::MakeFit() const {
  Fit fit;
  // The screen's right and up in the world for this azimuth and elevation (z up).
  const double ca = std::cos(azimuth_), sa = std::sin(azimuth_);
  const double ce = std::cos(elevation_), se = std::sin(elevation_);
  fit.right = Eigen::Vector3d(-sa, ca, 0);
  fit.up = Eigen::Vector3d(-se * ca, -se * sa, ce);
  std::vector<Eigen::Vector3d> all = {Eigen::Vector3d::Zero(), Eigen::Vector3d(kAxisM, 0, 0),
                                      Eigen::Vector3d(0, kAxisM, 0), Eigen::Vector3d(0, 0, kAxisM)};
  if (presenter_ != nullptr)
    for (int c = 0; c < static_cast<int>(presenter_->rig().cameras.size()); ++c) {
      const auto f = presenter_->Frustum(c, kFrustumDepthM);
      all.insert(all.end(), f.begin(), f.end());
    }
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const Eigen::Vector3d& p : all) {
    x0 = std::min(x0, p.dot(fit.right)), x1 = std::max(x1, p.dot(fit.right));
    y0 = std::min(y0, p.dot(fit.up)), y1 = std::max(y1, p.dot(fit.up));
  }
  const QRectF area(30, 30, width() - 60, height() - 60);
  fit.scale = std::min(area.width() / std::max(x1 - x0, 1e-6),
                       area.height() / std::max(y1 - y0, 1e-6));
  fit.middle = area.center();
  fit.mx = (x0 + x1) / 2, fit.my = (y0 + y1) / 2;
  return fit;
}

QPointF RigSketch::Place(const Fit& fit, const Eigen::Vector3d& p) {
  return QPointF(fit.middle.x() + (p.dot(fit.right) - fit.mx) * fit.scale,
                 fit.middle.y() - (p.dot(fit.up) - fit.my) * fit.scale);
}

QPointF RigSketch::ToScreen(const Eigen::Vector3d& p) const { return Place(MakeFit(), p); }

void RigSketch::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.setPen(Qt::black);
  painter.drawText(QRectF(0, 4, width(), 18), Qt::AlignHCenter,
                   "The rig: cameras as frusta (0.4 m deep), world axes x red, y green, z blue "
                   "(0.5 m) — drag to turn");
  if (presenter_ == nullptr || presenter_->rig().cameras.empty()) return;
  std::vector<std::array<Eigen::Vector3d, 5>> frusta;
  for (int c = 0; c < static_cast<int>(presenter_->rig().cameras.size()); ++c)
    frusta.push_back(presenter_->Frustum(c, kFrustumDepthM));
  const Fit fit = MakeFit();
  const auto map = [&fit](const Eigen::Vector3d& p) { return Place(fit, p); };
  // The world frame.
  const QColor axes[] = {QColor(220, 40, 40), QColor(40, 170, 40), QColor(40, 80, 230)};
  for (int i = 0; i < 3; ++i) {
    painter.setPen(QPen(axes[i], 2.5));
    painter.drawLine(map(Eigen::Vector3d::Zero()), map(kAxisM * Eigen::Vector3d::Unit(i)));
  }
  // The cameras.
  for (int c = 0; c < static_cast<int>(frusta.size()); ++c) {
    const auto& f = frusta[c];
    painter.setPen(QPen(CameraColour(c), 1.8));
    for (int i = 1; i <= 4; ++i) {
      painter.drawLine(map(f[0]), map(f[i]));
      painter.drawLine(map(f[i]), map(f[i % 4 + 1]));
    }
    // The image's top edge thicker: which way is up in the camera.
    painter.setPen(QPen(CameraColour(c), 4));
    painter.drawLine(map(f[1]), map(f[2]));
    painter.setPen(Qt::black);
    painter.drawText(map(f[0]) + QPointF(6, -6),
                     QString::fromStdString(presenter_->rig().cameras[c].name));
  }
}

CalibrationRoom::CalibrationRoom(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  summary_ = new QLabel;
  summary_->setWordWrap(true);
  summary_->setObjectName("calibration_summary");
  layout->addWidget(summary_);
  table_ = new QTableWidget(0, 8);
  table_->setObjectName("rig_table");
  table_->setHorizontalHeaderLabels({"Camera", "Image (px)", "fx, fy (px)", "cx, cy (px)",
                                     "k1, k2", "Centre (m)", "Looks along", "Principal point"});
  table_->horizontalHeader()->setStretchLastSection(true);
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setMaximumHeight(170);
  layout->addWidget(table_);
  sketch_ = new RigSketch;
  layout->addWidget(sketch_, 1);
}

void CalibrationRoom::Show(const CalibrationPresenter* presenter) {
  summary_->setText(presenter ? presenter->Summary() : QString("No rig open."));
  sketch_->SetPresenter(presenter);
  const std::vector<RigCameraRow> rows = presenter ? presenter->Cameras() : std::vector<RigCameraRow>{};
  table_->setRowCount(static_cast<int>(rows.size()));
  const auto vec = [](const Eigen::Vector3d& v, int digits) {
    return QString("(%1, %2, %3)")
        .arg(v.x(), 0, 'f', digits)
        .arg(v.y(), 0, 'f', digits)
        .arg(v.z(), 0, 'f', digits);
  };
  for (int r = 0; r < static_cast<int>(rows.size()); ++r) {
    const RigCameraRow& c = rows[r];
    // Where the principal point lies: a value outside the image is a broken calibration.
    const bool inside = c.cx > 0 && c.cy > 0 && c.cx < c.width && c.cy < c.height;
    const QStringList cells = {
        QString::fromStdString(c.name),
        QString("%1 × %2").arg(c.width).arg(c.height),
        QString("%1, %2").arg(c.fx, 0, 'f', 1).arg(c.fy, 0, 'f', 1),
        QString("%1, %2").arg(c.cx, 0, 'f', 1).arg(c.cy, 0, 'f', 1),
        QString("%1, %2").arg(c.k1, 0, 'g', 3).arg(c.k2, 0, 'g', 3),
        vec(c.centre, 3),
        vec(c.direction, 2),
        inside ? QString("inside the image") : QString("OUTSIDE the image: check the rig")};
    for (int column = 0; column < cells.size(); ++column)
      table_->setItem(r, column, new QTableWidgetItem(cells[column]));
  }
  table_->resizeColumnsToContents();
}

}  // namespace netlab::gui
