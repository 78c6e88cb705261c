#pragma once
// The synchronized sequence: frame k of every camera together, addressed by frame index (the
// trigger count). A camera that lacks frame k has a gap there; the other cameras' frames never
// shift. Gaps are found from index gaps, timestamp steps that disagree with the frame rate
// (a dropped or duplicated frame), identical consecutive frames, and unreadable files.

#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/progress.h"
#include "libreconstruct/recording/experiment.h"
#include "libreconstruct/recording/frame_source.h"

namespace netlab::recon {

struct CameraReport {
  std::string name;
  int frames = 0;                     // frames present
  int width = 0, height = 0;          // of its first readable frame
  int depth_bits = 0;                 // container depth, 8 or 16
  std::vector<int> missing;           // indices in the sequence's range without a frame
  std::vector<int> unreadable;        // present but unreadable (truncated, corrupt, wrong size)
  std::vector<int> duplicated;        // same timestamp as, or identical to, the previous frame
  std::vector<int> timestamp_gaps;    // indices after which the timestamps skip frames
  std::vector<int> untimed;           // present, but without a time where the camera has times
  std::vector<std::string> problems;  // one line per unreadable frame: where and why
};

struct CheckReport {
  std::vector<CameraReport> cameras;
  int first_frame = 0, last_frame = -1;
  int synchronized_frames = 0;  // frames every camera has readable
  int frames_read = 0;
  double wall_s = 0.0;
  double read_fps = 0.0;  // frames (per camera) read (and decoded) per second
  bool decoded = false;
  std::vector<std::string> warnings;  // different sizes or counts across cameras, untimed frames
  std::string BriefReport() const;
};

class SynchronizedSequence {
 public:
  // Opens every camera's source; InputError naming the camera on a missing file or pattern.
  explicit SynchronizedSequence(Experiment experiment);

  const Experiment& experiment() const { return experiment_; }
  int num_cameras() const { return static_cast<int>(sources_.size()); }
  const FrameSource& source(int camera) const { return *sources_[camera]; }
  // The frame range: the union of every camera's indices.
  int first_frame() const { return first_; }
  int last_frame() const { return last_; }
  bool Has(int camera, int frame) const;

  // The raw frame (mosaic), or empty with the reason.
  cv::Mat ReadRaw(int camera, int frame, std::string* error) const;
  // An 8-bit BGR image for display at 1/2^level resolution (level 0 full, 1 half by binning
  // the Bayer blocks, 2 quarter, ...), or empty with the reason.
  cv::Mat ReadDisplay(int camera, int frame, int level, std::string* error) const;
  ColorCorrection Correction(int camera) const { return corrections_[camera]; }

  // Reads every frame header (decode: every frame, demosaiced) and reports gaps and problems.
  // Progress: stage "frames decoded" (or "frame headers read"; of all cameras), from any of the
  // threads (one at a time); a cancel stops them between frames and throws Cancelled. Decoding
  // runs on `threads` threads.
  CheckReport Check(bool decode, const ProgressReporter& progress = {}, int threads = 2) const;

 private:
  Experiment experiment_;
  std::vector<std::unique_ptr<FrameSource>> sources_;
  std::vector<std::map<int, double>> timestamps_;
  std::vector<ColorCorrection> corrections_;
  int first_ = 0, last_ = -1;
};

}  // namespace netlab::recon
