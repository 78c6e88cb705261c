#pragma once
// The reconstruction room: the labels triangulated into 3D knot tracks with `netlab
// triangulate`'s engine, as ReconstructionPresenter (document/reconstruction_presenter.h) says.
// Along the top the options as the CLI names them (bundle adjustment none / points / rig, the
// labels' sigma, the link-length prior, the smoothness prior, the labels under review), Triangulate
// (progress, Cancel) and Export (tracks.h5 and xyzpts.csv / xyzres.csv, the CLI's files). On the
// left the outliers and degenerate points with why (a click takes the person to that label in
// the labeling room), and below them the current frame's knots with their reprojection residual
// and 3D sigma (KnotErrorModel: every knot, the outliers or the degenerate points; sortable; a
// click takes the person to that label); on the right the net in 3D at the frame of the slider
// (NetView3D).

#include <QWidget>
#include <atomic>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "app/gui/document/latest_request.h"
#include "app/gui/document/reconstruction_presenter.h"
#include "libreconstruct/labeling/missing_knots.h"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QSlider;
class QTableView;
class QTableWidget;
class QTimer;

namespace netlab::gui {

// The net at one frame in a perspective view, drawn with QPainter (offscreen too): the valid
// knots (discs; degenerate ones red), the links between valid neighbours, the target's boxes and
// balls at that time, the rig's cameras (a small pyramid each, named), the selected knots'
// trajectories over the whole shot, and on demand each knot's 1-sigma ellipsoid as the view
// sees it (an ellipse, scaled x10).
// Left drag turns it, right or middle drag pans, the wheel zooms, a double click fits it again; a
// click selects the nearest knot (Ctrl+click adds it to the selection).
class NetView3D : public QWidget {
  Q_OBJECT

 public:
  explicit NetView3D(QWidget* parent = nullptr);
  // What to draw (null: nothing); `target` may be empty. The view is fitted to the rig and the
  // tracks when they change.
  void Set(const KnotTracks* tracks, const calib::Rig* rig, const recon::Target* target, int cols);
  void SetRow(int row);  // the tracks' row shown (-1: none)
  int row() const { return row_; }
  void SetShowSigma(bool show) { show_sigma_ = show, update(); }
  void SetSelected(std::set<int> knots) { selected_ = std::move(knots), update(); }
  const std::set<int>& selected() const { return selected_; }
  // The view: turned by yaw about world z and pitch above the xy plane (rad), looking at
  // `centre` from `distance` (m).
  void SetView(double yaw, double pitch, double distance);
  double yaw() const { return yaw_; }
  double pitch() const { return pitch_; }
  double distance() const { return distance_; }
  // Where a world point is drawn (nullopt: behind the eye).
  std::optional<QPointF> ToScreen(const Eigen::Vector3d& p) const;
  long paints() const { return paints_; }
  // Centred on the shot's knots, as near as keeps every camera and knot in view.
  void FitView() {
    Fit();
    update();
  }
  QSize sizeHint() const override { return {600, 500}; }

 signals:
  void knotClicked(int knot);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent*) override { FitView(); }

 private:
  void Fit();
  const KnotTracks* tracks_ = nullptr;
  const calib::Rig* rig_ = nullptr;
  const recon::Target* target_ = nullptr;
  int cols_ = 1, row_ = -1;
  bool show_sigma_ = false;
  std::set<int> selected_;
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  double yaw_ = -0.9, pitch_ = 0.35, distance_ = 8.0;
  QPointF press_, last_;
  Qt::MouseButton button_ = Qt::NoButton;
  bool moved_ = false;
  long paints_ = 0;
};

class ReconstructionRoom : public QWidget {
  Q_OBJECT

 public:
  explicit ReconstructionRoom(QWidget* parent = nullptr);
  ~ReconstructionRoom() override;
  void Show(ReconstructionPresenter* presenter);

  QComboBox* adjustment_box() const { return adjustment_; }
  QDoubleSpinBox* sigma_box() const { return sigma_; }
  QDoubleSpinBox* link_box() const { return link_; }
  QDoubleSpinBox* smooth_box() const { return smooth_; }
  QPushButton* triangulate_button() const { return triangulate_button_; }
  QPushButton* cancel_button() const { return cancel_button_; }
  QPushButton* export_button() const { return export_button_; }
  QProgressBar* progress() const { return progress_; }
  QLabel* status_label() const { return status_; }
  QLabel* summary_label() const { return summary_; }
  QLabel* knot_label() const { return knot_; }
  QTableWidget* problems_table() const { return problems_; }
  // The current frame's knots with their residual and sigma, filtered by knot_filter_box.
  QTableView* knot_table() const { return knot_table_; }
  KnotErrorModel* knot_model() const { return knot_model_; }
  QComboBox* knot_filter_box() const { return knot_filter_; }
  QSlider* frame_slider() const { return slider_; }
  NetView3D* view() const { return view_; }
  int frame() const { return frame_; }
  void SetFrame(int t);
  // The slider's frame in words (ReconstructionPresenter::FrameStatus; "" : nothing open).
  QString FrameStatus() const { return presenter_ ? presenter_->FrameStatus(frame_) : QString(); }
  bool busy() const { return triangulator_.pending(); }
  // Export without its dialog: the tracks to `tracks_path`, xyzpts.csv and xyzres.csv beside it.
  bool ExportTo(const QString& tracks_path);

  // A row of the problems table: an outlier observation or a degenerate point.
  struct Problem {
    bool degenerate = false;
    int camera = -1;  // the session's camera (-1: a degenerate point, no one camera)
    int t = 0;        // the session's frame row
    int knot = 0;
    QString why;
  };
  const std::vector<Problem>& problems() const { return rows_; }

 signals:
  void frameChanged(int t);
  // The person wants to see this label (camera -1: any camera that has it) in the labeling room.
  void showLabel(int camera, int t, int knot);

 private:
  void Triangulate();
  void Refresh();
  void RefreshKnot();
  void RefreshKnotTable();
  bool Alive() const;

  ReconstructionPresenter* presenter_ = nullptr;
  std::weak_ptr<const int> alive_;
  recon::Target target_;
  int frame_ = 0;
  QComboBox* adjustment_ = nullptr;
  QDoubleSpinBox *sigma_ = nullptr, *link_ = nullptr, *smooth_ = nullptr;
  QCheckBox *unreviewed_ = nullptr, *show_sigma_ = nullptr;
  QPushButton *triangulate_button_ = nullptr, *cancel_button_ = nullptr, *export_button_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QLabel *status_ = nullptr, *summary_ = nullptr, *knot_ = nullptr, *frame_label_ = nullptr;
  QTableWidget* problems_ = nullptr;
  QComboBox* knot_filter_ = nullptr;
  QTableView* knot_table_ = nullptr;
  KnotErrorModel* knot_model_ = nullptr;
  QSlider* slider_ = nullptr;
  NetView3D* view_ = nullptr;
  QTimer* progress_timer_ = nullptr;
  std::vector<Problem> rows_;
  std::shared_ptr<std::atomic<double>> fraction_ = std::make_shared<std::atomic<double>>(0.0);
  LatestRequest<TriangulationRun> triangulator_;
};

}  // namespace netlab::gui
