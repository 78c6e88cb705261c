#include "app/gui/document/recording_presenter.h"

#include <QStringList>
#include <algorithm>
#include <map>

#include "libreconstruct/recording/experiment.h"

namespace netlab::gui {

RecordingPresenter::RecordingPresenter(const std::string& experiment_path)
    : experiment_path_(experiment_path),
      sequence_(
          std::make_unique<recon::SynchronizedSequence>(recon::LoadExperiment(experiment_path))) {}

recon::CheckReport RecordingPresenter::Check(const recon::SynchronizedSequence& sequence,
                                             bool decode, const ProgressReporter& progress) {
  return sequence.Check(decode, progress);
}

std::vector<RecordingFinding> RecordingPresenter::Findings() const {
  std::vector<RecordingFinding> rows;
  if (!report_) return rows;
  for (int c = 0; c < static_cast<int>(report_->cameras.size()); ++c) {
    const recon::CameraReport& r = report_->cameras[c];
    const auto add = [&](const char* kind, std::vector<int> frames, std::string detail) {
      if (frames.empty()) return;
      std::sort(frames.begin(), frames.end());
      rows.push_back({c, r.name, kind, std::move(frames), std::move(detail)});
    };
    add("missing", r.missing, "no frame with this number");
    add("unreadable", r.unreadable,
        r.problems.empty() ? "present but cannot be read" : r.problems.front());
    add("duplicated", r.duplicated, "the same timestamp as, or identical to, the frame before");
    add("timestamp gap", r.timestamp_gaps, "the timestamps skip frames after this one");
    add("untimed", r.untimed, "no timestamp where the camera has them");
  }
  return rows;
}

std::set<int> RecordingPresenter::MarkedFrames() const {
  std::set<int> frames;
  for (const RecordingFinding& f : Findings()) frames.insert(f.frames.begin(), f.frames.end());
  return frames;
}

QString RecordingPresenter::FrameList(const std::vector<int>& frames, int shown) {
  QStringList numbers;
  for (int i = 0; i < static_cast<int>(frames.size()) && i < shown; ++i)
    numbers << QString::number(frames[i]);
  QString text = numbers.join(", ");
  if (static_cast<int>(frames.size()) > shown) text += " …";
  return text + QString(" (%1 frame%2)").arg(frames.size()).arg(frames.size() == 1 ? "" : "s");
}

QString RecordingPresenter::Summary() const {
  const recon::Experiment& e = sequence_->experiment();
  QString text = QString("%1: %2 cameras, frames %3–%4 at %5 fps")
                     .arg(QString::fromStdString(experiment_path_))
                     .arg(sequence_->num_cameras())
                     .arg(sequence_->first_frame())
                     .arg(sequence_->last_frame())
                     .arg(e.fps);
  if (!report_) return text + " · checking every frame's header…";
  int findings = 0;
  for (const RecordingFinding& f : Findings()) findings += static_cast<int>(f.frames.size());
  text += QString(" · %1 synchronized frames · %2 · checked in %3 s")
              .arg(report_->synchronized_frames)
              .arg(findings == 0
                       ? QString("no findings: every camera whole")
                       : QString("%1 frame finding%2").arg(findings).arg(findings == 1 ? "" : "s"))
              .arg(report_->wall_s, 0, 'f', 2);
  for (const std::string& w : report_->warnings) text += " · " + QString::fromStdString(w);
  return text;
}

std::vector<TimestampSeries> RecordingPresenter::Offsets() const {
  const int cameras = sequence_->num_cameras();
  std::vector<std::map<int, double>> times(cameras);
  // As the sequence reads them: the experiment's timestamps file, else the source's own times.
  for (int c = 0; c < cameras; ++c) {
    const std::string& file = sequence_->experiment().cameras[c].timestamps;
    times[c] = file.empty() ? sequence_->source(c).Timestamps() : recon::ReadTimestamps(file);
  }
  std::vector<int> timed;
  for (int c = 0; c < cameras; ++c)
    if (!times[c].empty()) timed.push_back(c);
  std::vector<TimestampSeries> series;
  if (timed.size() < 2) return series;
  for (int c : timed) series.push_back({sequence_->experiment().cameras[c].name, {}});
  for (int f = sequence_->first_frame(); f <= sequence_->last_frame(); ++f) {
    double sum = 0.0;
    bool all = true;
    for (int c : timed) {
      const auto it = times[c].find(f);
      if (it == times[c].end()) {
        all = false;
        break;
      }
      sum += it->second;
    }
    if (!all) continue;
    const double mean = sum / static_cast<double>(timed.size());
    for (size_t i = 0; i < timed.size(); ++i)
      series[i].points.emplace_back(f, (times[timed[i]].at(f) - mean) * 1e3);
  }
  return series;
}

}  // namespace netlab::gui
