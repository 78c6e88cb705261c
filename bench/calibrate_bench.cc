// Calibration benchmark.
//
//   bench_calibrate [--views N] [--trials N] [--skip-images]
//
// A. Accuracy against noise: the paper's four-camera rig (2048 x 2048) and a double-sided
//    chessboard foil between the pairs at N views (default 40); the true corner projections with
//    Gaussian noise sigma = 0.1 ... 1 px per axis are calibrated (intrinsics estimated). Reported
//    next to what the noise allows: the residual RMS a perfect fit leaves (sigma sqrt(2) sqrt(1 -
//    p / 2n), n points, p parameters) and the camera-centre sigma predicted by the solver's
//    covariance, against the measured camera-centre, rotation and focal-length errors.
// B. Wall time of the whole pipeline on images: render, detect (2 threads), calibrate, for
//    4 cameras x N views at 2048 x 2048.

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <thread>

#include "calibration/calibrate.h"
#include "calibration/detect.h"
#include "calibration/synthetic.h"

namespace netlab::calib {
namespace {

Eigen::Quaterniond FacingPlusX() {
  Eigen::Matrix3d r;
  r << Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(1, 0, 0);
  return Eigen::Quaterniond(r);
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace
}  // namespace netlab::calib

int main(int argc, char** argv) {
  using namespace netlab::calib;
  int views = 40, trials = 3;
  bool images = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--views") && i + 1 < argc) views = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--trials") && i + 1 < argc) trials = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--skip-images")) images = false;
  }
  const Rig truth = PaperRig(1.0);
  const CalibrationTarget foil =
      CalibrationTarget::Foil(BoardPattern::Chessboard(9, 6, 0.06), 0.0005);
  std::mt19937 pose_rng(5);
  const auto poses =
      RandomTargetPoses(truth, foil, {0, 1, 2, 3}, views, Eigen::Vector3d(1.25, 0.0, 0.1),
                        Eigen::Vector3d(0.35, 0.35, 0.3), FacingPlusX(), 0.6, pose_rng);

  std::printf(
      "A. accuracy against corner noise: 4 cameras x %d views of a 9x6 chessboard foil, "
      "%d trials each\n\n",
      views, trials);
  std::printf(
      "| sigma (px) | RMS (px) | RMS a perfect fit leaves (px) | centre error (mm) | "
      "predicted centre sigma (mm) | rotation error (deg) | fx error (px) | solve (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (double sigma : {0.1, 0.25, 0.5, 1.0}) {
    double rms = 0, allowed = 0, centre = 0, predicted = 0, rotation = 0, fx = 0, solve = 0;
    for (int trial = 0; trial < trials; ++trial) {
      std::mt19937 rng(100 * trial + static_cast<int>(sigma * 1000));
      std::normal_distribution<double> noise(0.0, sigma);
      CalibrationInput input;
      input.num_frames = views;
      for (size_t c = 0; c < truth.cameras.size(); ++c) {
        input.camera_names.push_back(truth.cameras[c].name);
        input.image_sizes.emplace_back(2048, 2048);
        for (int f = 0; f < views; ++f)
          for (const FaceProjection& fp : ProjectTarget(truth.cameras[c], foil, poses[f])) {
            Observation o;
            o.camera = static_cast<int>(c);
            o.frame = f;
            o.ids = fp.ids;
            for (const Eigen::Vector2d& p : fp.pixels)
              o.pixels.push_back(p + Eigen::Vector2d(noise(rng), noise(rng)));
            input.observations.push_back(o);
          }
      }
      const auto start = std::chrono::steady_clock::now();
      const CalibrationResult result = CalibrateRig(foil, input, CalibrationOptions{});
      solve += Seconds(start) / trials;
      // Truth in the estimate's world frame (the foil in the reference camera's first frame).
      const int reference_frame = [&] {
        for (int f = 0; f < views; ++f)
          if (result.frame_seen[f]) return f;
        return 0;
      }();
      const Rigid3d world_true_from_world_est = poses[reference_frame];
      const int n = result.summary.observations;
      const int p = 4 * 14 + 6 * (views - 1);  // 6 pose + 8 intrinsics per camera, 6 per free frame
      rms += result.summary.rms_px / trials;
      allowed +=
          sigma * std::sqrt(2.0) * std::sqrt(1.0 - static_cast<double>(p) / (2.0 * n)) / trials;
      for (size_t c = 0; c < truth.cameras.size(); ++c) {
        const Rigid3d true_cam = truth.cameras[c].cam_from_world * world_true_from_world_est;
        const Camera& e = result.rig.cameras[c];
        centre += 1e3 * (e.Center() - true_cam.Inverse().translation).norm() / (4.0 * trials);
        predicted += 1e3 * result.summary.cameras[c].position_sigma_m / (4.0 * trials);
        rotation += e.cam_from_world.rotation.angularDistance(true_cam.rotation) * 180.0 / M_PI /
                    (4.0 * trials);
        fx += std::abs(e.intrinsics.fx - truth.cameras[c].intrinsics.fx) / (4.0 * trials);
      }
    }
    std::printf("| %.2f | %.3f | %.3f | %.2f | %.2f | %.4f | %.2f | %.2f |\n", sigma, rms, allowed,
                centre, predicted, rotation, fx, solve);
    std::fflush(stdout);
  }

  if (!images) return 0;
  std::printf(
      "\nB. the pipeline on images: 4 cameras x %d views at 2048 x 2048 (noise 2 grey "
      "levels)\n\n",
      views);
  auto start = std::chrono::steady_clock::now();
  const auto prints = MakeTargetPrints(foil);
  std::vector<CameraRays> rays;
  for (const Camera& c : truth.cameras) rays.emplace_back(c.intrinsics);
  const double ray_s = Seconds(start);
  start = std::chrono::steady_clock::now();
  std::vector<std::vector<cv::Mat>> rendered(4);
  for (int c = 0; c < 4; ++c)
    for (int f = 0; f < views; ++f) {
      RenderOptions options;
      options.noise_sigma = 2.0;
      options.seed = 1000 * c + f;
      rendered[c].push_back(RenderTarget(truth.cameras[c], rays[c], prints, poses[f], options));
    }
  const double render_s = Seconds(start);
  start = std::chrono::steady_clock::now();
  CalibrationInput input;
  input.num_frames = views;
  std::vector<std::vector<PatternDetection>> found(4, std::vector<PatternDetection>(views));
  std::vector<std::thread> pool;
  std::atomic<int> next{0};
  auto work = [&] {
    for (int task; (task = next++) < 4 * views;)
      found[task / views][task % views] =
          DetectPattern(rendered[task / views][task % views], foil.faces[0].pattern);
  };
  pool.emplace_back(work);
  work();
  pool[0].join();
  for (int c = 0; c < 4; ++c) {
    input.camera_names.push_back(truth.cameras[c].name);
    input.image_sizes.emplace_back(2048, 2048);
    for (int f = 0; f < views; ++f) {
      if (!found[c][f].empty()) input.observations.push_back(MakeObservation(c, f, found[c][f]));
    }
  }
  const double detect_s = Seconds(start);
  start = std::chrono::steady_clock::now();
  const CalibrationResult result = CalibrateRig(foil, input, CalibrationOptions{});
  const double solve_s = Seconds(start);
  double centre = 0.0;
  const Rigid3d world_true_from_world_est = poses[0];
  for (size_t c = 0; c < 4; ++c) {
    const Rigid3d true_cam = truth.cameras[c].cam_from_world * world_true_from_world_est;
    centre =
        std::max(centre, (result.rig.cameras[c].Center() - true_cam.Inverse().translation).norm());
  }
  std::printf("| stage | wall (s) | per image (ms) |\n|---|---|---|\n");
  std::printf("| undistortion rays (4 cameras) | %.2f | |\n", ray_s);
  std::printf("| render %d images | %.2f | %.0f |\n", 4 * views, render_s,
              1e3 * render_s / (4 * views));
  std::printf("| detect (2 threads) | %.2f | %.0f |\n", detect_s, 1e3 * detect_s / (4 * views));
  std::printf("| calibrate (%d points) | %.2f | |\n", result.summary.observations, solve_s);
  std::printf(
      "\ndetected %zu of %d views; RMS %.3f px; worst camera-centre error %.2f mm; "
      "metric check cam0-cam1 %.3f mm RMS, cam2-cam3 %.3f mm RMS\n",
      input.observations.size(), 4 * views, result.summary.rms_px, 1e3 * centre,
      result.summary.pairs.front().rms_error_mm, result.summary.pairs.back().rms_error_mm);
  return 0;
}
