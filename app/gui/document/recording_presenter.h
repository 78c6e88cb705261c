#pragma once
// The recording room without a window: `netlab ingest --check`'s findings on the project's four
// streams (missing, unreadable, duplicated frames, timestamp gaps, untimed frames, per camera) as
// the table and the timeline show them, and each camera's timestamps against the others' (the
// plot). The check reads the experiment through a sequence of its own, so that it can run on a
// worker while the labeling room's frame cache reads the same files.
//
//   RecordingPresenter recording("shot/experiment.yaml");           // InputError names the file
//   recording.SetReport(RecordingPresenter::Check(recording.sequence(), false, cancel));
//   recording.Findings();    // one row per camera and kind of finding
//   recording.Offsets();     // per camera: (frame, ms from the cameras' mean time of that frame)

#include <Eigen/Core>
#include <QString>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "libreconstruct/recording/sequence.h"

namespace netlab::gui {

// One row of the findings table: a camera's frames of one kind.
struct RecordingFinding {
  int camera = 0;
  std::string camera_name;
  std::string kind;         // "missing", "unreadable", "duplicated", "timestamp gap", "untimed"
  std::vector<int> frames;  // the recording's frame numbers, ascending
  std::string detail;       // what the kind means, or the first unreadable frame's reason
};

// One camera's timestamps against the others': at each frame every camera has a time for, its
// time minus the mean of the cameras' times (ms).
struct TimestampSeries {
  std::string camera;
  std::vector<Eigen::Vector2d> points;  // (frame number, offset in ms)
};

class RecordingPresenter {
 public:
  // Opens the experiment's streams (InputError naming the file or camera when it cannot).
  explicit RecordingPresenter(const std::string& experiment_path);

  const std::string& experiment_path() const { return experiment_path_; }
  const recon::SynchronizedSequence& sequence() const { return *sequence_; }

  // `netlab ingest --check` (decode: --decode) on `sequence`: any thread, reporting from it.
  static recon::CheckReport Check(const recon::SynchronizedSequence& sequence, bool decode,
                                  const ProgressReporter& progress = {});

  // The check's answer (GUI thread), and whether there is one.
  void SetReport(recon::CheckReport report) { report_ = std::move(report); }
  const std::optional<recon::CheckReport>& report() const { return report_; }

  // The table's rows, camera by camera, kinds in the order above; empty before a report or when
  // the recording is whole.
  std::vector<RecordingFinding> Findings() const;
  // Frame numbers with any finding (the timeline's marks).
  std::set<int> MarkedFrames() const;
  // The line above the table: frames, cameras, synchronized frames, findings, the check's time.
  QString Summary() const;
  // "1203, 1204, 1210 … (12 frames)": at most `shown` numbers, then the count.
  static QString FrameList(const std::vector<int>& frames, int shown = 6);
  // Each camera's timestamp offsets (cameras without timestamps are left out; empty when fewer
  // than two cameras have them).
  std::vector<TimestampSeries> Offsets() const;

 private:
  std::string experiment_path_;
  std::unique_ptr<recon::SynchronizedSequence> sequence_;
  std::optional<recon::CheckReport> report_;
};

}  // namespace netlab::gui
