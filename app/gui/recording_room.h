#pragma once
// The recording room: the project's four streams as `netlab ingest --check` finds them. A line of
// summary, the findings per camera in a table (a click on a row goes to its first frame), the
// frames with findings marked on a timeline (a click goes to the frame), and each camera's
// timestamps against the others' as a plot. It draws what the RecordingPresenter
// (document/recording_presenter.h) says; the window runs the check and owns the presenter.

#include <QWidget>
#include <vector>

#include "app/gui/document/recording_presenter.h"

class QLabel;
class QTableWidget;

namespace netlab::gui {

class Timeline;

// Each camera's timestamp offsets (ms) over the frames, one coloured line per camera, with the
// axes labeled and a legend.
class TimestampPlot : public QWidget {
  Q_OBJECT

 public:
  explicit TimestampPlot(QWidget* parent = nullptr);
  void SetSeries(std::vector<TimestampSeries> series);
  QSize sizeHint() const override { return {600, 220}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  std::vector<TimestampSeries> series_;
};

class RecordingRoom : public QWidget {
  Q_OBJECT

 public:
  explicit RecordingRoom(QWidget* parent = nullptr);
  // Shows `presenter`'s state (null: nothing open). Call again after its report changed.
  void Show(const RecordingPresenter* presenter);
  QTableWidget* table() const { return table_; }
  Timeline* timeline() const { return timeline_; }

 signals:
  // The person asked for this frame (the recording's number).
  void goToFrame(int frame_number);

 private:
  const RecordingPresenter* presenter_ = nullptr;
  QLabel* summary_ = nullptr;
  QTableWidget* table_ = nullptr;
  Timeline* timeline_ = nullptr;
  TimestampPlot* plot_ = nullptr;
  std::vector<RecordingFinding> findings_;
};

}  // namespace netlab::gui
