#pragma once
// The simulation room: does the simulated net lie where the cameras saw the real one? As
// SimulationPresenter (document/simulation_presenter.h) says. Along the top the measured tracks
// (the labels triangulated with `netlab triangulate`'s engine: the labels' sigma, Triangulate),
// then the simulations: a scenario with `--set`'s dotted overrides and Simulate (progress,
// Cancel), or Load simulation…; the simulations' table (a row each, its score side by side with
// the others'); Score (the alignment as `netlab score --align`), Open report, and the toggle of
// the simulated net. Below, the four cameras at one frame (a slider): the labels in orange, the
// selected simulation's knots (squares) and links in cyan, aligned in time and space as its score
// aligns them; the mouse over a knot says the distance between its label and its simulated knot.
// On the right the verdict in words.

#include <QWidget>
#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

#include "app/gui/camera_view.h"
#include "app/gui/document/latest_request.h"
#include "app/gui/document/reconstruction_presenter.h"
#include "app/gui/document/simulation_presenter.h"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QLineEdit;
class QProgressBar;
class QPushButton;
class QSlider;
class QTableWidget;
class QTimer;

namespace netlab::gui {

class KnotGrid;

// A score's charts, drawn with QPainter (offscreen too): the error over time (the RMS of |r| per
// knot class per measured frame, mm, the phases shaded and named with their RMS where it fits) or
// the d² histogram against chi²(3)'s expected counts.
class ScoreChart : public QWidget {
  Q_OBJECT

 public:
  enum class Kind { kErrorOverTime, kD2Histogram };
  explicit ScoreChart(Kind kind, QWidget* parent = nullptr);
  void SetScore(const netsim::ScoreResult* score);  // null: nothing scored
  // The largest value drawn (mm, or the largest count) and the number of points of each series.
  double y_max() const { return y_max_; }
  std::vector<int> series_points() const;
  QSize sizeHint() const override { return {360, 170}; }
  QSize minimumSizeHint() const override { return {200, 110}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  Kind kind_;
  const netsim::ScoreResult* score_ = nullptr;
  double y_max_ = 0.0;
};

class SimulationRoom : public QWidget {
  Q_OBJECT

 public:
  explicit SimulationRoom(QWidget* parent = nullptr);
  ~SimulationRoom() override;
  // Shows the presenters (null: nothing open); new ones drop the old ones' work.
  void Show(SimulationPresenter* simulation, ReconstructionPresenter* reconstruction);

  // The parts a person (and a test) works with.
  QDoubleSpinBox* sigma_box() const { return sigma_; }
  QPushButton* triangulate_button() const { return triangulate_button_; }
  QLineEdit* scenario_edit() const { return scenario_edit_; }
  QLineEdit* overrides_edit() const { return overrides_edit_; }
  QPushButton* simulate_button() const { return simulate_button_; }
  QPushButton* load_button() const { return load_button_; }
  QPushButton* cancel_button() const { return cancel_button_; }
  QProgressBar* progress() const { return progress_; }
  QTableWidget* simulations_table() const { return table_; }
  QComboBox* alignment_box() const { return alignment_; }
  QPushButton* score_button() const { return score_button_; }
  QPushButton* report_button() const { return report_button_; }
  QCheckBox* overlay_box() const { return show_simulated_; }
  QLabel* status_label() const { return status_; }
  QLabel* verdict_label() const { return verdict_; }
  QLabel* hover_label() const { return hover_; }
  QLineEdit* free_edit() const { return free_edit_; }
  QPushButton* fit_button() const { return fit_button_; }
  QLabel* fit_label() const { return fit_; }
  // The scenario's form: its main keys by dotted path; a value changed there becomes a --set
  // override in overrides_edit(), checked as netlab simulate checks the scenario.
  QTableWidget* form() const { return form_; }
  QLabel* form_check() const { return form_check_; }
  // Lists the scenario's keys (after its path is typed or chosen).
  void FillForm();
  ScoreChart* error_chart() const { return error_chart_; }
  ScoreChart* d2_chart() const { return d2_chart_; }
  // The net's knots coloured by their RMS error in the selected score (green 0, red the
  // largest).
  KnotGrid* error_grid() const { return error_grid_; }
  QLabel* error_grid_caption() const { return error_grid_caption_; }
  QSlider* frame_slider() const { return slider_; }
  CameraView* view(int c) const { return views_[c]; }
  int frame() const { return frame_; }
  void SetFrame(int t);
  // The slider's frame in words (ReconstructionPresenter::FrameStatus; "" : nothing open).
  QString FrameStatus() const {
    return reconstruction_ ? reconstruction_->FrameStatus(frame_) : QString();
  }
  // The simulation drawn and scored (-1: none).
  int selected() const { return selected_; }
  void Select(int i);
  // Load simulation… without its dialog.
  void LoadSimulation(const QString& path);
  // Work (a triangulation, a simulation, a score or a frame) is under way.
  bool busy() const;
  // The current frame is drawn in every view.
  bool frame_shown() const { return shown_frame_ == frame_; }

 signals:
  // The frame row shown changed (the labeling room opens at the frame left here).
  void frameChanged(int t);

 private:
  struct Loaded {
    int t = 0;
    std::array<ViewFrame, 4> frames;
    std::array<int, 4> width{}, height{};
    std::array<QString, 4> problems;
  };
  void Triangulate();
  void Simulate();
  // Scores simulation i on a worker (the labels triangulated first when there are no tracks);
  // a score asked for while one runs waits its turn.
  void Score(int i);
  void OpenReport();
  // The project file's folder: the score and fit files are written there.
  std::string ProjectFolder() const;
  // Fits the free parameters of the scenario (with its overrides) to the tracks on a worker.
  void Fit();
  void Cancel();
  void RequestFrame();
  void RefreshOverlays();
  void RefreshTable();
  void RefreshButtons();
  // The hover line for the cursor at `px` in a view; said again for the last cursor whenever
  // the overlays change (another simulation, frame or alignment), never left stale.
  void OnCursor(int camera, const Eigen::Vector2d& px);
  int hover_camera_ = -1;  // the view the cursor was last over (-1: none yet)
  Eigen::Vector2d hover_px_ = Eigen::Vector2d::Zero();
  void StartProgress(const QString& what);
  void StopProgress();
  bool Alive() const;

  SimulationPresenter* simulation_ = nullptr;
  ReconstructionPresenter* reconstruction_ = nullptr;
  std::weak_ptr<const int> alive_;
  int frame_ = 0, shown_frame_ = -1, selected_ = -1;
  std::vector<int> to_score_;  // asked for, after the running one (or the triangulation)
  int scoring_ = -1;

  QDoubleSpinBox* sigma_ = nullptr;
  QPushButton* triangulate_button_ = nullptr;
  QLabel* measured_ = nullptr;
  QLineEdit* scenario_edit_ = nullptr;
  QLineEdit* overrides_edit_ = nullptr;
  QPushButton *scenario_button_ = nullptr, *simulate_button_ = nullptr, *load_button_ = nullptr,
              *cancel_button_ = nullptr, *score_button_ = nullptr, *report_button_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QTableWidget* table_ = nullptr;
  QComboBox* alignment_ = nullptr;
  QCheckBox* show_simulated_ = nullptr;
  QLabel* status_ = nullptr;
  QLabel* verdict_ = nullptr;
  QLabel* hover_ = nullptr;
  QLineEdit* free_edit_ = nullptr;
  QPushButton* fit_button_ = nullptr;
  QLabel* fit_ = nullptr;
  QTableWidget* form_ = nullptr;
  QLabel* form_check_ = nullptr;
  std::string form_path_;
  bool filling_form_ = false;
  void SetOverride(const QString& key, const QString& value);
  bool CheckScenario();  // the scenario with the overrides loaded: said under the form
  ScoreChart* error_chart_ = nullptr;
  ScoreChart* d2_chart_ = nullptr;
  KnotGrid* error_grid_ = nullptr;
  QLabel* error_grid_caption_ = nullptr;
  void RefreshErrorGrid();
  QSlider* slider_ = nullptr;
  QLabel* frame_label_ = nullptr;
  std::array<CameraView*, 4> views_{};
  std::array<SimulatedView, 4> simulated_;  // what each view draws of the selected simulation
  QTimer* progress_timer_ = nullptr;
  std::shared_ptr<std::atomic<double>> fraction_ = std::make_shared<std::atomic<double>>(0.0);
  LatestRequest<TriangulationRun> triangulator_;
  LatestRequest<SimulationRun> simulator_;
  LatestRequest<ScoreRun> scorer_;
  // The fit's progress line, written by its worker and shown by the progress timer.
  struct FitStatus {
    std::mutex mutex;
    QString text;
  };
  std::shared_ptr<FitStatus> fit_status_ = std::make_shared<FitStatus>();
  LatestRequest<FitRun> fitter_;
  LatestRequest<Loaded> loader_;
};

}  // namespace netlab::gui
