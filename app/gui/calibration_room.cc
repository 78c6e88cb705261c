#include "app/gui/calibration_room.h"

#include <QCheckBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QMouseEvent>
#include <QPainter>
#include <QProgressBar>
#include <QPushButton>
#include <QShortcut>
#include <QSplitter>
#include <QTableWidget>
#include <QTimer>
#include <QUndoStack>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "calibration/detect.h"

namespace netlab::gui {
namespace {

constexpr double kFrustumDepthM = 0.4;  // how deep a camera's frustum is drawn
constexpr double kAxisM = 0.5;          // the world axes' length

QColor CameraColour(int i) {
  static const QColor colours[] = {QColor(31, 119, 180), QColor(255, 127, 14), QColor(44, 160, 44),
                                   QColor(214, 39, 40)};
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
  const QRectF area(30, 44, width() - 60, height() - 74);
  fit.scale =
      std::min(area.width() / std::max(x1 - x0, 1e-6), area.height() / std::max(y1 - y0, 1e-6));
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
  painter.drawText(QRectF(4, 4, width() - 8, 34), Qt::AlignHCenter | Qt::TextWordWrap,
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

// ---------------------------------------------------------------------------------------------
// The selected image.

namespace {

// 1, 2 or 5 times a power of ten, at most `x`.
double NiceBelow(double x) {
  if (!(x > 0)) return 1.0;
  const double p = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * p <= x) return m * p;
  return p;
}

QString ImageName(const CalibrationImage& image) {
  return QFileInfo(QString::fromStdString(image.path)).fileName();
}

}  // namespace

CalibrationImageView::CalibrationImageView(QWidget* parent) : QWidget(parent) {
  setMinimumSize(280, 280);
  setAutoFillBackground(true);
  QPalette p = palette();
  p.setColor(QPalette::Window, QColor(40, 40, 40));
  setPalette(p);
}

void CalibrationImageView::Set(const CalibrationPresenter* presenter, std::optional<ImageKey> key,
                               QImage image) {
  // The same image again without pixels: the ones it has are kept (a new result, new layers).
  if (!(image.isNull() && key == key_)) image_ = std::move(image);
  presenter_ = presenter;
  key_ = key;
  // One scale for every image of a result: a bad image's arrows are seen to be long. The
  // calibration's RMS is drawn (up to) 4 % of the image's width.
  residual_scale_ = 0.0;
  if (presenter_ != nullptr && presenter_->result() != nullptr && key_) {
    const CalibrationImage& i = presenter_->image(*key_);
    const double rms = presenter_->result()->summary.rms_px;
    if (rms > 0 && i.width > 0) residual_scale_ = NiceBelow(0.04 * i.width / rms);
  }
  update();
}

void CalibrationImageView::SetLayers(bool corners, bool residuals, bool coverage) {
  corners_ = corners;
  residuals_ = residuals;
  coverage_ = coverage;
  update();
}

QRectF CalibrationImageView::ImageRect() const {
  double w = image_.width(), h = image_.height();
  if (presenter_ != nullptr && key_) {
    const CalibrationImage& i = presenter_->image(*key_);
    if (i.width > 0) w = i.width, h = i.height;
  }
  if (w <= 0 || h <= 0) return {};
  const QRectF area = QRectF(rect()).adjusted(4, 4, -4, -40);
  const double s = std::min(area.width() / w, area.height() / h);
  return QRectF(area.center().x() - w * s / 2, area.center().y() - h * s / 2, w * s, h * s);
}

QPointF CalibrationImageView::ToScreen(const Eigen::Vector2d& pixel) const {
  const QRectF r = ImageRect();
  double w = image_.width();
  if (presenter_ != nullptr && key_ && presenter_->image(*key_).width > 0)
    w = presenter_->image(*key_).width;
  const double s = w > 0 ? r.width() / w : 1.0;
  return {r.left() + (pixel.x() + 0.5) * s, r.top() + (pixel.y() + 0.5) * s};
}

void CalibrationImageView::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  const QRectF r = ImageRect();
  const QRectF legend(6, height() - 38, width() - 12, 36);
  painter.setPen(QColor(230, 230, 230));
  if (presenter_ == nullptr || !key_) {
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap,
                     "No image selected: Detect, then click an image in the list");
    return;
  }
  const CalibrationImage& image = presenter_->image(*key_);
  if (!image_.isNull())
    painter.drawImage(r, image_);
  else if (!r.isEmpty())
    painter.fillRect(r, QColor(70, 70, 70));
  if (coverage_) {
    const CoverageGrid grid = presenter_->Coverage(key_->first);
    const int most = std::max(1, grid.max());
    const double cw = r.width() / grid.cols, ch = r.height() / grid.rows;
    for (int y = 0; y < grid.rows; ++y)
      for (int x = 0; x < grid.cols; ++x) {
        const int n = grid.at(x, y);
        // Empty cells blue (the distortion is not constrained there), the others from yellow
        // (few points) to red (the most).
        const QColor colour =
            n == 0 ? QColor(40, 90, 255, 80)
                   : QColor(255, static_cast<int>(220 * (1.0 - double(n) / most)), 0, 80);
        painter.fillRect(QRectF(r.left() + x * cw, r.top() + y * ch, cw, ch), colour);
      }
  }
  if (image.status == CalibrationImage::Status::kFound && corners_) {
    painter.setPen(QPen(QColor(60, 230, 60), 1.5));
    for (const Eigen::Vector2d& p : image.found.pixels) {
      const QPointF q = ToScreen(p);
      painter.drawLine(q + QPointF(-4, 0), q + QPointF(4, 0));
      painter.drawLine(q + QPointF(0, -4), q + QPointF(0, 4));
    }
  }
  const std::vector<PointResidual> residuals = presenter_->Residuals(*key_);
  if (residuals_ && residual_scale_ > 0) {
    painter.setPen(QPen(QColor(255, 50, 50), 2));
    for (const PointResidual& p : residuals) {
      const QPointF a = ToScreen(p.pixel);
      const QPointF b = ToScreen(p.pixel + residual_scale_ * p.residual);
      painter.drawLine(a, b);
    }
  }
  // What is drawn, in words.
  QStringList parts;
  if (image.status == CalibrationImage::Status::kFailed)
    parts << "detection failed: " + QString::fromStdString(image.why);
  else if (image.status == CalibrationImage::Status::kNotDetected)
    parts << "not searched yet";
  else {
    if (corners_) parts << QString("%1 points (green)").arg(image.found.ids.size());
    if (presenter_->is_excluded(*key_))
      parts << "excluded from the calibration";
    else if (residuals_ && residual_scale_ > 0)
      parts << QString("residuals ×%1 (red: a 1 px error drawn %1 px long)").arg(residual_scale_);
  }
  if (coverage_) parts << "coverage of the camera's images: blue no point, yellow few, red most";
  painter.setPen(QColor(230, 230, 230));
  painter.drawText(legend, Qt::AlignLeft | Qt::AlignVCenter | Qt::TextWordWrap, parts.join(" · "));
}

// ---------------------------------------------------------------------------------------------
// The room.

CalibrationRoom::CalibrationRoom(QWidget* parent)
    : QWidget(parent),
      detector_(this,
                [this](DetectionAnswer answer) {
                  progress_timer_->stop();
                  if (!Alive()) return;
                  presenter_->SetDetections(std::move(answer));
                  requested_.reset();
                  Refresh();
                  if (!selected_ && !presenter_->images().empty()) SelectImage(0);
                }),
      calibrator_(this,
                  [this](CalibrationRun run) {
                    if (!Alive()) return;
                    presenter_->SetCalibration(std::move(run));
                    requested_.reset();
                    Rerun();
                    Refresh();
                  }),
      loader_(this, [this](Loaded loaded) {
        if (!Alive() || !selected_ || loaded.key != *selected_) return;
        view_->Set(presenter_, selected_, std::move(loaded.image));
      }) {
  auto* layout = new QVBoxLayout(this);

  // The inputs, as `netlab calibrate` takes them.
  auto* inputs = new QGridLayout;
  inputs->addWidget(new QLabel("Target"), 0, 0);
  target_edit_ = new QLineEdit;
  target_edit_->setObjectName("calibration_target");
  target_edit_->setPlaceholderText(
      "a board, foil or marker-map YAML file, or chessboard:9x6:0.06, "
      "charuco:10x7:0.06:0.045:DICT_5X5_100 (as netlab calibrate --board)");
  inputs->addWidget(target_edit_, 0, 1);
  target_button_ = new QPushButton("Target file…");
  inputs->addWidget(target_button_, 0, 2);
  inputs->addWidget(new QLabel("Images"), 1, 0, Qt::AlignTop);
  globs_ = new QTableWidget(0, 2);
  globs_->setObjectName("calibration_globs");
  globs_->setHorizontalHeaderLabels({"Camera", "Images (a glob, as --images NAME=GLOB)"});
  globs_->horizontalHeader()->setStretchLastSection(true);
  globs_->verticalHeader()->setVisible(false);
  globs_->verticalHeader()->setDefaultSectionSize(22);
  globs_->setMaximumHeight(4 * 22 + 28);
  inputs->addWidget(globs_, 1, 1);
  auto* glob_buttons = new QVBoxLayout;
  folder_button_ = new QPushButton("Images folder…");
  folder_button_->setToolTip(
      "A folder with one sub-folder of images per camera (cam0/, cam1/, …) "
      "and, beside them, the target's YAML file");
  auto* add_camera = new QPushButton("Add camera");
  glob_buttons->addWidget(folder_button_);
  glob_buttons->addWidget(add_camera);
  glob_buttons->addStretch();
  inputs->addLayout(glob_buttons, 1, 2);
  layout->addLayout(inputs);

  auto* actions = new QHBoxLayout;
  detect_button_ = new QPushButton("Detect");
  cancel_button_ = new QPushButton("Cancel");
  progress_ = new QProgressBar;
  progress_->setMaximumWidth(220);
  progress_->setFormat("%v / %m images");
  calibrate_button_ = new QPushButton("Calibrate");
  save_button_ = new QPushButton("Save rig…");
  status_ = new QLabel;
  status_->setObjectName("calibration_status");
  status_->setWordWrap(true);
  for (QWidget* w : std::initializer_list<QWidget*>{detect_button_, cancel_button_, progress_,
                                                    calibrate_button_, save_button_})
    actions->addWidget(w);
  actions->addWidget(status_, 1);
  layout->addLayout(actions);

  auto* split = new QSplitter(Qt::Horizontal);
  images_ = new QTableWidget(0, 6);
  images_->setObjectName("calibration_images");
  images_->setHorizontalHeaderLabels({"Camera", "Image", "Used", "RMS (px)", "Points", "Status"});
  images_->horizontalHeader()->setStretchLastSection(true);
  images_->verticalHeader()->setVisible(false);
  images_->verticalHeader()->setDefaultSectionSize(20);
  images_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  images_->setSelectionBehavior(QAbstractItemView::SelectRows);
  images_->setSelectionMode(QAbstractItemView::SingleSelection);
  images_->setToolTip(
      "A click on Used excludes or includes the image and calibrates again "
      "(Ctrl+Z undoes)");
  images_->horizontalHeaderItem(kUsedColumn)
      ->setToolTip("Click to leave the image out or take it in");
  split->addWidget(images_);

  auto* middle = new QWidget;
  auto* middle_layout = new QVBoxLayout(middle);
  middle_layout->setContentsMargins(0, 0, 0, 0);
  auto* layers = new QHBoxLayout;
  view_caption_ = new QLabel;
  layers->addWidget(view_caption_, 1);
  show_corners_ = new QCheckBox("Corners");
  show_residuals_ = new QCheckBox("Residuals");
  show_coverage_ = new QCheckBox("Coverage");
  show_corners_->setChecked(true);
  show_residuals_->setChecked(true);
  show_coverage_->setChecked(false);
  for (QCheckBox* box : {show_corners_, show_residuals_, show_coverage_}) {
    layers->addWidget(box);
    connect(box, &QCheckBox::toggled, this, [this] {
      view_->SetLayers(show_corners_->isChecked(), show_residuals_->isChecked(),
                       show_coverage_->isChecked());
    });
  }
  middle_layout->addLayout(layers);
  view_ = new CalibrationImageView;
  middle_layout->addWidget(view_, 1);
  split->addWidget(middle);

  auto* right = new QWidget;
  auto* right_layout = new QVBoxLayout(right);
  right_layout->setContentsMargins(0, 0, 0, 0);
  results_ = new QLabel;
  results_->setObjectName("calibration_results");
  results_->setWordWrap(true);
  results_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  right_layout->addWidget(results_);
  cameras_ = new QTableWidget(0, 7);
  cameras_->setObjectName("calibration_cameras");
  cameras_->setHorizontalHeaderLabels(
      {"Camera", "RMS (px)", "Views", "Points", "Coverage", "Centre σ (mm)", "Foil side"});
  cameras_->horizontalHeader()->setStretchLastSection(true);
  cameras_->verticalHeader()->setVisible(false);
  cameras_->verticalHeader()->setDefaultSectionSize(20);
  cameras_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  cameras_->setMaximumHeight(4 * 20 + 30);
  right_layout->addWidget(cameras_);
  summary_ = new QLabel;
  summary_->setWordWrap(true);
  summary_->setObjectName("calibration_summary");
  right_layout->addWidget(summary_);
  table_ = new QTableWidget(0, 8);
  table_->setObjectName("rig_table");
  table_->setHorizontalHeaderLabels({"Camera", "Image (px)", "fx, fy (px)", "cx, cy (px)", "k1, k2",
                                     "Centre (m)", "Looks along", "Principal point"});
  table_->horizontalHeader()->setStretchLastSection(true);
  table_->verticalHeader()->setVisible(false);
  table_->verticalHeader()->setDefaultSectionSize(20);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setMaximumHeight(4 * 20 + 30);
  right_layout->addWidget(table_);
  sketch_ = new RigSketch;
  sketch_->setMinimumSize(300, 220);
  right_layout->addWidget(sketch_, 1);
  split->addWidget(right);
  split->setStretchFactor(0, 3);
  split->setStretchFactor(1, 4);
  split->setStretchFactor(2, 4);
  split->setSizes({520, 500, 580});
  layout->addWidget(split, 1);

  progress_timer_ = new QTimer(this);
  progress_timer_->setInterval(100);
  connect(progress_timer_, &QTimer::timeout, this, [this] {
    progress_->setMaximum(std::max(1, total_->load()));
    progress_->setValue(done_->load());
  });

  connect(target_button_, &QPushButton::clicked, this, [this] {
    const QString file =
        QFileDialog::getOpenFileName(this, "The calibration target (board, foil or marker map)",
                                     target_edit_->text(), "Target (*.yaml *.yml);;All files (*)");
    if (!file.isEmpty()) target_edit_->setText(file);
  });
  connect(folder_button_, &QPushButton::clicked, this, [this] {
    const QString folder = QFileDialog::getExistingDirectory(
        this, "The calibration images: a folder with one sub-folder per camera");
    if (!folder.isEmpty()) FillFromFolder(folder);
  });
  connect(add_camera, &QPushButton::clicked, this, [this] {
    const int row = globs_->rowCount();
    globs_->insertRow(row);
    globs_->setItem(row, 0, new QTableWidgetItem(QString("cam%1").arg(row)));
    globs_->setItem(row, 1, new QTableWidgetItem(""));
    globs_->editItem(globs_->item(row, 1));
  });
  connect(detect_button_, &QPushButton::clicked, this, &CalibrationRoom::Detect);
  connect(cancel_button_, &QPushButton::clicked, this, [this] {
    detector_.Cancel();
    status_->setText("Cancelling…");
  });
  connect(calibrate_button_, &QPushButton::clicked, this, &CalibrationRoom::Calibrate);
  connect(save_button_, &QPushButton::clicked, this, [this] {
    if (!Alive()) return;
    const QString path = QFileDialog::getSaveFileName(
        this, "Save the rig", QString::fromStdString(presenter_->rig_path()),
        "Rig (*.yaml);;All files (*)");
    if (!path.isEmpty()) SaveTo(path);
  });
  connect(images_, &QTableWidget::cellClicked, this, [this](int row, int column) {
    SelectImage(row);
    if (column != kUsedColumn || !Alive() || presenter_->result() == nullptr) return;
    const ImageKey key(row / std::max(1, presenter_->frames()),
                       row % std::max(1, presenter_->frames()));
    if (presenter_->image(key).status != CalibrationImage::Status::kFound) return;
    presenter_->ToggleExcluded(key);
    Rerun();
    Refresh();
  });
  connect(images_, &QTableWidget::currentCellChanged, this,
          [this](int row, int, int, int) { SelectImage(row); });
  // The keys of the window's Edit menu (the labeling room's, disabled here).
  auto* undo = new QShortcut(QKeySequence("Ctrl+Z"), this);
  undo->setContext(Qt::WidgetWithChildrenShortcut);
  connect(undo, &QShortcut::activated, this, [this] {
    if (!Alive() || !presenter_->undo_stack()->canUndo()) return;
    presenter_->undo_stack()->undo();
    Rerun();
    Refresh();
  });
  for (const QKeySequence& keys : {QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")}) {
    auto* redo = new QShortcut(keys, this);
    redo->setContext(Qt::WidgetWithChildrenShortcut);
    connect(redo, &QShortcut::activated, this, [this] {
      if (!Alive() || !presenter_->undo_stack()->canRedo()) return;
      presenter_->undo_stack()->redo();
      Rerun();
      Refresh();
    });
  }
  Refresh();
}

CalibrationRoom::~CalibrationRoom() = default;

bool CalibrationRoom::Alive() const { return presenter_ != nullptr && !alive_.expired(); }

bool CalibrationRoom::busy() const {
  return detector_.pending() || calibrator_.pending() || loader_.pending();
}

void CalibrationRoom::Show(CalibrationPresenter* presenter) {
  if (presenter != presenter_ || (presenter != nullptr && alive_.expired())) {
    detector_.Drop();
    calibrator_.Drop();
    loader_.Drop();
    progress_timer_->stop();
    presenter_ = presenter;
    alive_ = presenter ? presenter->lifetime() : std::weak_ptr<const int>();
    selected_.reset();
    requested_.reset();
    view_->Set(nullptr, std::nullopt, {});
    target_edit_->setText(presenter ? QString::fromStdString(presenter->target_spec()) : "");
    globs_->setRowCount(0);
    if (presenter) {
      for (const auto& [name, pattern] : presenter->globs()) {
        const int row = globs_->rowCount();
        globs_->insertRow(row);
        globs_->setItem(row, 0, new QTableWidgetItem(QString::fromStdString(name)));
        globs_->setItem(row, 1, new QTableWidgetItem(QString::fromStdString(pattern)));
      }
      if (presenter->globs().empty()) {
        const std::string folder = presenter->SuggestedImagesFolder();
        if (!folder.empty()) FillFromFolder(QString::fromStdString(folder));
      }
    }
  }
  Refresh();
}

void CalibrationRoom::FillFromFolder(const QString& folder) {
  std::string target;
  const auto globs = CalibrationPresenter::GlobsInFolder(folder.toStdString(), &target);
  if (globs.empty()) {
    ShowError(QString("%1: no sub-folder with images (PNG, JPEG, TIFF) in it: choose the folder "
                      "that holds cam0/, cam1/, …")
                  .arg(folder));
    return;
  }
  globs_->setRowCount(0);
  for (const auto& [name, pattern] : globs) {
    const int row = globs_->rowCount();
    globs_->insertRow(row);
    globs_->setItem(row, 0, new QTableWidgetItem(QString::fromStdString(name)));
    globs_->setItem(row, 1, new QTableWidgetItem(QString::fromStdString(pattern)));
  }
  if (!target.empty()) target_edit_->setText(QString::fromStdString(target));
  status_->setText(
      QString("%1 cameras from %2%3: Detect finds the target in their images")
          .arg(globs.size())
          .arg(folder)
          .arg(target.empty()
                   ? QString(" (no target file beside them: choose one)")
                   : QString(", target ") + QFileInfo(QString::fromStdString(target)).fileName()));
  status_->setStyleSheet("");
}

void CalibrationRoom::ShowError(const QString& text) {
  status_->setText(text);
  status_->setStyleSheet("color: #b00000;");
}

bool CalibrationRoom::ApplyInputs() {
  if (!Alive()) return false;
  const std::string spec = target_edit_->text().trimmed().toStdString();
  if (spec.empty()) {
    ShowError(
        "Choose the target first: its YAML file (Target file…) or a spec such as "
        "chessboard:9x6:0.06");
    return false;
  }
  std::vector<std::pair<std::string, std::string>> globs;
  for (int row = 0; row < globs_->rowCount(); ++row) {
    const QTableWidgetItem* name = globs_->item(row, 0);
    const QTableWidgetItem* pattern = globs_->item(row, 1);
    const QString n = name ? name->text().trimmed() : QString();
    const QString p = pattern ? pattern->text().trimmed() : QString();
    if (n.isEmpty() && p.isEmpty()) continue;
    if (p.isEmpty()) {
      ShowError(QString("Camera %1 has no images: give a glob such as calib/%1/*.png").arg(n));
      return false;
    }
    globs.emplace_back(n.toStdString(), p.toStdString());
  }
  if (globs.empty()) {
    ShowError(
        "Choose the images first: Images folder… (one sub-folder per camera), or a "
        "camera's name and glob per row");
    return false;
  }
  // Read again at every Detect: a changed target file or a new image is taken in.
  try {
    presenter_->SetTarget(spec);
  } catch (const std::exception& e) {
    ShowError("Target: " + QString::fromLocal8Bit(e.what()));
    return false;
  }
  try {
    presenter_->SetImages(globs);
  } catch (const std::exception& e) {
    ShowError("Images: " + QString::fromLocal8Bit(e.what()));
    return false;
  }
  return true;
}

void CalibrationRoom::Detect() {
  if (!ApplyInputs()) return;
  const DetectionJob job = presenter_->MakeDetectionJob();
  *done_ = 0;
  *total_ = static_cast<int>(job.images.size());
  progress_->setMaximum(std::max(1, total_->load()));
  progress_->setValue(0);
  calibrator_.Drop();
  requested_.reset();
  detector_.Request([job, done = done_, total = total_](const CancelToken& cancel) {
    return CalibrationPresenter::Detect(job, ProgressReporter(
                                                 [done, total](const Progress& p) {
                                                   *done = static_cast<int>(p.done);
                                                   *total = static_cast<int>(p.total);
                                                 },
                                                 cancel));
  });
  progress_timer_->start();
  Refresh();
}

void CalibrationRoom::Calibrate() {
  if (!Alive()) return;
  if (!presenter_->detected()) {
    ShowError("Detect the target in every image first (Detect)");
    return;
  }
  requested_ = presenter_->excluded();
  calibrator_.Request([job = presenter_->MakeCalibrationJob()](const CancelToken&) {
    return CalibrationPresenter::Calibrate(job);
  });
  Refresh();
}

void CalibrationRoom::Rerun() {
  if (!Alive() || !presenter_->NeedsCalibration()) return;
  if (calibrator_.pending() && requested_ == presenter_->excluded()) return;
  Calibrate();
}

bool CalibrationRoom::SaveTo(const QString& path) {
  if (!Alive() || presenter_->result() == nullptr) return false;
  try {
    presenter_->Save(path.toStdString());
  } catch (const std::exception& e) {
    ShowError("Save: " + QString::fromLocal8Bit(e.what()));
    return false;
  }
  Refresh();
  status_->setText(presenter_->has_project()
                       ? QString("Rig written to %1; the project names it").arg(path)
                       : QString("Rig written to %1").arg(path));
  emit rigSaved(path);
  return true;
}

void CalibrationRoom::SelectImage(int row) {
  if (!Alive() || row < 0 || row >= static_cast<int>(presenter_->images().size())) return;
  const CalibrationImage& image = presenter_->images()[row];
  const ImageKey key(image.camera, image.frame);
  if (selected_ == key) return;
  selected_ = key;
  {
    const QSignalBlocker block(images_);
    images_->selectRow(row);
  }
  view_caption_->setText(QString("%1 · %2").arg(
      QString::fromStdString(presenter_->camera_name(key.first)), ImageName(image)));
  view_->Set(presenter_, std::nullopt, {});
  view_->Set(presenter_, selected_, {});
  loader_.Request([key, path = image.path](const CancelToken&) {
    Loaded loaded{key, {}};
    const cv::Mat read = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (read.empty()) return loaded;
    cv::Mat gray = calib::ToGray8(read);
    // At most 1024 px across on screen: the corners and arrows carry the detail.
    const double s = std::min(1.0, 1024.0 / std::max(gray.cols, gray.rows));
    if (s < 1.0) cv::resize(gray, gray, cv::Size(), s, s, cv::INTER_AREA);
    loaded.image = QImage(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step),
                          QImage::Format_Grayscale8)
                       .copy();
    return loaded;
  });
}

void CalibrationRoom::RefreshImages() {
  const std::vector<CalibrationImage>& images =
      Alive() ? presenter_->images() : std::vector<CalibrationImage>{};
  images_->clearSpans();
  images_->setRowCount(static_cast<int>(images.size()));
  for (int row = 0; row < static_cast<int>(images.size()); ++row) {
    const CalibrationImage& image = images[row];
    const ImageKey key(image.camera, image.frame);
    QString status = "not searched", points, rms, used = "";
    QColor colour = palette().color(QPalette::Text);
    switch (image.status) {
      case CalibrationImage::Status::kNotDetected: break;
      case CalibrationImage::Status::kFailed:
        status = "failed: " + QString::fromStdString(image.why);
        colour = QColor(176, 0, 0);
        used = "—";
        break;
      case CalibrationImage::Status::kFound:
        status = "found";
        points = QString::number(image.found.ids.size());
        used = presenter_->is_excluded(key) ? "✗ excluded" : "✓";
        if (const auto r = presenter_->ImageRms(key)) rms = QString::number(*r, 'f', 3);
        if (presenter_->is_excluded(key)) colour = QColor(130, 130, 130);
        break;
    }
    QStringList cells = {QString::fromStdString(presenter_->camera_name(image.camera)),
                         ImageName(image),
                         used,
                         rms,
                         points,
                         status};
    // A failed image's reason over the columns it has no values for.
    if (image.status == CalibrationImage::Status::kFailed) {
      cells = {cells[0], cells[1], status, "", "", ""};
      images_->setSpan(row, kUsedColumn, 1, 4);
    }
    for (int column = 0; column < cells.size(); ++column) {
      auto* item = new QTableWidgetItem(cells[column]);
      item->setForeground(colour);
      if (column == kUsedColumn && image.status == CalibrationImage::Status::kFailed)
        item->setToolTip(cells[column]);
      images_->setItem(row, column, item);
    }
  }
  // The worst image's RMS in bold: the one to look at first.
  if (Alive())
    if (const auto worst = presenter_->WorstImage()) {
      const int row = worst->first * presenter_->frames() + worst->second;
      if (QTableWidgetItem* item = images_->item(row, 3)) {
        QFont bold = item->font();
        bold.setBold(true);
        item->setFont(bold);
        item->setToolTip("The largest RMS of the images used");
      }
    }
  images_->resizeColumnsToContents();
  // Not as wide as a failed image's reason, which spans it and the columns after it.
  images_->setColumnWidth(kUsedColumn, images_->fontMetrics().horizontalAdvance("✗ excluded") + 12);
}

void CalibrationRoom::Refresh() {
  const bool open = Alive();
  const bool detecting = detector_.pending();
  const bool calibrating = calibrator_.pending();
  target_edit_->setEnabled(open && !detecting);
  globs_->setEnabled(open && !detecting);
  folder_button_->setEnabled(open && !detecting);
  target_button_->setEnabled(open && !detecting);
  detect_button_->setEnabled(open && !detecting);
  cancel_button_->setEnabled(detecting);
  calibrate_button_->setEnabled(open && !detecting && presenter_->detected());
  save_button_->setEnabled(open && !detecting && presenter_->result() != nullptr);
  progress_->setVisible(detecting || (open && !presenter_->images().empty()));
  if (open && !detecting && presenter_->detected()) {
    progress_->setMaximum(static_cast<int>(presenter_->images().size()));
    progress_->setValue(static_cast<int>(presenter_->images().size()));
  }

  if (!open) {
    status_->setText("No project open.");
  } else if (detecting) {
    status_->setText("Detecting the target in every image…");
    status_->setStyleSheet("");
  } else if (calibrating) {
    status_->setText(QString("%1 · calibrating…").arg(presenter_->DetectionSummary()));
    status_->setStyleSheet("");
  } else if (!presenter_->images().empty() && status_->styleSheet().isEmpty()) {
    QString next;
    if (!presenter_->detected())
      next = " · Detect searches the rest";
    else if (presenter_->result() == nullptr && presenter_->run() == nullptr)
      next = " · Calibrate next";
    else if (presenter_->result() != nullptr && !presenter_->saved())
      next = " · click Used to leave an image out, Save rig… when done";
    status_->setText(presenter_->DetectionSummary() + next);
  } else if (presenter_->images().empty() && status_->text().isEmpty()) {
    status_->setText("Choose the target and the images (Images folder…), then Detect.");
  }

  RefreshImages();
  results_->setText(open ? presenter_->CalibrationText() : QString());

  // A row per camera of the calibration.
  const calib::CalibrationResult* result = open ? presenter_->result() : nullptr;
  const int n = result ? static_cast<int>(result->summary.cameras.size()) : 0;
  cameras_->setRowCount(n);
  for (int c = 0; c < n; ++c) {
    const calib::CameraReport& r = result->summary.cameras[c];
    const std::vector<int>& faces = result->summary.face_of_camera;
    const bool foil =
        presenter_->target() != nullptr &&
        presenter_->target()->kind == calib::CalibrationTarget::Kind::kDoubleSidedFoil;
    const QStringList cells = {
        QString::fromStdString(r.name),
        QString::number(r.rms_px, 'f', 3),
        QString::number(r.views),
        QString::number(r.points),
        QString("%1 %").arg(100.0 * r.coverage, 0, 'f', 0),
        QString::number(1000.0 * r.position_sigma_m, 'f', 2),
        foil && c < static_cast<int>(faces.size()) ? (faces[c] == 0 ? "front" : "back") : ""};
    for (int column = 0; column < cells.size(); ++column)
      cameras_->setItem(c, column, new QTableWidgetItem(cells[column]));
  }
  cameras_->resizeColumnsToContents();

  // The rig: the calibration's, else the project's.
  summary_->setText(open ? presenter_->Summary() : QString("No rig open."));
  sketch_->SetPresenter(open ? presenter_ : nullptr);
  const std::vector<RigCameraRow> rows = open ? presenter_->Cameras() : std::vector<RigCameraRow>{};
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
  // The selected image again (its residuals follow the result).
  if (open && selected_) view_->Set(presenter_, selected_, QImage());
}

}  // namespace netlab::gui
