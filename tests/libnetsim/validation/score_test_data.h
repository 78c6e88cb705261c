#pragma once
// A small scored shot for the file and report tests: a 6 x 6 net flying and opening, measured
// with 1 mm noise, one corner missing for a while, scored with a time fit.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "common/hdf5_util.h"
#include "libnetsim/validation/score.h"

namespace netlab::netsim::testing {

// Every value of a float64 dataset of a score file, flattened.
inline std::vector<double> ReadDoubles(hid_t file, const std::string& name) {
  const auto dims = h5::DatasetDims(file, name);
  size_t n = 1;
  for (hsize_t d : dims) n *= d;
  std::vector<double> v(n);
  h5::ReadDataset(file, name, H5T_NATIVE_DOUBLE, v.data());
  return v;
}

inline KnotTracks SmallFlight(int frames, double t0, double noise_m, std::mt19937* rng) {
  KnotTracks tracks;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) tracks.grid.push_back({r, c});
  std::normal_distribution<double> normal(0.0, noise_m);
  for (int i = 0; i < frames; ++i) {
    const double t = t0 + i / 179.0;
    tracks.time.push_back(i / 179.0);
    const double open = 0.6 + 1.5 * t - 1.2 * t * t;  // opens, then closes after 0.6 s
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) {
        Eigen::Vector3d p(0.5 * t + 0.01 * std::sin(6 * t + r + c), (c - 2.5) * 0.2 * open,
                          (r - 2.5) * 0.2 * open);
        if (rng) p += Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
        tracks.position.push_back(p);
        // Corner (5,5) hidden in frames 20..39: masked.
        tracks.valid.push_back(!(rng && r == 5 && c == 5 && i >= 20 && i < 40));
        if (rng) tracks.covariance.push_back(Eigen::Matrix3d::Identity() * noise_m * noise_m);
      }
  }
  return tracks;
}

inline ScoreResult SmallScore() {
  std::mt19937 rng(17);
  const KnotTracks measured = SmallFlight(200, 0.004, 1e-3, &rng);
  const KnotTracks sim = SmallFlight(220, 0.0, 0.0, nullptr);
  ScoreOptions options;
  options.contact_time_s = 0.9;
  return Score(measured, sim, options);
}

// A scratch folder per process and test.
inline std::filesystem::path ScratchDir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (tag + "_" + std::to_string(getpid()) + "_" +
                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace netlab::netsim::testing
