#pragma once
// The experiment file: which recordings make up one shot (YAML; the keys are a contract).
//
//   experiment: net_a_case1
//   fps: 179
//   cameras:
//     - name: cam0
//       frames: cam0/frame_%06d.pgm     # printf pattern, a video file, or file.h5:/cam0
//       bayer: RGGB                      # RGGB | BGGR | GRBG | GBRG | none
//       timestamps: cam0/timestamps.csv  # optional: frame_index,time_s
//       bit_depth: 8                     # 8, 10, 12 or 16; optional (default: the files' depth)
//       black_level: 0                   # optional, raw units
//       white_balance: [1.0, 1.0, 1.0]   # optional, gains for R, G, B
// Paths are relative to the experiment file.

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "libreconstruct/recording/bayer.h"

namespace netlab::recon {

struct CameraSpec {
  std::string name;
  std::string frames;  // as written in the file
  BayerPattern bayer = BayerPattern::kNone;
  std::string timestamps;  // resolved path, or ""
  std::optional<int> bit_depth;
  double black_level = 0.0;
  std::string black_level_where;  // "file:line: cameras[i].black_level" when given
  std::array<double, 3> white_balance_rgb = {1.0, 1.0, 1.0};
};

struct Experiment {
  std::string name;
  double fps = 0.0;
  std::vector<CameraSpec> cameras;
  std::string path;      // the experiment file
  std::string base_dir;  // its folder: frame specs resolve against it

  int Find(const std::string& camera) const;  // index, or -1
};

// Why `black_level` (raw units) does not fit data of `bit_depth` bits, or "" when it does: it
// must be below the white level 2^bit_depth - 1. Checked against bit_depth when the file gives
// it, else against the frames' depth when the recording is opened (SynchronizedSequence).
std::string BlackLevelProblem(double black_level, int bit_depth);

// Reads and checks an experiment file; InputError with file, line and key on bad input.
Experiment LoadExperiment(const std::string& path);
Experiment ParseExperiment(const std::string& text, const std::string& origin,
                           const std::string& base_dir);
// Writes an experiment file (via "<path>.partial" and a rename). Frame specs are written as they
// are; timestamp paths (resolved) relative to the new file's folder when inside it, else absolute.
void WriteExperiment(const std::string& path, const Experiment& experiment);

// A timestamps file: frame_index,time_s per line (header and # comments allowed). InputError
// naming the line on bad input.
std::map<int, double> ReadTimestamps(const std::string& path);

}  // namespace netlab::recon
