#include "app/gui/reconstruction_room.h"

#include <Eigen/Eigenvalues>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QProgressBar>
#include <QPushButton>
#include <QSlider>
#include <QSplitter>
#include <QTableView>
#include <QTableWidget>
#include <QTimer>
#include <QVBoxLayout>
#include <QWheelEvent>
#include <algorithm>
#include <array>
#include <cmath>

#include "app/gui/document/missing_knots.h"
#include "app/gui/document/project.h"
#include "app/gui/document/session.h"

namespace netlab::gui {
namespace {

constexpr double kSigmaScale = 10.0;  // a knot's sigma is drawn this many times its size

}  // namespace

// ---------------------------------------------------------------------------------------------
// NetView3D

NetView3D::NetView3D(QWidget* parent) : QWidget(parent) {
  setMinimumSize(300, 240);
  setMouseTracking(false);
  setFocusPolicy(Qt::ClickFocus);
}

void NetView3D::Set(const KnotTracks* tracks, const calib::Rig* rig, const recon::Target* target,
                    int cols) {
  const bool changed = tracks != tracks_ || rig != rig_;
  tracks_ = tracks;
  rig_ = rig;
  target_ = target;
  cols_ = std::max(1, cols);
  if (changed) Fit();
  update();
}

void NetView3D::SetRow(int row) {
  if (row == row_) return;
  row_ = row;
  update();
}

void NetView3D::SetView(double yaw, double pitch, double distance) {
  yaw_ = yaw;
  pitch_ = std::clamp(pitch, -1.55, 1.55);
  distance_ = std::clamp(distance, 0.05, 1e4);
  update();
}

void NetView3D::Fit() {
  // The centre: the knots' mean over the shot (else the cameras'); the distance: the nearest at
  // which the cameras and every knot of the shot are in view.
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d knots = Eigen::Vector3d::Zero();
  int n = 0;
  if (tracks_ != nullptr)
    for (size_t i = 0; i < tracks_->position.size(); ++i)
      if (tracks_->valid[i] && tracks_->position[i].allFinite()) {
        knots += tracks_->position[i];
        points.push_back(tracks_->position[i]);
        ++n;
      }
  std::vector<Eigen::Vector3d> cameras;
  if (rig_ != nullptr)
    for (const calib::Camera& c : rig_->cameras) cameras.push_back(c.Center());
  centre_.setZero();
  if (n > 0) {
    centre_ = knots / n;
  } else if (!cameras.empty()) {
    for (const auto& p : cameras) centre_ += p;
    centre_ /= static_cast<double>(cameras.size());
  }
  points.insert(points.end(), cameras.begin(), cameras.end());
  // A point (x, y, z) of the turned frame is in view (within 45 % of the view's smaller side of
  // its middle) from d >= 2 max(|x|, |z|) - y.
  const double cy = std::cos(yaw_), sy = std::sin(yaw_), cp = std::cos(pitch_),
               sp = std::sin(pitch_);
  distance_ = 1.0;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d q = p - centre_;
    const double x1 = cy * q.x() + sy * q.y(), y1 = -sy * q.x() + cy * q.y(), z1 = q.z();
    const double y2 = cp * y1 + sp * z1, z2 = -sp * y1 + cp * z1;
    distance_ = std::max(distance_, 2.0 * std::max(std::abs(x1), std::abs(z2)) - y2);
  }
}

std::optional<QPointF> NetView3D::ToScreen(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d q = p - centre_;
  const double cy = std::cos(yaw_), sy = std::sin(yaw_), cp = std::cos(pitch_),
               sp = std::sin(pitch_);
  // Turned about world z by yaw, then tilted about the screen's x axis by pitch; the eye looks
  // along +y from `distance` behind the centre.
  const double x1 = cy * q.x() + sy * q.y(), y1 = -sy * q.x() + cy * q.y(), z1 = q.z();
  const double y2 = cp * y1 + sp * z1, z2 = -sp * y1 + cp * z1;
  const double depth = distance_ + y2;
  if (depth < 0.02 * distance_) return std::nullopt;
  const double f = 0.9 * std::min(width(), height());
  return QPointF(width() / 2.0 + f * x1 / depth, height() / 2.0 - f * z2 / depth);
}

void NetView3D::paintEvent(QPaintEvent*) {
  ++paints_;
  QPainter painter(this);
  painter.fillRect(rect(), QColor(24, 26, 30));
  painter.setRenderHint(QPainter::Antialiasing, true);
  const auto line = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const auto pa = ToScreen(a), pb = ToScreen(b);
    if (pa && pb) painter.drawLine(*pa, *pb);
  };
  // The world axes at the origin, 0.5 m: x red, y green, z blue.
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  painter.setPen(QPen(QColor(220, 70, 70), 1.5));
  line(o, 0.5 * Eigen::Vector3d::UnitX());
  painter.setPen(QPen(QColor(70, 200, 70), 1.5));
  line(o, 0.5 * Eigen::Vector3d::UnitY());
  painter.setPen(QPen(QColor(80, 120, 255), 1.5));
  line(o, 0.5 * Eigen::Vector3d::UnitZ());
  // The rig's cameras: a pyramid 0.25 m deep along the optical axis, named.
  if (rig_ != nullptr) {
    painter.setPen(QPen(QColor(200, 200, 200), 1.0));
    for (const calib::Camera& c : rig_->cameras) {
      const Eigen::Vector3d centre = c.Center();
      const Eigen::Quaterniond world_from_cam = c.cam_from_world.rotation.conjugate();
      const double w = c.intrinsics.width > 0 ? c.intrinsics.width / (2 * c.intrinsics.fx) : 0.4;
      const double h = c.intrinsics.height > 0 ? c.intrinsics.height / (2 * c.intrinsics.fy) : 0.4;
      std::array<Eigen::Vector3d, 4> corner;
      const double depth = 0.25;
      corner[0] = centre + world_from_cam * Eigen::Vector3d(-w, -h, 1) * depth;
      corner[1] = centre + world_from_cam * Eigen::Vector3d(w, -h, 1) * depth;
      corner[2] = centre + world_from_cam * Eigen::Vector3d(w, h, 1) * depth;
      corner[3] = centre + world_from_cam * Eigen::Vector3d(-w, h, 1) * depth;
      for (int i = 0; i < 4; ++i) {
        line(centre, corner[i]);
        line(corner[i], corner[(i + 1) % 4]);
      }
      if (const auto p = ToScreen(centre))
        painter.drawText(*p + QPointF(4, -4), QString::fromStdString(c.name));
    }
  }
  if (tracks_ == nullptr || row_ < 0 || row_ >= tracks_->frames()) {
    painter.setPen(QColor(200, 200, 200));
    painter.drawText(
        rect().adjusted(10, 10, -10, -10), Qt::AlignTop | Qt::AlignLeft,
        tracks_ == nullptr ? "No tracks yet: Triangulate." : "No tracks at this frame.");
    return;
  }
  const int knots = tracks_->knots();
  const double time = tracks_->time[row_];
  // The target at this frame's time.
  if (target_ != nullptr) {
    painter.setPen(QPen(QColor(150, 150, 160), 1.2));
    painter.setBrush(Qt::NoBrush);
    for (const recon::TargetSolid& s : target_->solids) {
      const double at =
          tracks_->frame_index.empty() ? time : tracks_->frame_index[row_] / target_->fps;
      const Eigen::Vector3d centre = s.center + at * s.velocity;
      if (s.shape == recon::TargetSolid::Shape::kSphere) {
        const auto p = ToScreen(centre);
        const auto q = ToScreen(centre + s.radius * Eigen::Vector3d::UnitZ());
        if (p && q) {
          const double r = std::hypot(p->x() - q->x(), p->y() - q->y());
          painter.drawEllipse(*p, r, r);
        }
        continue;
      }
      std::array<Eigen::Vector3d, 8> v;
      for (int i = 0; i < 8; ++i)
        v[i] = centre + s.orientation * Eigen::Vector3d((i & 1 ? 1 : -1) * s.half_extents.x(),
                                                        (i & 2 ? 1 : -1) * s.half_extents.y(),
                                                        (i & 4 ? 1 : -1) * s.half_extents.z());
      for (int i = 0; i < 8; ++i)
        for (int bit : {1, 2, 4})
          if (!(i & bit)) line(v[i], v[i | bit]);
    }
  }
  // The selected knots' trajectories over the shot.
  painter.setPen(QPen(QColor(255, 200, 60, 200), 1.2));
  for (int k : selected_) {
    if (k < 0 || k >= knots) continue;
    QPainterPath path;
    bool open = false;
    for (int t = 0; t < tracks_->frames(); ++t) {
      const auto p = tracks_->Valid(t, k) ? ToScreen(tracks_->Position(t, k)) : std::nullopt;
      if (!p) {
        open = false;
        continue;
      }
      open ? path.lineTo(*p) : path.moveTo(*p);
      open = true;
    }
    painter.drawPath(path);
  }
  // The links between valid neighbours, then the knots.
  const auto usable = [&](int k) {
    return tracks_->Valid(row_, k) || tracks_->Degenerate(row_, k);
  };
  painter.setPen(QPen(QColor(120, 200, 255, 170), 1.0));
  for (int k = 0; k < knots; ++k) {
    if (!usable(k)) continue;
    const int r = tracks_->grid[k][0], c = tracks_->grid[k][1];
    for (const auto& [dr, dc] : {std::pair{0, 1}, std::pair{1, 0}}) {
      const int n = tracks_->FindKnot(r + dr, c + dc);
      if (n >= 0 && usable(n)) line(tracks_->Position(row_, k), tracks_->Position(row_, n));
    }
  }
  for (int k = 0; k < knots; ++k) {
    if (!usable(k)) continue;
    const auto p = ToScreen(tracks_->Position(row_, k));
    if (!p) continue;
    const bool degenerate = tracks_->Degenerate(row_, k);
    const bool selected = selected_.count(k) != 0;
    painter.setPen(Qt::NoPen);
    painter.setBrush(degenerate ? QColor(255, 70, 70)
                     : selected ? QColor(255, 200, 60)
                                : QColor(255, 150, 0));
    painter.drawEllipse(*p, selected ? 4.5 : 3.0, selected ? 4.5 : 3.0);
    if (show_sigma_ && !tracks_->covariance.empty()) {
      // The 1-sigma ellipsoid (scaled) as the view shows it: the covariance carried to the
      // screen by the projection's Jacobian (finite differences), drawn as its ellipse.
      const Eigen::Matrix3d& cov = tracks_->covariance[static_cast<size_t>(row_) * knots + k];
      const Eigen::Vector3d& x = tracks_->Position(row_, k);
      const double h = 1e-4 * distance_;
      Eigen::Matrix<double, 2, 3> jacobian;
      bool ok = true;
      for (int a = 0; a < 3 && ok; ++a) {
        const auto q = ToScreen(x + h * Eigen::Vector3d::Unit(a));
        ok = q.has_value();
        if (ok) jacobian.col(a) = Eigen::Vector2d(q->x() - p->x(), q->y() - p->y()) / h;
      }
      if (ok) {
        const Eigen::Matrix2d screen =
            kSigmaScale * kSigmaScale * jacobian * cov * jacobian.transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(screen);
        const double a = std::sqrt(std::max(0.0, eig.eigenvalues()[1]));
        const double b = std::sqrt(std::max(0.0, eig.eigenvalues()[0]));
        const Eigen::Vector2d axis = eig.eigenvectors().col(1);
        painter.save();
        painter.translate(*p);
        painter.rotate(std::atan2(axis.y(), axis.x()) * 180.0 / M_PI);
        painter.setBrush(Qt::NoBrush);
        painter.setPen(QPen(QColor(255, 120, 255, 200), 1.0));
        painter.drawEllipse(QPointF(0, 0), std::max(a, 0.5), std::max(b, 0.5));
        painter.restore();
      }
    }
  }
  painter.setPen(QColor(210, 210, 210));
  painter.drawText(rect().adjusted(8, 6, -8, -6), Qt::AlignBottom | Qt::AlignLeft,
                   QString("t = %1 s%2 · drag: turn · right drag: pan · wheel: zoom · double "
                           "click: fit")
                       .arg(time, 0, 'f', 4)
                       .arg(show_sigma_ ? QString(" · σ ×%1").arg(kSigmaScale) : QString()));
}

void NetView3D::mousePressEvent(QMouseEvent* event) {
  press_ = last_ = event->position();
  button_ = event->button();
  moved_ = false;
}

void NetView3D::mouseMoveEvent(QMouseEvent* event) {
  const QPointF d = event->position() - last_;
  last_ = event->position();
  if ((event->position() - press_).manhattanLength() > 3) moved_ = true;
  if (button_ == Qt::LeftButton) {
    SetView(yaw_ - 0.01 * d.x(), pitch_ + 0.01 * d.y(), distance_);
  } else if (button_ == Qt::RightButton || button_ == Qt::MiddleButton) {
    // Pan in the screen's plane: its right and up in the world.
    const double cy = std::cos(yaw_), sy = std::sin(yaw_), cp = std::cos(pitch_),
                 sp = std::sin(pitch_);
    const Eigen::Vector3d right(cy, sy, 0.0);
    const Eigen::Vector3d up(sy * sp, -cy * sp, cp);
    const double m_per_px = distance_ / (0.9 * std::min(width(), height()));
    centre_ += m_per_px * (-d.x() * right + d.y() * up);
    update();
  }
}

void NetView3D::mouseReleaseEvent(QMouseEvent* event) {
  const bool click = !moved_ && button_ == Qt::LeftButton;
  button_ = Qt::NoButton;
  if (!click || tracks_ == nullptr || row_ < 0 || row_ >= tracks_->frames()) return;
  int best = -1;
  double best_d = 12.0;
  for (int k = 0; k < tracks_->knots(); ++k) {
    if (!tracks_->Valid(row_, k) && !tracks_->Degenerate(row_, k)) continue;
    const auto p = ToScreen(tracks_->Position(row_, k));
    if (!p) continue;
    const double d = std::hypot(p->x() - event->position().x(), p->y() - event->position().y());
    if (d < best_d) best_d = d, best = k;
  }
  if (best < 0) return;
  if (event->modifiers() & Qt::ControlModifier) {
    if (!selected_.erase(best)) selected_.insert(best);
  } else {
    selected_ = {best};
  }
  update();
  emit knotClicked(best);
}

void NetView3D::wheelEvent(QWheelEvent* event) {
  SetView(yaw_, pitch_, distance_ * std::pow(0.999, event->angleDelta().y()));
}

// ---------------------------------------------------------------------------------------------
// ReconstructionRoom

ReconstructionRoom::ReconstructionRoom(QWidget* parent)
    : QWidget(parent), triangulator_(this, [this](TriangulationRun run) {
        progress_timer_->stop();
        if (!Alive()) return;
        const bool cancelled = run.cancelled;
        const QString error = QString::fromStdString(run.error);
        if (run.result) progress_->setValue(1000);
        presenter_->SetRun(std::move(run));
        QString saved;
        if (!cancelled && error.isEmpty()) {
          try {
            presenter_->SaveToProject();
            saved = " Written to " + QString::fromStdString(presenter_->tracks_path()) +
                    " (the project's tracks).";
          } catch (const std::exception& e) {
            saved = QString(" Not saved: ") + e.what();
          }
        }
        status_->setText(cancelled         ? "Triangulation cancelled."
                         : error.isEmpty() ? "Labels triangulated." + saved
                                           : "Triangulation failed: " + error);
        Refresh();
      }) {
  auto* layout = new QVBoxLayout(this);
  auto* options = new QHBoxLayout;
  options->addWidget(new QLabel("Bundle adjustment"));
  adjustment_ = new QComboBox;
  adjustment_->addItems({"points", "none", "rig"});
  adjustment_->setToolTip(
      "As netlab triangulate --ba: none (triangulation only), points (the "
      "default: Ceres over the sequence with the priors), rig (the cameras' "
      "extrinsics first)");
  options->addWidget(adjustment_);
  const auto spin = [&](const QString& label, const QString& tip, double max, int decimals,
                        const QString& zero) {
    options->addWidget(new QLabel(label));
    auto* box = new QDoubleSpinBox;
    box->setRange(0.0, max);
    box->setDecimals(decimals);
    box->setSingleStep(std::pow(10.0, -decimals + 1));
    box->setSpecialValueText(zero);
    box->setToolTip(tip);
    options->addWidget(box);
    return box;
  };
  sigma_ = spin("Labels' σ (px)", "--sigma-px: the labels' noise; 0: from the residuals", 10.0, 3,
                "from the residuals");
  link_ = spin("Link length (m)", "--link-length: adjacent knots this far apart (a prior); 0: off",
               10.0, 4, "off");
  smooth_ =
      spin("Smoothing σ (m)",
           "--smooth-sigma: p[t-1] - 2 p[t] + p[t+1] = 0 with this sigma; 0: off", 1.0, 5, "off");
  unreviewed_ = new QCheckBox("Labels under review too");
  unreviewed_->setToolTip("--use-unreviewed");
  options->addWidget(unreviewed_);
  options->addStretch(1);
  layout->addLayout(options);
  auto* actions = new QHBoxLayout;
  triangulate_button_ = new QPushButton("Triangulate");
  actions->addWidget(triangulate_button_);
  cancel_button_ = new QPushButton("Cancel");
  actions->addWidget(cancel_button_);
  progress_ = new QProgressBar;
  progress_->setRange(0, 1000);
  progress_->setMaximumWidth(200);
  actions->addWidget(progress_);
  export_button_ = new QPushButton("Export…");
  export_button_->setToolTip(
      "tracks.h5, and xyzpts.csv / xyzres.csv beside it for DLTdv users "
      "(netlab triangulate --out, --csv)");
  actions->addWidget(export_button_);
  actions->addStretch(1);
  layout->addLayout(actions);
  status_ = new QLabel("Triangulate the labels: their 3D tracks, residuals and sigma.");
  status_->setWordWrap(true);
  layout->addWidget(status_);
  summary_ = new QLabel;
  summary_->setWordWrap(true);
  layout->addWidget(summary_);

  auto* splitter = new QSplitter(Qt::Horizontal);
  auto* left = new QWidget;
  auto* left_layout = new QVBoxLayout(left);
  left_layout->setContentsMargins(0, 0, 0, 0);
  left_layout->addWidget(new QLabel("Outliers and degenerate points (a click: the label)"));
  problems_ = new QTableWidget(0, 5);
  problems_->setObjectName("reconstruction_problems");
  problems_->setHorizontalHeaderLabels({"Kind", "Frame", "Knot", "Camera", "Why"});
  problems_->horizontalHeader()->setStretchLastSection(true);
  problems_->setSelectionBehavior(QAbstractItemView::SelectRows);
  problems_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  problems_->verticalHeader()->hide();
  left_layout->addWidget(problems_, 1);
  auto* knots_row = new QHBoxLayout;
  knots_row->addWidget(new QLabel("This frame's knots (a click: the label):"));
  knot_filter_ = new QComboBox;
  knot_filter_->addItems({"all", "outliers", "degenerate"});
  knot_filter_->setToolTip(
      "all: every knot of the net; outliers: the knots with a view left out as an outlier; "
      "degenerate: the points left out for their sigma");
  knots_row->addWidget(knot_filter_);
  knots_row->addStretch(1);
  left_layout->addLayout(knots_row);
  knot_model_ = new KnotErrorModel(this);
  knot_table_ = new QTableView;
  knot_table_->setObjectName("reconstruction_knot_errors");
  knot_table_->setModel(knot_model_);
  knot_table_->setSortingEnabled(true);
  knot_table_->sortByColumn(KnotErrorModel::kKnot, Qt::AscendingOrder);
  knot_table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  knot_table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  knot_table_->verticalHeader()->hide();
  knot_table_->verticalHeader()->setDefaultSectionSize(knot_table_->fontMetrics().height() + 6);
  knot_table_->horizontalHeader()->setStretchLastSection(true);
  left_layout->addWidget(knot_table_, 2);  // the frame's 36..121 knots get the room
  knot_ = new QLabel("Click a knot in the 3D view: its residual and sigma.");
  knot_->setWordWrap(true);
  left_layout->addWidget(knot_);
  splitter->addWidget(left);
  auto* right = new QWidget;
  auto* right_layout = new QVBoxLayout(right);
  right_layout->setContentsMargins(0, 0, 0, 0);
  view_ = new NetView3D;
  right_layout->addWidget(view_, 1);
  auto* slider_row = new QHBoxLayout;
  slider_ = new QSlider(Qt::Horizontal);
  slider_row->addWidget(slider_, 1);
  frame_label_ = new QLabel;
  frame_label_->setMinimumWidth(160);
  slider_row->addWidget(frame_label_);
  show_sigma_ = new QCheckBox(QString("σ (×%1)").arg(kSigmaScale));
  slider_row->addWidget(show_sigma_);
  right_layout->addLayout(slider_row);
  splitter->addWidget(right);
  splitter->setStretchFactor(0, 2);
  splitter->setStretchFactor(1, 3);
  splitter->setSizes({560, 840});  // the problems' reasons readable beside the 3D view
  layout->addWidget(splitter, 1);

  progress_timer_ = new QTimer(this);
  progress_timer_->setInterval(100);
  connect(progress_timer_, &QTimer::timeout, this,
          [this] { progress_->setValue(static_cast<int>(1000 * fraction_->load())); });
  connect(triangulate_button_, &QPushButton::clicked, this, &ReconstructionRoom::Triangulate);
  connect(cancel_button_, &QPushButton::clicked, this, [this] {
    if (!triangulator_.pending()) return;
    // The engine stops only between its stages: its answer is forgotten now.
    triangulator_.Cancel();
    triangulator_.Drop();
    progress_timer_->stop();
    status_->setText("Triangulation cancelled.");
    Refresh();
  });
  connect(export_button_, &QPushButton::clicked, this, [this] {
    const QString path =
        QFileDialog::getSaveFileName(this, "Export the tracks", "tracks.h5", "Knot tracks (*.h5)");
    if (!path.isEmpty()) ExportTo(path);
  });
  connect(slider_, &QSlider::valueChanged, this, [this](int t) { SetFrame(t); });
  connect(show_sigma_, &QCheckBox::toggled, view_, &NetView3D::SetShowSigma);
  connect(view_, &NetView3D::knotClicked, this, [this](int) { RefreshKnot(); });
  connect(knot_filter_, &QComboBox::currentIndexChanged, this, [this] { RefreshKnotTable(); });
  connect(knot_table_, &QTableView::clicked, this, [this](const QModelIndex& index) {
    if (!presenter_ || !index.isValid()) return;
    const KnotErrorModel::Row& r = knot_model_->row(index.row());
    int camera = -1;  // the first outlier view's camera, else any that has the label
    if (!r.outlier_cameras.empty()) {
      const std::string name = knot_model_->camera_name(r.outlier_cameras.front());
      const auto& names = presenter_->session().camera_names();
      for (int c = 0; c < static_cast<int>(names.size()); ++c)
        if (names[c] == name) camera = c;
    }
    emit showLabel(camera, frame_, r.knot);
  });
  connect(problems_, &QTableWidget::cellClicked, this, [this](int row, int) {
    if (row < 0 || row >= static_cast<int>(rows_.size())) return;
    const Problem& p = rows_[row];
    emit showLabel(p.camera, p.t, p.knot);
  });
  Refresh();
}

ReconstructionRoom::~ReconstructionRoom() = default;

bool ReconstructionRoom::Alive() const { return presenter_ != nullptr && !alive_.expired(); }

void ReconstructionRoom::Show(ReconstructionPresenter* presenter) {
  if (presenter != presenter_) {
    triangulator_.Drop();
    progress_timer_->stop();
    presenter_ = presenter;
    alive_ = presenter ? presenter->lifetime() : std::weak_ptr<const int>();
    target_ = recon::Target();
    if (presenter_ && !presenter_->session().project().target.empty()) {
      try {
        target_ = LoadTarget(presenter_->session().project().target, presenter_->session().fps());
      } catch (const std::exception& e) {
        status_->setText(QString("The target is not drawn: ") + e.what());
      }
    }
    view_->SetSelected({});
    // The project's tracks, until the labels are triangulated here.
    if (presenter_ && presenter_->tracks() == nullptr) {
      try {
        const Project project = LoadProject(presenter_->session().project().path);
        if (!project.tracks.empty()) presenter_->LoadTracks(project.tracks);
      } catch (const std::exception& e) {
        status_->setText(QString("The project's tracks are not read: ") + e.what());
      }
    }
    if (presenter_) {
      slider_->blockSignals(true);
      slider_->setRange(0, std::max(0, presenter_->session().frames() - 1));
      slider_->blockSignals(false);
    }
  }
  Refresh();
}

void ReconstructionRoom::SetFrame(int t) {
  if (!presenter_) return;
  t = std::clamp(t, 0, std::max(0, presenter_->session().frames() - 1));
  if (slider_->value() != t) {
    slider_->blockSignals(true);
    slider_->setValue(t);
    slider_->blockSignals(false);
  }
  const bool changed = t != frame_;
  frame_ = t;
  view_->SetRow(presenter_->TrackRow(t));
  frame_label_->setText(presenter_->FrameStatus(t));
  RefreshKnot();
  RefreshKnotTable();
  if (changed) emit frameChanged(t);
}

void ReconstructionRoom::RefreshKnotTable() {
  const int row = presenter_ ? presenter_->TrackRow(frame_) : -1;
  knot_model_->Set(presenter_ ? presenter_->tracks() : nullptr, row,
                   static_cast<KnotErrorModel::Filter>(knot_filter_->currentIndex()));
  knot_table_->resizeColumnsToContents();
  knot_table_->horizontalHeader()->setStretchLastSection(true);
}

void ReconstructionRoom::Triangulate() {
  if (!presenter_) return;
  TriangulationOptions options;
  recon::ParseAdjustment(adjustment_->currentText().toStdString(), &options.adjustment);
  options.sigma_px = sigma_->value();
  options.link_length_m = link_->value();
  options.smooth_sigma_m = smooth_->value();
  options.use_unreviewed = unreviewed_->isChecked();
  TriangulationJob job;
  try {
    job = presenter_->MakeJob(options);
  } catch (const std::exception& e) {
    status_->setText(QString("Cannot triangulate: ") + e.what());
    return;
  }
  *fraction_ = 0.0;
  progress_->setValue(0);
  progress_timer_->start();
  status_->setText("Triangulating the labels…");
  auto fraction = fraction_;
  triangulator_.Request([job = std::move(job), fraction](const CancelToken& cancel) {
    return ReconstructionPresenter::Triangulate(
        job, ProgressReporter([fraction](const Progress& p) { *fraction = p.fraction(); }, cancel));
  });
  Refresh();
}

bool ReconstructionRoom::ExportTo(const QString& tracks_path) {
  if (!presenter_) return false;
  const std::string prefix = QFileInfo(tracks_path).absolutePath().toStdString() + "/";
  try {
    presenter_->Export(tracks_path.toStdString(), prefix);
  } catch (const std::exception& e) {
    status_->setText(QString("Not exported: ") + e.what());
    return false;
  }
  status_->setText(QString("Exported %1, %2xyzpts.csv and %2xyzres.csv")
                       .arg(tracks_path, QString::fromStdString(prefix)));
  return true;
}

void ReconstructionRoom::Refresh() {
  const bool open = presenter_ != nullptr;
  triangulate_button_->setEnabled(open && !triangulator_.pending());
  cancel_button_->setEnabled(triangulator_.pending());
  export_button_->setEnabled(open && presenter_->tracks() != nullptr);
  rows_.clear();
  problems_->setRowCount(0);
  if (!open) {
    view_->Set(nullptr, nullptr, nullptr, 1);
    return;
  }
  const Session& session = presenter_->session();
  QString summary = presenter_->Summary();
  if (const size_t n = presenter_->updated_rows().size())
    summary += QString(
                   "\n%1 frame%2 triangulated again after an edit of the labels (knot by knot, "
                   "no adjustment): Triangulate renews the whole shot")
                   .arg(n)
                   .arg(n == 1 ? "" : "s");
  summary_->setText(summary);
  view_->Set(presenter_->tracks(), &session.rig(), target_.empty() ? nullptr : &target_,
             session.project().cols);
  // The problems: each outlier observation and degenerate point, in frame order.
  const int cols = session.project().cols;
  const auto row_of = [&](int frame_number) {
    const std::vector<int>& numbers = session.frame_numbers();
    const auto it = std::lower_bound(numbers.begin(), numbers.end(), frame_number);
    return it != numbers.end() && *it == frame_number ? static_cast<int>(it - numbers.begin()) : -1;
  };
  if (const TriangulationRun* run = presenter_->run(); run && run->result) {
    const recon::SequenceResult& r = *run->result;
    for (const recon::ObservationOutlier& o : r.outliers) {
      Problem p;
      p.t = row_of(o.frame);
      if (p.t < 0) continue;
      p.knot = o.knot;
      const std::string& name = r.rig.cameras[o.camera].name;
      for (int c = 0; c < session.cameras(); ++c)
        if (session.camera_names()[c] == name) p.camera = c;
      p.why = std::isnan(o.residual_px)
                  ? QString("no point triangulated from its views")
                  : QString("%1 px from the point's projection (threshold %2 px)")
                        .arg(o.residual_px, 0, 'f', 2)
                        .arg(r.outlier_threshold_px, 0, 'f', 2);
      rows_.push_back(p);
    }
    for (const recon::DegeneratePoint& d : r.degenerate_points) {
      Problem p;
      p.degenerate = true;
      p.t = row_of(d.frame);
      if (p.t < 0) continue;
      p.knot = d.knot;
      p.why = QString::fromStdString(d.reason);
      rows_.push_back(p);
    }
    std::stable_sort(rows_.begin(), rows_.end(),
                     [](const Problem& a, const Problem& b) { return a.t < b.t; });
  }
  problems_->setRowCount(static_cast<int>(rows_.size()));
  for (size_t i = 0; i < rows_.size(); ++i) {
    const Problem& p = rows_[i];
    const int row = static_cast<int>(i);
    problems_->setItem(row, 0, new QTableWidgetItem(p.degenerate ? "degenerate" : "outlier"));
    problems_->setItem(row, 1, new QTableWidgetItem(QString::number(session.frame_number(p.t))));
    problems_->setItem(
        row, 2, new QTableWidgetItem(QString("(%1,%2)").arg(p.knot / cols).arg(p.knot % cols)));
    problems_->setItem(row, 3,
                       new QTableWidgetItem(
                           p.camera >= 0 ? QString::fromStdString(session.camera_names()[p.camera])
                                         : QString("—")));
    problems_->setItem(row, 4, new QTableWidgetItem(p.why));
    problems_->item(row, 4)->setToolTip(p.why);
  }
  problems_->resizeColumnsToContents();
  problems_->horizontalHeader()->setStretchLastSection(true);
  SetFrame(frame_);
}

void ReconstructionRoom::RefreshKnot() {
  const KnotTracks* tracks = presenter_ ? presenter_->tracks() : nullptr;
  const int row = view_->row();
  if (tracks == nullptr || row < 0 || view_->selected().empty()) {
    knot_->setText("Click a knot in the 3D view: its residual and sigma.");
    return;
  }
  const int k = *view_->selected().begin();
  const int cols = presenter_->session().project().cols;
  const size_t i = static_cast<size_t>(row) * tracks->knots() + k;
  QString text = QString("Knot (%1,%2) at frame %3: ")
                     .arg(k / cols)
                     .arg(k % cols)
                     .arg(presenter_->session().frame_number(frame_));
  if (!tracks->Valid(row, k) && !tracks->Degenerate(row, k)) {
    knot_->setText(text + "not triangulated.");
    return;
  }
  const Eigen::Vector3d& p = tracks->Position(row, k);
  text +=
      QString("(%1, %2, %3) m").arg(p.x(), 0, 'f', 4).arg(p.y(), 0, 'f', 4).arg(p.z(), 0, 'f', 4);
  if (!tracks->reprojection_error_px.empty() && std::isfinite(tracks->reprojection_error_px[i]))
    text += QString("; reprojection RMS %1 px").arg(tracks->reprojection_error_px[i], 0, 'f', 3);
  if (!tracks->covariance.empty()) {
    const Eigen::Vector3d ev =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(tracks->covariance[i]).eigenvalues();
    text += QString("; σ %1 / %2 / %3 mm")
                .arg(std::sqrt(std::max(0.0, ev[0])) * 1e3, 0, 'f', 3)
                .arg(std::sqrt(std::max(0.0, ev[1])) * 1e3, 0, 'f', 3)
                .arg(std::sqrt(std::max(0.0, ev[2])) * 1e3, 0, 'f', 3);
  }
  if (tracks->Degenerate(row, k)) text += " (degenerate: left out of the valid points)";
  knot_->setText(text);
}

}  // namespace netlab::gui
