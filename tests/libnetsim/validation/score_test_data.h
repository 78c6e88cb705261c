#pragma once
// A small scored shot for the file and report tests: a 6 x 6 net flying and opening, measured
// with 1 mm noise, one corner missing for a while, scored with a time fit. And a right and a
// wrong model made by the simulator: a 5 x 5 net flown with air drag and without it.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "common/hdf5_util.h"
#include "libnetsim/scenario/run_scenario.h"
#include "libnetsim/scenario/scenario.h"
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

// A 5 x 5 net with air drag, flying 0.6 s: the simulator's "real" net of the wrong-model tests.
inline constexpr char kDragScene[] = R"(
name: small_net
duration: 0.6
output_interval: 0.005586592178770949
integrator: {type: explicit, dt: auto}
drag: {air_density: 1.0, drag_coefficient: 1.2}
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          stretch_damping: 7.6e-4, bend_stiffness: 9.82e-5, bend_damping: 6.0e-9,
          twist_stiffness: 7.07e-5, twist_damping: 5.7e-11}
nets:
  - {name: net, material: nylon, knots: [5, 5], mesh: 0.1, segments_per_link: 2,
     center: [0, 0, 0], normal: [1, 0, 0], x_axis: [0, 1, 0], knot_mass: 3e-05,
     corner_mass: 0.02, velocity: [0.8, 0, 0],
     corner_velocities: [[0.05, -0.05, -0.05], [0.05, 0.05, -0.05], [0.05, -0.05, 0.05],
                         [0.05, 0.05, 0.05]]}
)";

// kDragScene simulated as it is (right) and without its air drag (wrong), in a scratch folder
// removed afterwards.
struct DragModels {
  KnotTracks right, wrong;
};
inline DragModels SimulateDragModels() {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("netlab_drag_models_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  auto run = [&](const std::string& text, const std::string& name) {
    RunOptions run_options;
    run_options.out_path = (dir / name).string();
    EXPECT_TRUE(RunScenario(ParseScenario(text, name, dir.string()), run_options).stable);
    return ReadKnotTracks(run_options.out_path);
  };
  std::string no_drag = kDragScene;
  no_drag.erase(no_drag.find("drag: {"), no_drag.find("materials:") - no_drag.find("drag: {"));
  DragModels models{run(kDragScene, "right.h5"), run(no_drag, "wrong.h5")};
  std::filesystem::remove_all(dir);
  return models;
}

}  // namespace netlab::netsim::testing
