#include "app/gui/recording_room.h"

#include <QHeaderView>
#include <QLabel>
#include <QPainter>
#include <QPainterPath>
#include <QTableWidget>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <limits>

#include "app/gui/timeline.h"

namespace netlab::gui {
namespace {

// One colour per camera, as distinct as four can be.
QColor SeriesColour(int i) {
  static const QColor colours[] = {QColor(31, 119, 180),  QColor(255, 127, 14),
                                   QColor(44, 160, 44),   QColor(214, 39, 40),
                                   QColor(148, 103, 189), QColor(140, 86, 75)};
  return colours[i % 6];
}

}  // namespace

TimestampPlot::TimestampPlot(QWidget* parent) : QWidget(parent) {
  setMinimumHeight(180);
  setAutoFillBackground(true);
  QPalette p = palette();
  p.setColor(QPalette::Window, Qt::white);
  setPalette(p);
}

void TimestampPlot::SetSeries(std::vector<TimestampSeries> series) {
  series_ = std::move(series);
  update();
}

void TimestampPlot::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  const QRectF area(70, 28, width() - 90, height() - 62);  // the plot inside its axes
  painter.setPen(Qt::black);
  painter.drawText(QRectF(0, 4, width(), 20), Qt::AlignHCenter,
                   "Each camera's timestamp minus the cameras' mean at that frame (ms)");
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const TimestampSeries& s : series_)
    for (const Eigen::Vector2d& p : s.points) {
      x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
    }
  if (series_.empty() || !std::isfinite(x0)) {
    painter.setPen(Qt::darkGray);
    painter.drawText(area, Qt::AlignCenter,
                     "No timestamps to compare: fewer than two cameras carry them "
                     "(experiment.yaml: timestamps)");
    return;
  }
  // A symmetric range around 0, at least ±0.01 ms, so that equal clocks draw flat at the middle.
  const double span = std::max({std::abs(y0), std::abs(y1), 0.01}) * 1.15;
  y0 = -span, y1 = span;
  if (x1 <= x0) x1 = x0 + 1;
  const auto map = [&](const Eigen::Vector2d& p) {
    return QPointF(area.left() + (p.x() - x0) / (x1 - x0) * area.width(),
                   area.bottom() - (p.y() - y0) / (y1 - y0) * area.height());
  };
  // Axes, the zero line and the ticks.
  painter.setPen(QPen(Qt::black, 1));
  painter.drawRect(area);
  painter.setPen(QPen(Qt::gray, 1, Qt::DashLine));
  painter.drawLine(map({x0, 0}), map({x1, 0}));
  painter.setPen(Qt::black);
  for (double y : {y0, 0.0, y1})
    painter.drawText(QRectF(0, map({x0, y}).y() - 8, area.left() - 6, 16),
                     Qt::AlignRight | Qt::AlignVCenter, QString::number(y, 'g', 3));
  for (double x : {x0, (x0 + x1) / 2, x1})
    painter.drawText(QRectF(map({x, y0}).x() - 40, area.bottom() + 2, 80, 16), Qt::AlignHCenter,
                     QString::number(std::lround(x)));
  painter.drawText(QRectF(area.left(), area.bottom() + 16, area.width(), 16), Qt::AlignHCenter,
                   "frame");
  painter.save();
  painter.translate(12, area.center().y());
  painter.rotate(-90);
  painter.drawText(QRectF(-60, -8, 120, 16), Qt::AlignCenter, "offset (ms)");
  painter.restore();
  // One line per camera, and its name in the legend.
  for (int i = 0; i < static_cast<int>(series_.size()); ++i) {
    const TimestampSeries& s = series_[i];
    QPainterPath path;
    for (size_t j = 0; j < s.points.size(); ++j)
      j == 0 ? path.moveTo(map(s.points[j])) : path.lineTo(map(s.points[j]));
    painter.setPen(QPen(SeriesColour(i), 1.6));
    painter.drawPath(path);
    const QPointF legend(area.right() - 90, area.top() + 10 + 16 * i);
    painter.drawLine(legend, legend + QPointF(18, 0));
    painter.setPen(Qt::black);
    painter.drawText(legend + QPointF(24, 5), QString::fromStdString(s.camera));
  }
}

RecordingRoom::RecordingRoom(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  summary_ = new QLabel;
  summary_->setWordWrap(true);
  summary_->setObjectName("recording_summary");
  layout->addWidget(summary_);
  table_ = new QTableWidget(0, 4);
  table_->setObjectName("findings_table");
  table_->setHorizontalHeaderLabels({"Camera", "Finding", "Frames", "What it means"});
  table_->horizontalHeader()->setStretchLastSection(true);
  table_->verticalHeader()->setVisible(false);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSelectionMode(QAbstractItemView::SingleSelection);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  layout->addWidget(table_, 2);
  auto* marks = new QLabel("Frames with findings (red marks; a click goes to the frame):");
  layout->addWidget(marks);
  timeline_ = new Timeline;
  timeline_->setObjectName("recording_timeline");
  layout->addWidget(timeline_);
  plot_ = new TimestampPlot;
  layout->addWidget(plot_, 3);
  connect(table_, &QTableWidget::cellClicked, this, [this](int row, int) {
    if (row >= 0 && row < static_cast<int>(findings_.size()) && !findings_[row].frames.empty())
      emit goToFrame(findings_[row].frames.front());
  });
  connect(timeline_, &Timeline::seek, this, [this](int t) {
    if (presenter_) emit goToFrame(presenter_->sequence().first_frame() + t);
  });
}

void RecordingRoom::Show(const RecordingPresenter* presenter) {
  presenter_ = presenter;
  findings_ = presenter ? presenter->Findings() : std::vector<RecordingFinding>{};
  summary_->setText(presenter ? presenter->Summary() : QString("No recording open."));
  table_->setRowCount(static_cast<int>(findings_.size()));
  for (int row = 0; row < static_cast<int>(findings_.size()); ++row) {
    const RecordingFinding& f = findings_[row];
    const QStringList cells = {
        QString::fromStdString(f.camera_name), QString::fromStdString(f.kind),
        RecordingPresenter::FrameList(f.frames), QString::fromStdString(f.detail)};
    for (int column = 0; column < cells.size(); ++column)
      table_->setItem(row, column, new QTableWidgetItem(cells[column]));
  }
  table_->resizeColumnsToContents();
  if (presenter) {
    const int first = presenter->sequence().first_frame();
    timeline_->SetRange(presenter->sequence().last_frame() - first + 1);
    std::set<int> rows;
    for (int f : presenter->MarkedFrames()) rows.insert(f - first);
    timeline_->SetReviewFrames(std::move(rows));
    plot_->SetSeries(presenter->Offsets());
  } else {
    timeline_->SetReviewFrames({});
    plot_->SetSeries({});
  }
}

}  // namespace netlab::gui
