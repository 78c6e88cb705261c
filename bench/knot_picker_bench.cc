// bench_knot_picker: the knot picker's colour hint (I in `netlab gui`, Session::IdentifyJunction)
// at every visible knot of a rendered shot (labels_true.h5 has them all), pointed at exactly:
// how often the colours identify the knot alone (and whether rightly), how many knots they offer
// otherwise (and whether the true one is among them), how often they say nothing, and the time
// per press. Two cases: seeding (no labels yet: the link length is unknown, the yarns are read
// out to 16 px) and the link length known (read out to 0.4 link). A printed table, never a test.
//
//   build/bench/bench_knot_picker --shot out/demo/shot --coloring out/demo/coloring.yaml
//                                 [--frames 5] [--brush 6]

#include <QCoreApplication>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "app/gui/document/project.h"
#include "app/gui/document/session.h"
#include "libreconstruct/labeling/label_engine.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Tally {
  int asked = 0, found = 0, identified = 0, identified_wrong = 0, offered = 0,
      offered_without_truth = 0, unknown = 0;
  std::vector<int> candidates;
  std::vector<double> ms;
  void Print(const std::string& name) const {
    std::vector<int> c = candidates;
    std::vector<double> t = ms;
    std::sort(c.begin(), c.end());
    std::sort(t.begin(), t.end());
    std::printf(
        "| %s | %d | %d | %d (%d wrong) | %d (%d without the true knot) | %d | %d | %.1f "
        "ms |\n",
        name.c_str(), asked, found, identified, identified_wrong, offered, offered_without_truth,
        c.empty() ? 0 : c[c.size() / 2], unknown, t.empty() ? 0.0 : t[t.size() / 2]);
  }
};

// The median image length of the true links of (camera, frame row) in `truth`; 0 when none.
double TrueLinkPx(const recon::LabelSet& truth, int tc, int row) {
  std::vector<double> lengths;
  for (int k = 0; k < truth.knots(); ++k) {
    const std::array<int, 4> around = recon::GridSlots(truth.rows, truth.cols, k);
    for (int s = 0; s < 2; ++s)
      if (around[s] >= 0 && truth.at(tc, row, k).present() &&
          truth.at(tc, row, around[s]).present())
        lengths.push_back((truth.at(tc, row, around[s]).px - truth.at(tc, row, k).px).norm());
  }
  if (lengths.empty()) return 0.0;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return lengths[lengths.size() / 2];
}

void Run(const std::string& shot, const std::string& coloring, int frames, double brush) {
  const recon::LabelSet truth = recon::ReadLabels(shot + "/labels_true.h5");
  const std::string dir = (fs::temp_directory_path() / "bench_knot_picker").string();
  fs::create_directories(dir);
  const std::string labels = dir + "/labels.h5";
  fs::remove(labels);
  fs::remove(labels + ".journal");
  const std::string project_path = dir + "/project.yaml";
  SaveProject(
      MakeProject(shot + "/experiment.yaml", shot + "/rig_true.yaml", coloring, labels, 0, 0),
      project_path);
  const auto session = Session::Open(LoadProject(project_path));
  frames = std::min(frames, session->frames());
  std::map<std::string, Tally> seeding, known;
  Tally all_seeding, all_known;
  for (int t = 0; t < frames; ++t)
    for (int c = 0; c < session->cameras(); ++c) {
      const std::string& name = session->camera_names()[c];
      const int tc = truth.FindCamera(name);
      const auto row =
          std::find(truth.frame_index.begin(), truth.frame_index.end(), session->frame_number(t));
      if (tc < 0 || row == truth.frame_index.end()) continue;
      const int tr = static_cast<int>(row - truth.frame_index.begin());
      const double link = TrueLinkPx(truth, tc, tr);
      for (int k = 0; k < truth.knots(); ++k) {
        const recon::Label& want = truth.at(tc, tr, k);
        if (!want.present()) continue;
        for (const bool seeded : {true, false}) {
          const auto start = Clock::now();
          const Session::JunctionHint hint =
              session->IdentifyJunction(c, t, want.px, brush, seeded ? 0.0 : link);
          const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
          for (Tally* tally : seeded ? std::vector<Tally*>{&seeding[name], &all_seeding}
                                     : std::vector<Tally*>{&known[name], &all_known}) {
            ++tally->asked;
            tally->ms.push_back(ms);
            tally->found += hint.found;
            const auto& knots = hint.reading.knots;
            const bool has = std::find(knots.begin(), knots.end(), k) != knots.end();
            switch (hint.reading.status) {
              case recon::IdentifyStatus::kIdentified:
                ++tally->identified;
                tally->identified_wrong += !has;
                break;
              case recon::IdentifyStatus::kAmbiguous:
                ++tally->offered;
                tally->offered_without_truth += !has;
                tally->candidates.push_back(static_cast<int>(knots.size()));
                break;
              case recon::IdentifyStatus::kUnknown: ++tally->unknown; break;
            }
          }
        }
      }
    }
  std::printf("bench_knot_picker: %s, frames 0..%d, %d knots, brush %.0f px at the true pixel\n\n",
              shot.c_str(), frames - 1, truth.knots(), brush);
  std::printf(
      "| case, camera | knot-views | junction found | identified alone | offered several "
      "| knots offered (median) | nothing said | time per I (median) |\n"
      "|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, tally] : seeding) tally.Print("seeding (link unknown), " + name);
  all_seeding.Print("**seeding, all**");
  for (const auto& [name, tally] : known) tally.Print("link length known, " + name);
  all_known.Print("**link length known, all**");
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  std::string shot, coloring;
  int frames = 5;
  double brush = 6.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--shot" && i + 1 < argc)
      shot = argv[++i];
    else if (a == "--coloring" && i + 1 < argc)
      coloring = argv[++i];
    else if (a == "--frames" && i + 1 < argc)
      frames = std::max(1, std::stoi(argv[++i]));
    else if (a == "--brush" && i + 1 < argc)
      brush = std::stod(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: bench_knot_picker --shot DIR --coloring C.yaml [--frames N] "
                   "[--brush PX]\n");
      return 2;
    }
  }
  if (shot.empty() || coloring.empty()) {
    std::fprintf(stderr, "bench_knot_picker: --shot and --coloring are needed\n");
    return 2;
  }
  QCoreApplication app(argc, argv);
  try {
    netlab::gui::Run(shot, coloring, frames, brush);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_knot_picker: %s\n", e.what());
    return 1;
  }
  return 0;
}
