#include "app/gui/simulation_room.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDesktopServices>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QPainter>
#include <QPainterPath>
#include <QProgressBar>
#include <QPushButton>
#include <QSlider>
#include <QSplitter>
#include <QTabWidget>
#include <QTableWidget>
#include <QTimer>
#include <QUrl>
#include <QVBoxLayout>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include "app/gui/document/session.h"
#include "app/gui/knot_grid.h"

namespace netlab::gui {
namespace {

// The hover line before the mouse is over a knot.
constexpr char kHoverPrompt[] = "Point at a knot: its label's distance to its simulated knot.";

// The labels in this room: one colour, apart from the simulated net's cyan.
const QColor kLabelColour(255, 150, 0);

QString Number(double v, int digits = 3) { return QString::number(v, 'g', digits); }

// A file in `folder` named `stem`.h5, or stem_2.h5, stem_3.h5, ... when it exists.
std::string FreshPath(const std::string& folder, const std::string& stem) {
  namespace fs = std::filesystem;
  fs::path path = fs::path(folder) / (stem + ".h5");
  for (int n = 2; fs::exists(path); ++n)
    path = fs::path(folder) / (stem + "_" + std::to_string(n) + ".h5");
  return path.string();
}

// The classes' colours in the error chart (corner, edge, inner).
const QColor kClassColour[3] = {QColor(220, 60, 60), QColor(40, 140, 220), QColor(60, 170, 60)};

// A round step for an axis up to `max`: 1, 2 or 5 times a power of ten, about 4 ticks.
double TickStep(double max) {
  if (!(max > 0)) return 1.0;
  const double raw = max / 4.0, power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * power >= raw) return m * power;
  return 10.0 * power;
}

// A tick's value as a person reads an axis: 3000, not 3e+03 (the steps are round, so six
// digits cut only the sums' rounding: 0.30000000000000004 reads 0.3; -0 reads 0).
QString TickLabel(double v) { return QString::number(v == 0.0 ? 0.0 : v, 'g', 6); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// ScoreChart

ScoreChart::ScoreChart(Kind kind, QWidget* parent) : QWidget(parent), kind_(kind) {}

void ScoreChart::SetScore(const netsim::ScoreResult* score) {
  score_ = score;
  y_max_ = 0.0;
  if (score_ != nullptr) {
    if (kind_ == Kind::kErrorOverTime) {
      for (const auto& row : score_->rms_per_class)
        for (double v : row)
          if (std::isfinite(v)) y_max_ = std::max(y_max_, v * 1e3);
    } else {
      for (size_t b = 0; b < score_->d2_counts.size(); ++b)
        y_max_ = std::max({y_max_, score_->d2_counts[b], score_->d2_expected[b]});
    }
  }
  update();
}

std::vector<int> ScoreChart::series_points() const {
  std::vector<int> n;
  if (score_ == nullptr) return n;
  if (kind_ == Kind::kD2Histogram) return {static_cast<int>(score_->d2_counts.size())};
  n.assign(3, 0);
  for (const auto& row : score_->rms_per_class)
    for (int c = 0; c < 3; ++c) n[c] += std::isfinite(row[c]);
  return n;
}

void ScoreChart::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.fillRect(rect(), Qt::white);
  painter.setRenderHint(QPainter::Antialiasing, true);
  const QString title = kind_ == Kind::kErrorOverTime
                            ? "RMS error (mm) per knot class over time (s)"
                            : "d²: counts (bars), chi²(3) expected (line)";
  painter.setPen(Qt::black);
  painter.drawText(QRect(6, 2, width() - 12, 16), Qt::AlignLeft | Qt::AlignVCenter, title);
  if (score_ == nullptr || y_max_ <= 0) {
    painter.setPen(Qt::gray);
    painter.drawText(rect(), Qt::AlignCenter, "Not scored yet.");
    return;
  }
  const QRectF plot(44, 22, width() - 54, height() - 42);
  double x0 = 0, x1 = 1;
  if (kind_ == Kind::kErrorOverTime && !score_->time.empty()) {
    x0 = score_->time.front();
    x1 = std::max(score_->time.back(), x0 + 1e-9);
  } else if (kind_ == Kind::kD2Histogram && !score_->d2_edges.empty()) {
    x0 = score_->d2_edges.front();
    x1 = score_->d2_edges.back();
  }
  const double y1 = 1.08 * y_max_;
  const auto X = [&](double x) { return plot.left() + (x - x0) / (x1 - x0) * plot.width(); };
  const auto Y = [&](double y) { return plot.bottom() - y / y1 * plot.height(); };
  // Phases (the error chart): shaded alternately, named at the top.
  if (kind_ == Kind::kErrorOverTime) {
    for (size_t p = 0; p < score_->summary.per_phase.size(); ++p) {
      const netsim::ScoreRow& row = score_->summary.per_phase[p];
      const double a = std::clamp(X(row.start_s), plot.left(), plot.right());
      const double b = std::clamp(X(row.end_s), plot.left(), plot.right());
      if (b <= a) continue;
      painter.fillRect(QRectF(a, plot.top(), b - a, plot.height()),
                       p % 2 ? QColor(245, 245, 245) : QColor(232, 238, 246));
      // The name and the phase's RMS error where they fit whole, else the name alone, cut with
      // "…" where three letters fit, else none (a phase a few pixels wide showed its name's
      // first letter, read with the next one's).
      const QString phase = QString::fromStdString(row.name);
      const int room = static_cast<int>(b - a - 4);
      QString name = std::isfinite(row.rms_m)
                         ? QString("%1 %2 mm").arg(phase).arg(row.rms_m * 1e3, 0, 'g', 3)
                         : phase;
      if (painter.fontMetrics().horizontalAdvance(name) > room) {
        name = painter.fontMetrics().elidedText(phase, Qt::ElideRight, room);
        if (name.size() < 4 && name != phase) continue;
      }
      painter.setPen(QColor(90, 90, 90));
      painter.drawText(QRectF(a + 2, plot.top(), b - a - 4, 14), Qt::AlignLeft | Qt::AlignTop,
                       name);
    }
  }
  // Axes and ticks.
  painter.setPen(QColor(120, 120, 120));
  painter.drawRect(plot);
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() - 1.5));
  painter.setFont(small);
  const double ystep = TickStep(y1);
  for (double y = 0; y <= y1 + 1e-12; y += ystep) {
    painter.drawLine(QPointF(plot.left() - 3, Y(y)), QPointF(plot.left(), Y(y)));
    painter.drawText(QRectF(0, Y(y) - 7, plot.left() - 5, 14), Qt::AlignRight | Qt::AlignVCenter,
                     TickLabel(y));
  }
  const double xstep = TickStep(x1 - x0);
  for (double x = std::ceil(x0 / xstep) * xstep; x <= x1 + 1e-12; x += xstep) {
    painter.drawLine(QPointF(X(x), plot.bottom()), QPointF(X(x), plot.bottom() + 3));
    painter.drawText(QRectF(X(x) - 30, plot.bottom() + 3, 60, 14), Qt::AlignCenter, TickLabel(x));
  }
  if (kind_ == Kind::kErrorOverTime) {
    for (int c = 0; c < 3; ++c) {
      QPainterPath path;
      bool open = false;
      for (size_t t = 0; t < score_->time.size(); ++t) {
        const double v = score_->rms_per_class[t][c];
        if (!std::isfinite(v)) {
          open = false;
          continue;
        }
        const QPointF p(X(score_->time[t]), Y(v * 1e3));
        open ? path.lineTo(p) : path.moveTo(p);
        open = true;
      }
      painter.setPen(QPen(kClassColour[c], 1.5));
      painter.setBrush(Qt::NoBrush);
      painter.drawPath(path);
      painter.drawText(QRectF(plot.right() - 150 + 50 * c, plot.bottom() - 16, 48, 14),
                       Qt::AlignCenter, netsim::kKnotClassNames[c]);
    }
  } else {
    painter.setPen(Qt::NoPen);
    painter.setBrush(QColor(120, 160, 220));
    for (size_t b = 0; b < score_->d2_counts.size(); ++b) {
      const double a = X(score_->d2_edges[b]), e = X(score_->d2_edges[b + 1]);
      painter.drawRect(QRectF(a + 0.5, Y(score_->d2_counts[b]), std::max(0.5, e - a - 1),
                              plot.bottom() - Y(score_->d2_counts[b])));
    }
    QPainterPath expected;
    for (size_t b = 0; b < score_->d2_expected.size(); ++b) {
      const double mid = 0.5 * (score_->d2_edges[b] + score_->d2_edges[b + 1]);
      const QPointF p(X(mid), Y(score_->d2_expected[b]));
      b == 0 ? expected.moveTo(p) : expected.lineTo(p);
    }
    painter.setPen(QPen(QColor(200, 60, 60), 1.5));
    painter.setBrush(Qt::NoBrush);
    painter.drawPath(expected);
  }
}

// ---------------------------------------------------------------------------------------------
// SimulationRoom

SimulationRoom::SimulationRoom(QWidget* parent)
    : QWidget(parent),
      triangulator_(this,
                    [this](TriangulationRun run) {
                      if (run.result) *fraction_ = 1.0;
                      StopProgress();
                      if (!Alive()) return;
                      const bool cancelled = run.cancelled;
                      const QString error = QString::fromStdString(run.error);
                      reconstruction_->SetRun(std::move(run));
                      QString saved;
                      if (!cancelled && error.isEmpty()) {
                        try {
                          reconstruction_->SaveToProject();
                          saved = " Written to " +
                                  QString::fromStdString(reconstruction_->tracks_path()) +
                                  " (the project's tracks).";
                        } catch (const std::exception& e) {
                          saved = QString(" Not saved: ") + e.what();
                        }
                      }
                      measured_->setText(reconstruction_->Summary());
                      status_->setText(cancelled         ? "Triangulation cancelled."
                                       : error.isEmpty() ? "Labels triangulated." + saved
                                                         : "Triangulation failed: " + error);
                      if (reconstruction_->tracks() == nullptr) to_score_.clear();
                      RefreshButtons();
                      RefreshOverlays();
                      if (!to_score_.empty()) {
                        const int next = to_score_.front();
                        to_score_.erase(to_score_.begin());
                        Score(next);
                      }
                    }),
      simulator_(this,
                 [this](SimulationRun run) {
                   if (run.tracks) *fraction_ = 1.0;
                   StopProgress();
                   if (!Alive()) return;
                   if (run.cancelled) {
                     status_->setText("Simulation cancelled (no file written).");
                   } else if (!run.tracks) {
                     status_->setText("Simulation failed: " + QString::fromStdString(run.error));
                   } else {
                     status_->setText(QString("Simulated in %1 s: %2")
                                          .arg(run.wall_s, 0, 'f', 1)
                                          .arg(QString::fromStdString(run.path)));
                     const int i = simulation_->Add(std::move(run));
                     try {
                       simulation_->AddToProject(i);
                     } catch (const std::exception& e) {
                       status_->setText(status_->text() + " Not named in the project: " + e.what());
                     }
                     RefreshTable();
                     Select(i);
                   }
                   RefreshButtons();
                 }),
      scorer_(this,
              [this](ScoreRun run) {
                StopProgress();
                if (!Alive()) return;
                const int i = run.index;
                simulation_->SetScore(std::move(run), ProjectFolder());
                status_->setText(
                    simulation_->simulation(i).score
                        ? "Scored " + QString::fromStdString(simulation_->simulation(i).name) + "."
                        : "Not scored.");
                scoring_ = -1;
                RefreshTable();
                // The person's selection stays (the project's simulations are scored in turn).
                Select(selected_ >= 0 ? selected_ : i);
                if (!to_score_.empty()) {
                  const int next = to_score_.front();
                  to_score_.erase(to_score_.begin());
                  Score(next);
                }
                RefreshButtons();
              }),
      fitter_(this,
              [this](FitRun run) {
                StopProgress();
                if (!Alive()) return;
                simulation_->SetFit(std::move(run), ProjectFolder());
                fit_->setText(simulation_->FitText());
                status_->setText(simulation_->fit()->cancelled ? "Fit cancelled."
                                 : simulation_->fit()->result  ? "Fitted."
                                                               : "The fit failed.");
                RefreshButtons();
              }),
      loader_(this, [this](Loaded loaded) {
        if (!Alive() || loaded.t != frame_) return;
        for (int c = 0; c < 4; ++c)
          if (views_[c])
            views_[c]->SetFrame(std::move(loaded.frames[c]), loaded.width[c], loaded.height[c],
                                loaded.problems[c]);
        shown_frame_ = loaded.t;
        RefreshOverlays();
      }) {
  auto* layout = new QVBoxLayout(this);

  // The measured tracks.
  auto* measured_row = new QHBoxLayout;
  measured_row->addWidget(new QLabel("Labels' σ (px)"));
  sigma_ = new QDoubleSpinBox;
  sigma_->setObjectName("simulation_sigma");
  sigma_->setRange(0.0, 10.0);
  sigma_->setDecimals(3);
  sigma_->setSingleStep(0.01);
  sigma_->setSpecialValueText("from the residuals");
  sigma_->setToolTip(
      "The labels' noise for the tracks' covariances (netlab triangulate "
      "--sigma-px); 0: estimated from the reprojection residuals");
  measured_row->addWidget(sigma_);
  triangulate_button_ = new QPushButton("Triangulate labels");
  triangulate_button_->setToolTip(
      "The labels triangulated into 3D knot tracks (netlab triangulate's engine, --ba points)");
  measured_row->addWidget(triangulate_button_);
  measured_ = new QLabel("Not triangulated yet.");
  measured_->setWordWrap(true);
  measured_row->addWidget(measured_, 1);
  layout->addLayout(measured_row);

  // The simulations: a scenario run, or a file loaded.
  auto* sim_row = new QHBoxLayout;
  sim_row->addWidget(new QLabel("Scenario"));
  scenario_edit_ = new QLineEdit;
  scenario_edit_->setObjectName("simulation_scenario");
  scenario_edit_->setPlaceholderText("scenario.yaml (docs/scenarios.md)");
  sim_row->addWidget(scenario_edit_, 2);
  scenario_button_ = new QPushButton("…");
  scenario_button_->setToolTip("Choose the scenario file");
  sim_row->addWidget(scenario_button_);
  overrides_edit_ = new QLineEdit;
  overrides_edit_->setObjectName("simulation_overrides");
  overrides_edit_->setPlaceholderText(
      "--set PATH=VALUE …, separated by spaces: drag.drag_coefficient=1.0 integrator.dt=1e-5");
  sim_row->addWidget(overrides_edit_, 3);
  simulate_button_ = new QPushButton("Simulate");
  sim_row->addWidget(simulate_button_);
  load_button_ = new QPushButton("Load simulation…");
  load_button_->setToolTip("A knot-track file written by netlab simulate");
  sim_row->addWidget(load_button_);
  cancel_button_ = new QPushButton("Cancel");
  sim_row->addWidget(cancel_button_);
  progress_ = new QProgressBar;
  progress_->setRange(0, 1000);
  progress_->setTextVisible(true);
  progress_->setFormat("");
  progress_->setMaximumWidth(220);
  sim_row->addWidget(progress_);
  layout->addLayout(sim_row);

  // The fit: the scenario's free parameters against the tracks.
  auto* fit_row = new QHBoxLayout;
  fit_row->addWidget(new QLabel("Fit"));
  free_edit_ = new QLineEdit;
  free_edit_->setObjectName("simulation_free");
  free_edit_->setPlaceholderText(
      "free parameters of the scenario, as netlab fit --free: drag.drag_coefficient,"
      "materials.nylon_1mm.bend_stiffness,time_offset (or tick keys in the Scenario tab's Fit "
      "column)");
  fit_row->addWidget(free_edit_, 1);
  fit_button_ = new QPushButton("Fit");
  fit_button_->setToolTip(
      "netlab fit's engine: the free parameters that make the scenario "
      "(with the overrides above) agree best with the triangulated labels");
  fit_row->addWidget(fit_button_);
  layout->addLayout(fit_row);

  status_ = new QLabel("Load a simulation, or choose a scenario and Simulate.");
  status_->setObjectName("simulation_status");
  status_->setWordWrap(true);
  layout->addWidget(status_);

  // The four cameras and the frame slider; on the right the simulations and the verdict.
  auto* splitter = new QSplitter(Qt::Horizontal);
  auto* views_box = new QWidget;
  auto* views_layout = new QVBoxLayout(views_box);
  views_layout->setContentsMargins(0, 0, 0, 0);
  auto* grid = new QGridLayout;
  grid->setSpacing(2);
  for (int c = 0; c < 4; ++c) {
    views_[c] = new CameraView(c);
    views_[c]->setMinimumSize(200, 160);
    views_[c]->SetShowEpipolar(false);
    grid->addWidget(views_[c], c / 2, c % 2);
    connect(views_[c], &CameraView::cursorMoved, this,
            [this](int camera, Eigen::Vector2d px, QString) { OnCursor(camera, px); });
  }
  views_layout->addLayout(grid, 1);
  auto* slider_row = new QHBoxLayout;
  slider_ = new QSlider(Qt::Horizontal);
  slider_->setObjectName("simulation_frame");
  slider_row->addWidget(slider_, 1);
  frame_label_ = new QLabel;
  frame_label_->setMinimumWidth(200);
  slider_row->addWidget(frame_label_);
  views_layout->addLayout(slider_row);
  hover_ = new QLabel(kHoverPrompt);
  hover_->setObjectName("simulation_hover");
  views_layout->addWidget(hover_);
  splitter->addWidget(views_box);

  auto* side = new QWidget;
  auto* side_layout = new QVBoxLayout(side);
  side_layout->setContentsMargins(4, 0, 0, 0);
  table_ = new QTableWidget(0, 5);
  table_->setObjectName("simulation_table");
  table_->setHorizontalHeaderLabels({"Simulation", "Verdict", "RMS (mm)", "mean d²", "p"});
  table_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::Stretch);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSelectionMode(QAbstractItemView::SingleSelection);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->verticalHeader()->hide();
  side_layout->addWidget(table_, 1);
  auto* score_row = new QHBoxLayout;
  score_row->addWidget(new QLabel("Align"));
  alignment_ = new QComboBox;
  alignment_->addItems({"time+rigid", "time", "rigid", "none"});
  alignment_->setToolTip(
      "As netlab score --align: the launch-time offset and/or one rigid motion fitted (a rig "
      "calibrated from a foil has its own world frame: time+rigid)");
  score_row->addWidget(alignment_);
  score_button_ = new QPushButton("Score");
  score_button_->setToolTip(
      "The selected simulation against the triangulated labels (netlab "
      "score's engine; the labels are triangulated first when need be)");
  score_row->addWidget(score_button_);
  report_button_ = new QPushButton("Open report");
  score_row->addWidget(report_button_);
  side_layout->addLayout(score_row);
  show_simulated_ = new QCheckBox("Simulated net over the frames");
  show_simulated_->setChecked(true);
  side_layout->addWidget(show_simulated_);
  auto* legend = new QLabel(
      "<span style='color:#ff9600'>○ labels</span> &nbsp; "
      "<span style='color:#00e6ff'>□ simulated knots and links</span>");
  side_layout->addWidget(legend);
  verdict_ = new QLabel("Not scored yet.");
  verdict_->setObjectName("simulation_verdict");
  verdict_->setWordWrap(true);
  verdict_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  verdict_->setMinimumWidth(320);
  verdict_->setAlignment(Qt::AlignTop | Qt::AlignLeft);
  // The verdict and its charts, and the scenario's form, as two tabs.
  auto* tabs = new QTabWidget;
  tabs->setObjectName("simulation_tabs");
  auto* verdict_page = new QWidget;
  auto* verdict_layout = new QVBoxLayout(verdict_page);
  verdict_layout->setContentsMargins(0, 4, 0, 0);
  verdict_layout->addWidget(verdict_, 1);
  fit_ = new QLabel;
  fit_->setObjectName("simulation_fit");
  fit_->setWordWrap(true);
  fit_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  verdict_layout->addWidget(fit_);
  error_chart_ = new ScoreChart(ScoreChart::Kind::kErrorOverTime);
  verdict_layout->addWidget(error_chart_);
  d2_chart_ = new ScoreChart(ScoreChart::Kind::kD2Histogram);
  auto* bottom = new QHBoxLayout;
  bottom->addWidget(d2_chart_, 3);
  auto* grid_box = new QVBoxLayout;
  error_grid_ = new KnotGrid;
  error_grid_->setObjectName("simulation_error_grid");
  error_grid_->setToolTip("Each knot's RMS error in the selected score: green 0, red the largest");
  grid_box->addWidget(error_grid_, 1);
  error_grid_caption_ = new QLabel;
  error_grid_caption_->setWordWrap(true);
  grid_box->addWidget(error_grid_caption_);
  bottom->addLayout(grid_box, 2);
  verdict_layout->addLayout(bottom);
  tabs->addTab(verdict_page, "Verdict");
  auto* form_page = new QWidget;
  auto* form_layout = new QVBoxLayout(form_page);
  form_layout->setContentsMargins(0, 4, 0, 0);
  form_ = new QTableWidget(0, 3);
  form_->setObjectName("simulation_form");
  form_->setHorizontalHeaderLabels({"Key (--set's dotted path)", "Value", "Fit"});
  form_->horizontalHeader()->setSectionResizeMode(1, QHeaderView::Stretch);
  form_->verticalHeader()->hide();
  form_->setToolTip(
      "The scenario's main keys; a changed value becomes a --set override, a number ticked in "
      "Fit a free parameter of the fit");
  form_layout->addWidget(form_, 1);
  form_check_ = new QLabel("Choose a scenario: its keys are listed here.");
  form_check_->setWordWrap(true);
  form_layout->addWidget(form_check_);
  tabs->addTab(form_page, "Scenario");
  side_layout->addWidget(tabs, 2);
  splitter->addWidget(side);
  splitter->setStretchFactor(0, 3);
  splitter->setStretchFactor(1, 1);
  layout->addWidget(splitter, 1);

  progress_timer_ = new QTimer(this);
  progress_timer_->setInterval(100);
  connect(progress_timer_, &QTimer::timeout, this, [this] {
    progress_->setValue(static_cast<int>(1000 * fraction_->load()));
    if (fitter_.pending()) {
      const std::lock_guard<std::mutex> lock(fit_status_->mutex);
      if (!fit_status_->text.isEmpty()) status_->setText("Fitting: " + fit_status_->text);
    }
  });

  connect(triangulate_button_, &QPushButton::clicked, this, [this] { Triangulate(); });
  connect(simulate_button_, &QPushButton::clicked, this, &SimulationRoom::Simulate);
  connect(load_button_, &QPushButton::clicked, this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, "Load a simulation", {},
                                                      "Knot tracks (*.h5);;All files (*)");
    if (!path.isEmpty()) LoadSimulation(path);
  });
  connect(scenario_button_, &QPushButton::clicked, this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, "Scenario", {},
                                                      "Scenarios (*.yaml *.yml);;All files (*)");
    if (path.isEmpty()) return;
    scenario_edit_->setText(path);
    FillForm();
  });
  connect(cancel_button_, &QPushButton::clicked, this, &SimulationRoom::Cancel);
  connect(score_button_, &QPushButton::clicked, this, [this] { Score(selected_); });
  connect(report_button_, &QPushButton::clicked, this, &SimulationRoom::OpenReport);
  connect(fit_button_, &QPushButton::clicked, this, &SimulationRoom::Fit);
  connect(scenario_edit_, &QLineEdit::editingFinished, this, &SimulationRoom::FillForm);
  connect(scenario_edit_, &QLineEdit::textChanged, this, [this] {
    form_->setRowCount(0);
    form_path_.clear();  // the same file typed again is listed again
  });
  connect(overrides_edit_, &QLineEdit::editingFinished, this, &SimulationRoom::CheckScenario);
  connect(form_, &QTableWidget::cellChanged, this, [this](int row, int column) {
    if (filling_form_) return;
    if (column == 2) {  // ticked or not: the key among the free parameters or not
      const QString key = form_->item(row, 0)->text();
      QStringList free;
      for (const QString& part : free_edit_->text().split(',', Qt::SkipEmptyParts))
        if (part.trimmed() != key) free << part.trimmed();
      if (form_->item(row, 2)->checkState() == Qt::Checked) free << key;
      free_edit_->setText(free.join(','));
      return;
    }
    if (column != 1) return;
    SetOverride(form_->item(row, 0)->text(), form_->item(row, 1)->text().trimmed());
  });
  connect(show_simulated_, &QCheckBox::toggled, this, [this] { RefreshOverlays(); });
  connect(slider_, &QSlider::valueChanged, this, [this](int t) { SetFrame(t); });
  connect(table_, &QTableWidget::itemSelectionChanged, this, [this] {
    const QList<QTableWidgetItem*> items = table_->selectedItems();
    if (!items.isEmpty() && items.front()->row() != selected_) Select(items.front()->row());
  });
  RefreshButtons();
}

SimulationRoom::~SimulationRoom() = default;

bool SimulationRoom::Alive() const { return simulation_ != nullptr && !alive_.expired(); }

void SimulationRoom::Show(SimulationPresenter* simulation,
                          ReconstructionPresenter* reconstruction) {
  if (simulation == simulation_ && reconstruction == reconstruction_) {
    RefreshButtons();
    if (simulation_) RequestFrame();
    return;
  }
  triangulator_.Drop();
  simulator_.Drop();
  scorer_.Drop();
  fitter_.Cancel();
  fitter_.Drop();
  loader_.Drop();
  loader_.Wait();  // it reads the old session's frames
  StopProgress();
  simulation_ = simulation;
  reconstruction_ = reconstruction;
  alive_ = simulation ? simulation->lifetime() : std::weak_ptr<const int>();
  selected_ = -1;
  error_chart_->SetScore(nullptr);  // it points into the old presenter's scores
  d2_chart_->SetScore(nullptr);
  verdict_->setText("Not scored yet.");
  verdict_->setStyleSheet({});
  fit_->setText("");
  shown_frame_ = -1;
  frame_ = 0;
  hover_camera_ = -1;
  hover_->setText(kHoverPrompt);
  to_score_.clear();
  scoring_ = -1;
  if (simulation_) {
    // The project's tracks and simulations, each scored: the room opens on their verdicts.
    const int before = simulation_->simulations();
    const std::vector<std::string> errors = simulation_->OpenFromProject(reconstruction_);
    QString text;
    for (const std::string& e : errors) text += QString::fromStdString(e) + "\n";
    if (!text.isEmpty()) status_->setText("Cannot read: " + text.trimmed());
    if (reconstruction_->tracks() != nullptr)
      for (int i = before; i < simulation_->simulations(); ++i) to_score_.push_back(i);
    // Scored again as the project's saved score was (its alignment), to the same colours.
    const QString alignment = QString::fromStdString(simulation_->SavedScoreAlignment());
    if (alignment_->findText(alignment) >= 0) alignment_->setCurrentText(alignment);
    const Session& s = reconstruction_->session();
    slider_->blockSignals(true);
    slider_->setRange(0, std::max(0, s.frames() - 1));
    slider_->setValue(0);
    slider_->blockSignals(false);
    measured_->setText(reconstruction_->Summary());
    fit_->setText(simulation_->FitText());
    RefreshTable();
    // The simulation whose saved score the Net grid showed before the room opened, else the
    // first.
    int first = simulation_->simulations() > 0 ? 0 : -1;
    const std::string saved = simulation_->SavedScoreSimulation();
    for (int i = 0; i < simulation_->simulations(); ++i)
      if (!saved.empty() && simulation_->simulation(i).path == saved) first = i;
    Select(first);
    RequestFrame();
    if (!to_score_.empty()) {
      const int next = to_score_.front();
      to_score_.erase(to_score_.begin());
      Score(next);
    }
  }
  RefreshButtons();
}

bool SimulationRoom::busy() const {
  return triangulator_.pending() || simulator_.pending() || scorer_.pending() ||
         fitter_.pending() || loader_.pending();
}

void SimulationRoom::SetFrame(int t) {
  if (!simulation_) return;
  const int frames = reconstruction_->session().frames();
  t = std::clamp(t, 0, std::max(0, frames - 1));
  if (slider_->value() != t) {
    slider_->blockSignals(true);
    slider_->setValue(t);
    slider_->blockSignals(false);
  }
  if (t == frame_ && shown_frame_ == t) return;
  frame_ = t;
  RequestFrame();
  emit frameChanged(t);
}

void SimulationRoom::RequestFrame() {
  if (!simulation_) return;
  const Session* session = &reconstruction_->session();
  const int t = frame_;
  std::array<double, 4> fit{};
  for (int c = 0; c < 4; ++c) fit[c] = views_[c]->FitScreenPerImage(2048);
  loader_.Request([session, t, fit](const CancelToken&) {
    Loaded loaded;
    loaded.t = t;
    for (int c = 0; c < std::min(4, session->cameras()); ++c) {
      std::string error;
      const cv::Mat image = session->Image(c, t, &error);
      if (image.empty()) {
        loaded.problems[c] = QString::fromStdString(error);
        continue;
      }
      loaded.width[c] = image.cols;
      loaded.height[c] = image.rows;
      const double screen_per_image = fit[c] * 2048.0 / std::max(1, image.cols);
      loaded.frames[c] = MakeViewFrame(image, screen_per_image, cv::Mat());
    }
    return loaded;
  });
  RefreshOverlays();
}

void SimulationRoom::Select(int i) {
  if (!simulation_ || i < 0 || i >= simulation_->simulations()) return;
  selected_ = i;
  simulation_->SetShown(i);
  if (table_->currentRow() != i) {
    table_->blockSignals(true);
    table_->selectRow(i);
    table_->blockSignals(false);
  }
  verdict_->setText("<b>" + QString::fromStdString(simulation_->simulation(i).name) + "</b><br>" +
                    simulation_->Verdict(i).toHtmlEscaped().replace("\n", "<br>"));
  const auto& score = simulation_->simulation(i).score;
  const QString colour = !score ? "palette(window)"
                         : score->summary.verdict == netsim::Verdict::kConsistent ? "#d8f5d0"
                                                                                  : "#f8d4d0";
  verdict_->setStyleSheet("QLabel { background: " + colour + "; padding: 6px; }");
  error_chart_->SetScore(score ? &*score : nullptr);
  d2_chart_->SetScore(score ? &*score : nullptr);
  RefreshErrorGrid();
  RefreshOverlays();
  RefreshButtons();
}

void SimulationRoom::RefreshErrorGrid() {
  const Session* session = reconstruction_ ? &reconstruction_->session() : nullptr;
  if (session == nullptr) return;
  const int rows = session->project().rows, cols = session->project().cols;
  if (error_grid_->rows() != rows || error_grid_->cols() != cols) error_grid_->SetNet(rows, cols);
  std::vector<KnotGrid::Cell> cells(rows * cols);
  const netsim::ScoreResult* score = selected_ >= 0 && simulation_->simulation(selected_).score
                                         ? &*simulation_->simulation(selected_).score
                                         : nullptr;
  double worst = 0.0;
  if (score != nullptr)
    for (const netsim::ScoreRow& row : score->summary.per_knot)
      if (std::isfinite(row.rms_m)) worst = std::max(worst, row.rms_m);
  if (score != nullptr && worst > 0 &&
      static_cast<int>(score->summary.per_knot.size()) == rows * cols) {
    for (int k = 0; k < rows * cols; ++k) {
      const double rms = score->summary.per_knot[k].rms_m;
      if (!std::isfinite(rms)) continue;
      cells[k].label = KnotGrid::ErrorColour(rms / worst);
    }
    error_grid_caption_->setText(
        QString("Per knot: RMS 0 (green) to %1 mm (red)").arg(worst * 1e3, 0, 'g', 3));
  } else {
    error_grid_caption_->setText(score ? "Per knot: no error" : "Per knot: not scored");
  }
  error_grid_->SetCells(std::move(cells));
}

void SimulationRoom::RefreshTable() {
  if (!simulation_) return;
  table_->blockSignals(true);
  table_->setRowCount(simulation_->simulations());
  for (int i = 0; i < simulation_->simulations(); ++i) {
    const Simulation& s = simulation_->simulation(i);
    auto set = [&](int column, const QString& text) {
      auto* item = new QTableWidgetItem(text);
      if (column > 0) item->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
      table_->setItem(i, column, item);
    };
    set(0, QString::fromStdString(s.name));
    set(1, s.score ? QString::fromStdString(netsim::VerdictName(s.score->summary.verdict))
           : s.score_error.empty() ? "—"
                                   : "error");
    set(2, s.score ? Number(s.score->summary.rms_m * 1e3) : "");
    set(3, s.score ? Number(s.score->summary.mean_d2) : "");
    set(4, s.score ? Number(s.score->summary.p_value, 2) : "");
    if (s.score)
      table_->item(i, 1)->setForeground(s.score->summary.verdict == netsim::Verdict::kConsistent
                                            ? QColor(0, 130, 0)
                                            : QColor(190, 0, 0));
  }
  table_->resizeColumnsToContents();
  table_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::Stretch);
  table_->setToolTip("A row per simulation: its score against the triangulated labels");
  for (int i = 0; i < table_->rowCount(); ++i)
    table_->item(i, 0)->setToolTip(QString::fromStdString(simulation_->simulation(i).path));
  table_->blockSignals(false);
}

void SimulationRoom::RefreshButtons() {
  const bool open = simulation_ != nullptr;
  const bool working =
      triangulator_.pending() || simulator_.pending() || scorer_.pending() || fitter_.pending();
  triangulate_button_->setEnabled(open && !working);
  simulate_button_->setEnabled(open && !working);
  load_button_->setEnabled(open && !working);
  cancel_button_->setEnabled(working);
  score_button_->setEnabled(open && !working && selected_ >= 0);
  fit_button_->setEnabled(open && !working);
  report_button_->setEnabled(open && selected_ >= 0 &&
                             !simulation_->simulation(selected_).report_path.empty());
}

void SimulationRoom::StartProgress(const QString& what) {
  *fraction_ = 0.0;
  progress_->setRange(0, 1000);
  progress_->setValue(0);
  progress_->setFormat(what + " %p%");
  progress_timer_->start();
  RefreshButtons();
}

void SimulationRoom::StopProgress() {
  progress_timer_->stop();
  progress_->setRange(0, 1000);
  progress_->setValue(static_cast<int>(1000 * fraction_->load()));
  QTimer::singleShot(0, this, [this] { RefreshButtons(); });
}

void SimulationRoom::Triangulate() {
  if (!simulation_) return;
  TriangulationOptions options;
  options.sigma_px = sigma_->value();
  TriangulationJob job;
  try {
    job = reconstruction_->MakeJob(options);
  } catch (const std::exception& e) {
    status_->setText(QString("Cannot triangulate: ") + e.what());
    return;
  }
  status_->setText("Triangulating the labels…");
  auto fraction = fraction_;
  triangulator_.Request([job = std::move(job), fraction](const CancelToken& cancel) {
    return ReconstructionPresenter::Triangulate(
        job, ProgressReporter([fraction](const Progress& p) { *fraction = p.fraction(); }, cancel));
  });
  StartProgress("triangulate");
}

void SimulationRoom::Simulate() {
  if (!simulation_) return;
  const std::string scenario = scenario_edit_->text().trimmed().toStdString();
  if (scenario.empty()) {
    status_->setText("Choose a scenario file first (or Load simulation…).");
    return;
  }
  std::vector<std::string> overrides;
  for (const QString& part : overrides_edit_->text().split(' ', Qt::SkipEmptyParts))
    overrides.push_back(part.toStdString());
  const std::string folder =
      QFileInfo(QString::fromStdString(reconstruction_->session().project().path))
          .absolutePath()
          .toStdString();
  SimulationJob job;
  try {
    job = SimulationPresenter::MakeSimulationJob(
        scenario, overrides,
        FreshPath(folder, "sim_" + std::filesystem::path(scenario).stem().string()));
  } catch (const std::exception& e) {
    status_->setText(QString("Cannot simulate: ") + e.what());
    return;
  }
  status_->setText("Simulating " + QString::fromStdString(scenario) + "…");
  auto fraction = fraction_;
  simulator_.Request([job = std::move(job), fraction](const CancelToken& cancel) {
    return SimulationPresenter::Simulate(
        job, ProgressReporter([fraction](const Progress& p) { *fraction = p.fraction(); }, cancel));
  });
  StartProgress("simulate");
}

void SimulationRoom::LoadSimulation(const QString& path) {
  if (!simulation_) return;
  SimulationRun run = SimulationPresenter::Load(path.toStdString());
  if (!run.tracks) {
    status_->setText("Cannot load the simulation: " + QString::fromStdString(run.error));
    return;
  }
  const int i = simulation_->Add(std::move(run));
  status_->setText("Loaded " + path + ".");
  try {
    simulation_->AddToProject(i);
  } catch (const std::exception& e) {
    status_->setText(status_->text() + " Not named in the project: " + e.what());
  }
  RefreshTable();
  Select(i);
}

void SimulationRoom::Score(int i) {
  if (!simulation_ || i < 0 || i >= simulation_->simulations()) return;
  if (scoring_ >= 0 || triangulator_.pending()) {  // its turn comes
    to_score_.push_back(i);
    return;
  }
  if (simulation_->measured() == nullptr) {  // the labels first
    to_score_.insert(to_score_.begin(), i);
    Triangulate();
    return;
  }
  netsim::Alignment alignment = netsim::Alignment::kTimeAndRigid;
  netsim::ParseAlignment(alignment_->currentText().toStdString(), &alignment);
  ScoreJob job = simulation_->MakeScoreJob(i, alignment);
  scoring_ = i;
  status_->setText("Scoring " + QString::fromStdString(simulation_->simulation(i).name) + "…");
  scorer_.Request(
      [job = std::move(job)](const CancelToken&) { return SimulationPresenter::RunScore(job); });
  progress_->setRange(0, 0);  // the score has no progress to tell: busy
  RefreshButtons();
}

void SimulationRoom::FillForm() {
  const std::string path = scenario_edit_->text().trimmed().toStdString();
  if (path.empty() || path == form_path_) return;
  form_path_ = path;
  std::vector<std::pair<std::string, std::string>> rows;
  try {
    rows = SimulationPresenter::ScenarioKeys(path);
  } catch (const std::exception& e) {
    form_check_->setText(
        QString("<span style='color:#b00000'>%1</span>").arg(QString(e.what()).toHtmlEscaped()));
    return;
  }
  filling_form_ = true;
  form_->setRowCount(static_cast<int>(rows.size()));
  for (size_t i = 0; i < rows.size(); ++i) {
    auto* key = new QTableWidgetItem(QString::fromStdString(rows[i].first));
    key->setFlags(key->flags() & ~Qt::ItemIsEditable);
    form_->setItem(static_cast<int>(i), 0, key);
    form_->setItem(static_cast<int>(i), 1,
                   new QTableWidgetItem(QString::fromStdString(rows[i].second)));
    // A number can be a free parameter of the fit: a box, ticked when the fit names it already.
    auto* free = new QTableWidgetItem;
    free->setFlags(Qt::ItemIsEnabled);
    bool number = false;
    QString::fromStdString(rows[i].second).toDouble(&number);
    if (number) {
      free->setFlags(Qt::ItemIsEnabled | Qt::ItemIsUserCheckable);
      const QStringList named = free_edit_->text().split(',', Qt::SkipEmptyParts);
      const bool ticked = std::any_of(named.begin(), named.end(), [&](const QString& part) {
        return part.trimmed() == key->text();
      });
      free->setCheckState(ticked ? Qt::Checked : Qt::Unchecked);
    }
    form_->setItem(static_cast<int>(i), 2, free);
  }
  form_->resizeColumnToContents(0);
  form_->resizeColumnToContents(2);
  filling_form_ = false;
  CheckScenario();
}

void SimulationRoom::SetOverride(const QString& key, const QString& value) {
  // The overrides edit keeps one PATH=VALUE per key: this one replaced or added.
  QStringList parts = overrides_edit_->text().split(' ', Qt::SkipEmptyParts);
  parts.erase(std::remove_if(parts.begin(), parts.end(),
                             [&](const QString& p) { return p.startsWith(key + "="); }),
              parts.end());
  QString compact = value;
  compact.remove(' ');  // one word each: [0.5, 0, 0] as [0.5,0,0]
  parts.push_back(key + "=" + compact);
  overrides_edit_->setText(parts.join(' '));
  CheckScenario();
}

bool SimulationRoom::CheckScenario() {
  const std::string path = scenario_edit_->text().trimmed().toStdString();
  if (path.empty()) return false;
  std::vector<std::string> overrides;
  for (const QString& part : overrides_edit_->text().split(' ', Qt::SkipEmptyParts))
    overrides.push_back(part.toStdString());
  const std::string error = SimulationPresenter::CheckScenario(path, overrides);
  if (!error.empty()) {
    form_check_->setText(QString("<span style='color:#b00000'>%1</span>")
                             .arg(QString::fromStdString(error).toHtmlEscaped()));
    return false;
  }
  form_check_->setText(QString("The scenario is valid with %1 override%2.")
                           .arg(overrides.size())
                           .arg(overrides.size() == 1 ? "" : "s"));
  return true;
}

void SimulationRoom::Fit() {
  if (!simulation_) return;
  const std::string scenario = scenario_edit_->text().trimmed().toStdString();
  const std::string free = free_edit_->text().trimmed().toStdString();
  if (scenario.empty() || free.empty()) {
    status_->setText("Choose the scenario and type its free parameters first.");
    return;
  }
  if (simulation_->measured() == nullptr) {
    status_->setText("Triangulate the labels first (the fit compares with their tracks).");
    return;
  }
  std::vector<std::string> overrides;
  for (const QString& part : overrides_edit_->text().split(' ', Qt::SkipEmptyParts))
    overrides.push_back(part.toStdString());
  FitJob job;
  try {
    job = simulation_->MakeFitJob(scenario, overrides, free);
  } catch (const std::exception& e) {
    status_->setText(QString("Cannot fit: ") + e.what());
    return;
  }
  {
    const std::lock_guard<std::mutex> lock(fit_status_->mutex);
    fit_status_->text.clear();
  }
  status_->setText("Fitting " + QString::fromStdString(free) + "…");
  fit_->setText("");
  auto status = fit_status_;
  fitter_.Request([job = std::move(job), status](const CancelToken& cancel) {
    const auto start = std::chrono::steady_clock::now();
    return SimulationPresenter::Fit(
        job,
        ProgressReporter(
            [status, start](const Progress& p) {
              const double elapsed_s =
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
              const std::lock_guard<std::mutex> lock(status->mutex);
              status->text = SimulationPresenter::ProgressText(p, elapsed_s);
            },
            cancel));
  });
  progress_->setRange(0, 0);  // busy: the fit's ETA is in the status line
  progress_timer_->start();
  RefreshButtons();
}

std::string SimulationRoom::ProjectFolder() const {
  return QFileInfo(QString::fromStdString(reconstruction_->session().project().path))
      .absolutePath()
      .toStdString();
}

void SimulationRoom::OpenReport() {
  if (!simulation_ || selected_ < 0) return;
  const std::string& report = simulation_->simulation(selected_).report_path;
  if (!report.empty())
    QDesktopServices::openUrl(QUrl::fromLocalFile(QString::fromStdString(report)));
}

void SimulationRoom::Cancel() {
  triangulator_.Cancel();
  simulator_.Cancel();
  fitter_.Cancel();  // stops its simulations under way; the answer says cancelled
  // A score is not cancellable inside: its answer is dropped.
  to_score_.clear();
  if (scorer_.pending()) {
    scorer_.Drop();
    scoring_ = -1;
    StopProgress();
    status_->setText("Score cancelled.");
  }
  if (triangulator_.pending()) {
    // The engine stops only between its stages: forget the answer now.
    triangulator_.Drop();
    StopProgress();
    status_->setText("Triangulation cancelled.");
  }
}

void SimulationRoom::RefreshOverlays() {
  if (!simulation_) return;
  const Session& session = reconstruction_->session();
  const recon::LabelSet& labels = session.document().labels();
  const int t = frame_;
  const bool draw = show_simulated_->isChecked() && selected_ >= 0;
  for (int c = 0; c < 4; ++c) {
    ViewOverlay overlay;
    simulated_[c] = SimulatedView();
    if (c >= session.cameras()) {
      views_[c]->SetOverlay(overlay);
      continue;
    }
    for (int k = 0; k < labels.knots(); ++k) {
      const recon::Label& l = labels.at(c, t, k);
      if (!l.present()) continue;
      overlay.labels.push_back({k, l.px, kLabelColour, l.state == recon::LabelState::kNeedsReview});
    }
    QString caption = QString("%1 · frame %2")
                          .arg(QString::fromStdString(session.camera_names()[c]))
                          .arg(session.frame_number(t));
    if (draw) {
      simulated_[c] = simulation_->InCamera(selected_, c, t);
      for (size_t i = 0; i < simulated_[c].knots.size(); ++i)
        overlay.simulated.push_back({simulated_[c].knots[i], simulated_[c].px[i], {}, false});
      overlay.simulated_links = simulated_[c].links;
      caption += QString(" · simulated t = %1 s").arg(simulated_[c].sim_time_s, 0, 'f', 4);
    }
    overlay.caption = caption;
    views_[c]->SetOverlay(std::move(overlay));
  }
  frame_label_->setText(reconstruction_->FrameStatus(t));
  if (hover_camera_ >= 0) OnCursor(hover_camera_, hover_px_);
}

void SimulationRoom::OnCursor(int camera, const Eigen::Vector2d& px) {
  if (!simulation_ || camera >= reconstruction_->session().cameras()) return;
  hover_camera_ = camera;
  hover_px_ = px;
  const Session& session = reconstruction_->session();
  const int t = frame_;
  // The knot nearest the cursor among the labels and the simulated knots, within 12 screen px.
  const double reach = 12.0 / std::max(1e-9, views_[camera]->scale());
  int best = -1;
  double best_d = reach;
  const recon::LabelSet& labels = session.document().labels();
  for (int k = 0; k < labels.knots(); ++k) {
    const recon::Label& l = labels.at(camera, t, k);
    if (l.present() && (l.px - px).norm() < best_d) best_d = (l.px - px).norm(), best = k;
  }
  const SimulatedView& sim = simulated_[camera];
  for (size_t i = 0; i < sim.knots.size(); ++i)
    if ((sim.px[i] - px).norm() < best_d) best_d = (sim.px[i] - px).norm(), best = sim.knots[i];
  if (best < 0) {
    hover_->setText(kHoverPrompt);
    return;
  }
  const int cols = session.project().cols;
  QString text = QString("%1, frame %2, knot (%3,%4): ")
                     .arg(QString::fromStdString(session.camera_names()[camera]))
                     .arg(session.frame_number(t))
                     .arg(best / cols)
                     .arg(best % cols);
  if (selected_ < 0) {
    text += "no simulation";
  } else if (const auto d = simulation_->LabelDistancePx(selected_, camera, t, best)) {
    text += QString("label to simulated knot %1 px").arg(*d, 0, 'f', 2);
  } else {
    text += labels.at(camera, t, best).present() ? "not simulated here" : "no label";
  }
  if (selected_ >= 0)
    if (const auto r = simulation_->ResidualM(selected_, t, best))
      text += QString("; in 3D, measured to simulated %1 mm").arg(*r * 1e3, 0, 'f', 2);
  hover_->setText(text);
}

}  // namespace netlab::gui
