#pragma once
// The HDF5 frame store: a recording converted into one file, one chunked dataset per camera, for
// fast random access (a frame is one chunk) and, optionally, compression.
//
// Layout of OUT.h5:
//   /<camera>             [T, H, W] uint8 | uint16 (or [T, H, W, 3]), chunks [1, H, W];
//                         attributes bayer, bit_depth, first_index, fps
//   /<camera>_valid       [T] uint8: 1 where the source had a readable frame (else zeros stored)
//   /<camera>_timestamps  [T] float64, s (NaN where unknown)
// Frame index first_index + t is stored at t, for every camera the same range, so the cameras stay
// synchronized through gaps.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "libreconstruct/recording/sequence.h"

namespace netlab::recon {

struct FrameStoreOptions {
  int deflate_level = 0;  // 0: none; 1..9: gzip (smaller, slower)
};

// The experiment file that reads the store at `path`, written beside it: "shot/store.h5" ->
// "shot/store.yaml" (a name without ".h5" gets ".yaml" appended).
std::string FrameStoreExperimentPath(const std::string& path);

// The files a recording is read from, named for a message ("cam0 frames", "cam0
// timestamps"): every video or frame store and timestamps file (an image pattern names many files
// and none of them can be an output of netlab's, so it is left out).
std::vector<std::pair<std::string, std::string>> RecordingFiles(const Experiment& experiment);

// Converts `sequence` into the store at `path` (via "<path>.partial" and a rename) and returns the
// experiment that reads it (frames "<file name>:/<camera>"). Progress: stage "frames converted"
// (of all cameras), on the calling thread; polled between frames, a cancel throws Cancelled
// and leaves no "<path>.partial".
Experiment ConvertToFrameStore(const SynchronizedSequence& sequence, const std::string& path,
                               const FrameStoreOptions& options,
                               const ProgressReporter& progress = {});

}  // namespace netlab::recon
