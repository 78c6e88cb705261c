// Knot identification benchmark: how often IdentifyKnot names the right knot, flags it, or
// (never acceptable) names a wrong one, against image noise and a colour shift.
//
//   bench_identify [--nets N]        (IDENT_DEBUG=1: print the reasons of any wrong identity)
//
// The scene: N (default 12) flat 4 x 4-knot nets (25 cm mesh, 1 mm thread, bare crossings, each
// link one of 6 colours chosen by ChoosePalette from DefaultYarnCandidates against a dark
// background, codes unique under the set rule), 1.5 m in front of cam0 of PaperRig(0.5)
// (1024 px, threads ~1 px wide), each net turned by a different angle about the optical axis
// (net i: 7.5 i degrees, so some run along the pixel rows and lose a colour channel to the
// Bayer mosaic). Rendered with RenderScene, Expose (RGGB, 8 bit, read noise sigma), Demosaic;
// every knot identified from its true pixel and true yarn directions with default options and
// the true codebook (16 knots). "Colour shift": the light multiplied by white-balance gains
// B 1.3, G 1.0, R 0.7 before the sensor while the codebook keeps the unshifted colours.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/recording/bayer.h"
#include "libreconstruct/twin/coloured_net.h"
#include "libreconstruct/twin/render.h"

namespace netlab::recon {
namespace {

struct Row {
  int correct = 0, wrong = 0, ambiguous = 0, unknown = 0;
  double ms = 0;
  int total() const { return correct + wrong + ambiguous + unknown; }
};

int Main(int argc, char** argv) {
  int nets = 12;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--nets") == 0 && i + 1 < argc) nets = std::atoi(argv[++i]);
  }
  const calib::Camera camera = calib::PaperRig(0.5).cameras[0];
  const Colour background(0.02f, 0.02f, 0.02f);
  const std::vector<Candidate> candidates = DefaultYarnCandidates();
  Lighting lighting;
  lighting.background = background;
  double min_de = 0;
  std::vector<PaletteColour> palette;
  for (int i : ChoosePalette(candidates, 6, lighting, &min_de)) {
    palette.push_back({candidates[i].name, lighting.Seen(candidates[i].srgb)});
  }
  std::printf("palette (min dE00 %.1f incl. background):", min_de);
  for (const PaletteColour& p : palette) std::printf(" %s", p.name.c_str());
  std::printf("\n\n");

  std::vector<ColouredNet> scenes;
  std::vector<cv::Mat> renders;
  for (int n = 0; n < nets; ++n) {
    scenes.push_back(MakeColouredNet(camera, 4, 0.25, 1.5, 7.5 * n * M_PI / 180.0, 0.0005, palette,
                                     background, 100 + n));
    renders.push_back(RenderScene(camera, scenes.back().scene, SceneRenderOptions{}));
  }

  std::printf(
      "| noise sigma | colour shift | knots | identified correct | identified wrong | "
      "ambiguous | unknown | ms / knot |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (bool shift : {false, true}) {
    for (double sigma : {0.0, 2.0, 4.0, 8.0, 16.0}) {
      Row row;
      for (int n = 0; n < nets; ++n) {
        // A new image: assigning the product to a Mat sharing renders[n] would scale it in place.
        const cv::Mat linear =
            shift ? cv::Mat(renders[n].mul(cv::Scalar(1.3, 1.0, 0.7))) : renders[n];
        SensorOptions sensor;
        sensor.noise_sigma = sigma;
        sensor.seed = 1 + n;
        const cv::Mat frame = Demosaic(Expose(linear, camera.intrinsics, sensor),
                                       BayerPattern::kRGGB, ColorCorrection{});
        for (const KnotView& view : VisibleKnots(camera, scenes[n], 20)) {
          const auto start = std::chrono::steady_clock::now();
          const KnotIdentification id = IdentifyKnot(frame, view.pixel, view.directions,
                                                     IdentifyOptions{}, scenes[n].codebook);
          row.ms +=
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                  .count();
          switch (id.status) {
            case IdentifyStatus::kIdentified:
              (id.knots.size() == 1 && id.knots[0] == view.knot ? row.correct : row.wrong)++;
              if (std::getenv("IDENT_DEBUG") && id.knots[0] != view.knot) {
                std::printf("net %d knot %d true", n, view.knot);
                for (int c : scenes[n].codebook.knots[view.knot].link_colours) {
                  std::printf(" %s", palette[c].name.c_str());
                }
                for (const std::string& r : id.reasons) std::printf("; %s", r.c_str());
                std::printf("\n");
              }
              break;
            case IdentifyStatus::kAmbiguous: ++row.ambiguous; break;
            case IdentifyStatus::kUnknown: ++row.unknown; break;
          }
        }
      }
      const double t = row.total();
      std::printf("| %.0f | %s | %d | %d (%.0f%%) | %d | %d (%.0f%%) | %d (%.0f%%) | %.3f |\n",
                  sigma, shift ? "B1.3 G1.0 R0.7" : "none", row.total(), row.correct,
                  100 * row.correct / t, row.wrong, row.ambiguous, 100 * row.ambiguous / t,
                  row.unknown, 100 * row.unknown / t, row.ms / t);
    }
  }
  return 0;
}

}  // namespace
}  // namespace netlab::recon

int main(int argc, char** argv) { return netlab::recon::Main(argc, argv); }
