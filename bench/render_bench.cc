// Renderer benchmark: what one camera-frame of the synthetic experiment costs.
//
//   bench_render [--runs N]
//
// The scene: a flat 11 x 11-knot net (10 cm mesh, 220 links of 4 segments, 1 mm thread, knots
// as 2.5 mm (diameter) balls, four 1 cm corner balls) bent into a mild cup (its centre 8 cm
// behind its edges), ~1 m from the ejector, and the target box (0.4 x 0.3 x 0.3 m at x = 2.2 m),
// on a dark background, seen by the paper's rig at full (2048 px) and quarter (512 px) scale.
// Measured per camera-frame, best of N runs (default 3), one thread:
// - render, 1 sample: zero the accumulator, one RenderScene;
// - render, 4 samples: zero it, four RenderScene of the net 2.5 mm apart (motion blur);
// - Expose at 8 and 12 bits (RGGB, read noise 2 grey levels, vignetting 0.5).
// The first render of each camera (building its ray grid and the scratch canvas) is shown apart.
// Then the flight effects (libreconstruct/twin/flight_effects.h), one sample, mean over the
// cameras: point lamps (PaperLamps, shadow rays against the box), the textile background, the
// depth map with ApplyDepthOfField (f/4 at 3 m), Expose with a camera response (gain, white
// balance, gamma, PRNU, DSNU, hot pixels).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/twin/flight_effects.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {
namespace {

double Ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

// The net at `shift` m along the flight axis (x), and the target box.
Scene BenchScene(double shift) {
  constexpr int kKnots = 11, kSegments = 4;
  constexpr double kMesh = 0.1, kCup = 0.08;
  const double half = 0.5 * kMesh * (kKnots - 1);
  // The cup: x = 1 - kCup (1 - rho^2 / rho_max^2) along the flight axis, y and z across it.
  auto at = [&](double y, double z) {
    return Eigen::Vector3d(1.0 + shift - kCup * (1.0 - (y * y + z * z) / (2.0 * half * half)), y,
                           z);
  };
  auto knot = [&](int i, int j) { return Eigen::Vector2d((i - 5) * kMesh, (j - 5) * kMesh); };
  Scene scene;
  scene.background = {0.04f, 0.04f, 0.05f};
  for (int i = 0; i < kKnots; ++i)
    for (int j = 0; j < kKnots; ++j) {
      const Eigen::Vector2d k = knot(i, j);
      scene.balls.push_back({at(k.x(), k.y()), 0.00125, {0.85f, 0.85f, 0.85f}});
      for (int direction = 0; direction < 2; ++direction) {
        const int i2 = i + (direction == 0), j2 = j + (direction == 1);
        if (i2 >= kKnots || j2 >= kKnots) continue;
        const Eigen::Vector2d k2 = knot(i2, j2);
        ThreadPolyline link;
        link.radius = 0.0005;
        link.colour = direction == 0 ? Colour(0.1f, 0.7f, 0.9f) : Colour(0.8f, 0.5f, 0.2f);
        for (int s = 0; s <= kSegments; ++s) {
          const Eigen::Vector2d p = k + (k2 - k) * (double(s) / kSegments);
          link.points.push_back(at(p.x(), p.y()));
        }
        scene.threads.push_back(std::move(link));
      }
    }
  for (int corner = 0; corner < 4; ++corner) {
    const double y = (corner & 1 ? 1 : -1) * (half + 0.02),
                 z = (corner & 2 ? 1 : -1) * (half + 0.02);
    scene.balls.push_back({at(y, z), 0.005, {0.2f, 0.2f, 0.8f}});
  }
  Box box;
  box.center = {2.2, 0.0, 0.0};
  box.half_extents = {0.2, 0.15, 0.15};
  box.orientation = Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitZ());
  box.colour = {0.55f, 0.6f, 0.6f};
  scene.boxes.push_back(box);
  return scene;
}

struct Row {
  std::string camera;
  double first = 0.0, render1 = 1e30, render4 = 1e30, expose8 = 1e30, expose12 = 1e30;
};

}  // namespace
}  // namespace netlab::recon

int main(int argc, char** argv) {
  using namespace netlab;
  using namespace netlab::recon;
  int runs = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: bench_render [--runs N]\n");
      return 2;
    }
  }
  Scene blur[4];
  for (int k = 0; k < 4; ++k) blur[k] = BenchScene(0.0025 * k);
  const Scene& scene = blur[0];
  const SceneRenderOptions options;
  std::printf("Scene: %zu thread polylines, %zu balls, %zu box; best of %d runs, one thread.\n",
              scene.threads.size(), scene.balls.size(), scene.boxes.size(), runs);

  for (double scale : {1.0, 0.25}) {
    const calib::Rig rig = calib::PaperRig(scale);
    std::vector<Row> rows;
    double checksum = 0.0;
    for (const calib::Camera& camera : rig.cameras) {
      Row row;
      row.camera = camera.name;
      cv::Mat accumulator;
      auto start = std::chrono::steady_clock::now();
      RenderScene(camera, scene, options, 1.0f, &accumulator);
      row.first = Ms(start);
      SensorOptions sensor;
      sensor.noise_sigma = 2.0;
      sensor.vignetting = 0.5;
      for (int run = 0; run < runs; ++run) {
        start = std::chrono::steady_clock::now();
        accumulator.setTo(cv::Scalar::all(0));
        RenderScene(camera, scene, options, 1.0f, &accumulator);
        row.render1 = std::min(row.render1, Ms(start));

        start = std::chrono::steady_clock::now();
        accumulator.setTo(cv::Scalar::all(0));
        for (const Scene& sub_frame : blur)
          RenderScene(camera, sub_frame, options, 0.25f, &accumulator);
        row.render4 = std::min(row.render4, Ms(start));

        sensor.seed = 1000 + run;
        sensor.bit_depth = 8;
        start = std::chrono::steady_clock::now();
        const cv::Mat raw8 = Expose(accumulator, camera.intrinsics, sensor);
        row.expose8 = std::min(row.expose8, Ms(start));
        sensor.bit_depth = 12;
        start = std::chrono::steady_clock::now();
        const cv::Mat raw12 = Expose(accumulator, camera.intrinsics, sensor);
        row.expose12 = std::min(row.expose12, Ms(start));
        checksum += cv::sum(raw8)[0] + cv::sum(raw12)[0];
      }
      rows.push_back(row);
    }
    const int pixels = rig.cameras[0].intrinsics.width;
    std::printf("\nPaperRig(%.2f): %d x %d px, ms per camera-frame\n\n", scale, pixels, pixels);
    std::printf(
        "| camera | render, 1 sample | render, 4 samples | Expose 8-bit | Expose 12-bit "
        "| first render (cold) |\n|---|---|---|---|---|---|\n");
    Row mean;
    mean.camera = "mean";
    mean.render1 = mean.render4 = mean.expose8 = mean.expose12 = 0.0;
    for (const Row& r : rows) {
      std::printf("| %s | %.1f | %.1f | %.1f | %.1f | %.1f |\n", r.camera.c_str(), r.render1,
                  r.render4, r.expose8, r.expose12, r.first);
      mean.render1 += r.render1 / rows.size();
      mean.render4 += r.render4 / rows.size();
      mean.expose8 += r.expose8 / rows.size();
      mean.expose12 += r.expose12 / rows.size();
      mean.first += r.first / rows.size();
    }
    std::printf("| **mean** | %.1f | %.1f | %.1f | %.1f | %.1f |\n", mean.render1, mean.render4,
                mean.expose8, mean.expose12, mean.first);
    std::printf("(checksum %.0f)\n", checksum);

    // The flight effects, mean ms per camera-frame over the cameras.
    double lamps = 0, textile = 0, dof = 0, response = 0, plain = 0;
    SceneRenderOptions lit = options;
    const LampRig paper = PaperLamps(rig, Eigen::Vector3d(1.0, 0.0, 0.0));
    lit.lamps = paper.lamps;
    lit.ambient = paper.ambient;
    lit.glossy = paper.glossy;
    DepthOfField lens{4.0, 3.0, 5.5e-6 / scale};
    SensorOptions responding;
    responding.noise_sigma = 2.0;
    responding.vignetting = 0.5;
    responding.response = DrawCameraResponses(1, 0.1, 1)[0];
    for (const calib::Camera& camera : rig.cameras) {
      const cv::Mat panel = TextileBackground(camera.intrinsics, 0.1, true, 1);
      SceneRenderOptions on_textile = options;
      on_textile.background_image = &panel;
      double best[5] = {1e30, 1e30, 1e30, 1e30, 1e30};
      for (int run = 0; run < runs; ++run) {
        cv::Mat accumulator, depth;
        auto start = std::chrono::steady_clock::now();
        RenderScene(camera, scene, options, 1.0f, &accumulator);
        best[0] = std::min(best[0], Ms(start));
        accumulator.release();
        start = std::chrono::steady_clock::now();
        RenderScene(camera, scene, lit, 1.0f, &accumulator);
        best[1] = std::min(best[1], Ms(start));
        accumulator.release();
        start = std::chrono::steady_clock::now();
        RenderScene(camera, scene, on_textile, 1.0f, &accumulator);
        best[2] = std::min(best[2], Ms(start));
        accumulator.release();
        start = std::chrono::steady_clock::now();
        RenderScene(camera, scene, options, 1.0f, &accumulator, &depth);
        const cv::Mat blurred = ApplyDepthOfField(accumulator, depth, camera.intrinsics.fx, lens);
        best[3] = std::min(best[3], Ms(start));
        start = std::chrono::steady_clock::now();
        const cv::Mat raw = Expose(blurred, camera.intrinsics, responding);
        best[4] = std::min(best[4], Ms(start));
        checksum += cv::sum(raw)[0];
      }
      plain += best[0] / rig.cameras.size();
      lamps += best[1] / rig.cameras.size();
      textile += best[2] / rig.cameras.size();
      dof += best[3] / rig.cameras.size();
      response += best[4] / rig.cameras.size();
    }
    std::printf("\nFlight effects, PaperRig(%.2f), mean ms per camera-frame (one sample)\n\n",
                scale);
    std::printf(
        "| render | + paper lamps | + textile background | + depth map and f/4 blur "
        "| Expose 8-bit with a camera response |\n|---|---|---|---|---|\n");
    std::printf("| %.1f | %.1f | %.1f | %.1f | %.1f |\n", plain, lamps, textile, dof, response);
  }
  return 0;
}
