// bench_error_budget: the loop's error budget on the digital twin. The render's true pixels of a
// shot, with Gaussian pixel noise of each level added (and stated), are triangulated through the
// rig and scored against the simulation that made the shot: how pixel noise becomes 3D error,
// whether the triangulation's covariance tells that error, and what the score then says. With
// --labels, the same for a labeling (e.g. netlab label's, from the corners) at its stated noise.
// Prints a table; never fails on time.
//
//   build/bench/bench_error_budget --shot DIR --sim sim.h5 [--rig rig.yaml] [--fps 179]
//                                  [--labels labels.h5 --labels-sigma 0.09]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "common/tracks/track_file.h"
#include "libnetsim/validation/score.h"
#include "libreconstruct/geometry/bundle_adjust.h"
#include "libreconstruct/geometry/track_export.h"
#include "libreconstruct/labels/label_set.h"

namespace {

using namespace netlab;

struct Row {
  std::string what;
  double stated_px = 0;
  recon::TruthComparison truth;
  double predicted_rms_m = 0;  // sqrt(mean trace of the covariances)
  netsim::ScoreSummary score;
  double seconds = 0;
};

// The labels with Gaussian noise of sd `sigma_px` on each coordinate of every label.
recon::LabelSet Noisy(recon::LabelSet labels, double sigma_px, std::mt19937* rng) {
  std::normal_distribution<double> normal(0.0, sigma_px);
  for (auto& camera : labels.labels)
    for (auto& l : camera)
      if (l.present() && sigma_px > 0) l.px += Eigen::Vector2d(normal(*rng), normal(*rng));
  return labels;
}

Row Measure(const std::string& what, const calib::Rig& rig, const recon::LabelSet& labels,
            double stated_px, const KnotTracks& sim, double fps) {
  Row row;
  row.what = what;
  row.stated_px = stated_px;
  const auto start = std::chrono::steady_clock::now();
  recon::SequenceOptions options;
  options.sigma_px = stated_px;
  const recon::SequenceResult result = recon::ReconstructSequence(rig, labels, options);
  const KnotTracks tracks = recon::TracksFromSequence(result, fps, what);
  row.truth = recon::CompareWithTruth(tracks, sim);
  double trace = 0;
  int n = 0;
  for (size_t i = 0; i < tracks.valid.size(); ++i)
    if (tracks.valid[i]) trace += tracks.covariance[i].trace(), ++n;
  row.predicted_rms_m = n > 0 ? std::sqrt(trace / n) : 0.0;
  netsim::ScoreOptions score;
  score.alignment = netsim::Alignment::kTime;
  row.score = netsim::Score(tracks, sim, score).summary;
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return row;
}

const char* Arg(int argc, char** argv, const char* name, const char* fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return argv[i + 1];
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  const char* shot = Arg(argc, argv, "--shot", nullptr);
  const char* sim_path = Arg(argc, argv, "--sim", nullptr);
  if (!shot || !sim_path) {
    std::fprintf(stderr,
                 "usage: bench_error_budget --shot DIR --sim sim.h5 [--rig rig.yaml] [--fps F]\n"
                 "                          [--labels labels.h5 --labels-sigma PX]\n");
    return 2;
  }
  const std::string dir = shot;
  const calib::Rig rig = calib::ReadRig(Arg(argc, argv, "--rig", (dir + "/rig_true.yaml").c_str()));
  const double fps = std::atof(Arg(argc, argv, "--fps", "179"));
  const KnotTracks sim = ReadKnotTracks(sim_path);
  const recon::LabelSet truth = recon::ReadLabels(dir + "/labels_true.h5");

  std::vector<Row> rows;
  std::mt19937 rng(17);
  for (double sigma : {0.05, 0.1, 0.2, 0.5, 1.0}) {
    char what[64];
    std::snprintf(what, sizeof what, "true pixels + %.2f px", sigma);
    rows.push_back(Measure(what, rig, Noisy(truth, sigma, &rng), sigma, sim, fps));
  }
  if (const char* labels = Arg(argc, argv, "--labels", nullptr)) {
    const double stated = std::atof(Arg(argc, argv, "--labels-sigma", "0.09"));
    const recon::LabelSet set = recon::ReadLabelsAny(labels, truth.rows, truth.cols, truth.cameras);
    rows.push_back(Measure("labels (" + std::string(labels) + ")", rig, set, stated, sim, fps));
  }

  std::printf(
      "| pixels | stated σ (px) | points | 3D RMS vs truth (mm) | predicted by Σ (mm) | "
      "mean eᵀΣ⁻¹e vs truth | score RMS (mm) | mean d² | verdict | s |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows)
    std::printf("| %s | %.2f | %lld | %.3f | %.3f | %.2f | %.3f | %.2f | %s | %.1f |\n",
                r.what.c_str(), r.stated_px, static_cast<long long>(r.truth.points),
                r.truth.rms_m * 1e3, r.predicted_rms_m * 1e3, r.truth.mean_mahalanobis2,
                r.score.rms_m * 1e3, r.score.mean_d2, netsim::VerdictName(r.score.verdict).c_str(),
                r.seconds);
  return 0;
}
