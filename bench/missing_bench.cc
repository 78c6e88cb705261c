// bench_missing: the review queue's missing knots (app/gui/document/missing_knots.h) on a labeled
// shot: how long the count takes (the whole shot on opening, one frame row after an edit), how
// many of the knots it lists are false alarms (not visible: labels_true.h5 of a rendered shot has
// every visible knot) and how many of the visible knots without a label it leaves unlisted, with
// and without the target (--target: the simulation the shot was rendered from, or its scenario).
// A printed table, never a test.
//
//   build/bench/bench_missing --labels out/demo/labels.h5 --rig out/demo/shot/rig_true.yaml
//                             --truth out/demo/shot/labels_true.h5 --target out/demo/sim.h5
//                             [--fps 179] [--repeat 5]

#include <QCoreApplication>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "app/gui/document/label_document.h"
#include "app/gui/document/missing_knots.h"
#include "calibration/rig.h"
#include "libreconstruct/labels/label_set.h"

namespace netlab::gui {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The label of (camera name, frame number, knot) in `truth`; null when it has no such row.
const recon::Label* TruthOf(const recon::LabelSet& truth, const std::string& camera, int frame,
                            int knot) {
  const int c = truth.FindCamera(camera);
  const auto it = std::find(truth.frame_index.begin(), truth.frame_index.end(), frame);
  if (c < 0 || it == truth.frame_index.end()) return nullptr;
  return &truth.at(c, static_cast<int>(it - truth.frame_index.begin()), knot);
}

// A. Time: the whole shot, repeated; one frame row after an edit through the document.
void Timing(const recon::LabelSet& labels, const calib::Rig& rig, const std::vector<int>& index,
            const MissingKnotsOptions& options, int repeat) {
  std::vector<double> full;
  size_t found = 0;
  for (int r = 0; r < repeat; ++r) {
    const auto start = Clock::now();
    found = 0;
    for (int t = 0; t < labels.frames(); ++t)
      found += FindMissingKnots(labels, rig, index, t, options).size();
    full.push_back(MsSince(start));
  }
  std::sort(full.begin(), full.end());
  const double whole = full[full.size() / 2], per_row = whole / std::max(1, labels.frames());
  // An edit through the document: a label deleted, then undone (each one row counted again).
  const std::string scratch =
      (std::filesystem::temp_directory_path() / "bench_missing_labels.h5").string();
  LabelDocument document(labels, scratch);
  MissingKnots missing(&document, &rig, index, options);
  std::vector<double> edit;
  for (int t = 0; t < labels.frames(); ++t)
    for (int k = 0; k < labels.knots(); ++k) {
      if (!labels.at(0, t, k).accepted()) continue;
      const auto start = Clock::now();
      document.Apply("Delete", {{0, t, k, recon::Label{}}});
      edit.push_back(MsSince(start));
      document.undo_stack()->undo();
      break;
    }
  document.DiscardJournal();
  std::sort(edit.begin(), edit.end());
  std::printf("| what | time |\n|---|---|\n");
  std::printf("| whole shot, %d frame rows x %d knots x %zu cameras (%zu missing) | %.1f ms |\n",
              labels.frames(), labels.knots(), labels.cameras.size(), found, whole);
  std::printf("| per frame row (whole shot / rows) | %.3f ms |\n", per_row);
  std::printf(
      "| an edit through the document (apply, journal, its rows counted; median) | %.3f ms "
      "|\n",
      edit.empty() ? 0.0 : edit[edit.size() / 2]);
  std::printf("| 3200 frame rows, extrapolated | %.2f s |\n\n", per_row * 3200 / 1000.0);
}

// What the list says against the truth, over every frame row.
struct Score {
  int listed = 0, visible = 0, false_alarms = 0;
  int by_basis[3] = {0, 0, 0}, false_by_basis[3] = {0, 0, 0};  // MissingBasis
  int runs = 0;  // (camera, knot) runs of consecutive frame rows listed: Shift+D presses
  std::vector<double> error;  // expected vs true position of the visible ones, px
  int unlabeled_visible = 0, unlisted = 0;
  std::vector<int> unlisted_by_others;  // by the other cameras with accepted labels
};

Score Compare(const recon::LabelSet& labels, const calib::Rig& rig, const std::vector<int>& index,
              const recon::LabelSet& truth, const MissingKnotsOptions& options) {
  Score s;
  const int cameras = static_cast<int>(labels.cameras.size());
  s.unlisted_by_others.assign(cameras, 0);
  std::vector<std::vector<int>> last_listed(cameras, std::vector<int>(labels.knots(), -2));
  for (int t = 0; t < labels.frames(); ++t) {
    std::vector<std::vector<bool>> named(cameras, std::vector<bool>(labels.knots(), false));
    for (const MissingKnot& m : FindMissingKnots(labels, rig, index, t, options)) {
      ++s.listed;
      ++s.by_basis[static_cast<int>(m.basis)];
      named[m.camera][m.knot] = true;
      s.runs += last_listed[m.camera][m.knot] != t - 1;
      last_listed[m.camera][m.knot] = t;
      const recon::Label* want =
          TruthOf(truth, labels.cameras[m.camera], labels.frame_index[t], m.knot);
      if (want && want->present()) {
        ++s.visible;
        s.error.push_back((want->px - m.expected_px).norm());
      } else {
        ++s.false_alarms;
        ++s.false_by_basis[static_cast<int>(m.basis)];
      }
    }
    // Visible knots without a label that the list does not name.
    for (int c = 0; c < cameras; ++c)
      for (int k = 0; k < labels.knots(); ++k) {
        const recon::Label* want = TruthOf(truth, labels.cameras[c], labels.frame_index[t], k);
        if (!want || !want->present() || labels.at(c, t, k).present()) continue;
        ++s.unlabeled_visible;
        if (named[c][k]) continue;
        ++s.unlisted;
        int others = 0;
        for (int o = 0; o < cameras; ++o) others += o != c && labels.at(o, t, k).accepted();
        ++s.unlisted_by_others[others];
      }
  }
  std::sort(s.error.begin(), s.error.end());
  return s;
}

double Percent(int part, int whole) { return whole ? 100.0 * part / whole : 0.0; }

// B. The list against the truth: on the labels given, on the truth itself (every listed knot a
// false alarm) and on the truth with 3 % of its labels deleted (the deleted visible ones should
// be listed); without the target, with it, and with it and the labeled-neighbour rule.
void Truth(const recon::LabelSet& labels, const calib::Rig& rig, const std::vector<int>& index,
           recon::LabelSet truth, const MissingKnotsOptions& with_target) {
  for (auto& camera : truth.labels)
    for (recon::Label& l : camera)
      if (l.present()) l.state = recon::LabelState::kAccepted;
  recon::LabelSet thinned = truth;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int deleted = 0;
  for (auto& camera : thinned.labels)
    for (recon::Label& l : camera)
      if (l.present() && uniform(rng) < 0.03) l = recon::Label{}, ++deleted;
  const std::pair<const char*, const recon::LabelSet*> cases[] = {
      {"the labels given", &labels},
      {"the truth (all visible knots)", &truth},
      {"the truth, 3 % deleted", &thinned}};
  struct Variant {
    const char* target;
    const char* rule;
    MissingKnotsOptions options;
  };
  std::vector<Variant> variants;
  variants.push_back({"no", "no", with_target});
  variants.back().options.target = {};
  if (!with_target.target.empty()) {
    variants.push_back({"yes", "no", with_target});
    variants.push_back({"yes", "yes", with_target});
    variants.back().options.need_labeled_neighbour = true;
  }
  std::printf(
      "| labels | target | neighbour rule | listed (cameras / neighbours / motion) | "
      "false alarms | visible without a label | unlisted | runs (Shift+D) | "
      "expected vs true, median / max |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, set] : cases)
    for (const Variant& v : variants) {
      const Score s = Compare(*set, rig, index, truth, v.options);
      std::printf(
          "| %s | %s | %s | %d (%d / %d / %d) | %d (%.1f %%) | %d | %d (%.1f %%) | %d | "
          "%.2f / %.2f px |\n",
          name, v.target, v.rule, s.listed, s.by_basis[0], s.by_basis[1], s.by_basis[2],
          s.false_alarms, Percent(s.false_alarms, s.listed), s.unlabeled_visible, s.unlisted,
          Percent(s.unlisted, s.unlabeled_visible), s.runs,
          s.error.empty() ? 0.0 : s.error[s.error.size() / 2],
          s.error.empty() ? 0.0 : s.error.back());
    }
  std::printf("\n(the truth, 3 %% deleted: %d visible labels deleted)\n\n", deleted);
  // The labels given, with the target where there is one: false alarms and unlisted knots by
  // what placed them.
  const Score s = Compare(labels, rig, index, truth,
                          variants.size() > 1 ? variants[1].options : variants[0].options);
  std::printf("| the labels given%s | listed | false alarms |\n|---|---|---|\n",
              with_target.target.empty() ? "" : ", with the target");
  const char* basis[] = {"the other cameras", "the grid neighbours", "the motion"};
  for (int b = 0; b < 3; ++b)
    std::printf("| placed by %s | %d | %d |\n", basis[b], s.by_basis[b], s.false_by_basis[b]);
  std::printf("\n| visible knots without a label | %d |\n|---|---|\n", s.unlabeled_visible);
  std::printf("| not listed | %d |\n", s.unlisted);
  for (size_t n = 0; n < s.unlisted_by_others.size(); ++n)
    std::printf("|   of them with accepted labels in %zu other cameras | %d |\n", n,
                s.unlisted_by_others[n]);
}

}  // namespace
}  // namespace netlab::gui

int main(int argc, char** argv) {
  using namespace netlab;
  std::string labels_path, rig_path, truth_path;
  std::string target_path;
  double fps = 179.0;
  int repeat = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--labels" && i + 1 < argc)
      labels_path = argv[++i];
    else if (a == "--rig" && i + 1 < argc)
      rig_path = argv[++i];
    else if (a == "--truth" && i + 1 < argc)
      truth_path = argv[++i];
    else if (a == "--target" && i + 1 < argc)
      target_path = argv[++i];
    else if (a == "--fps" && i + 1 < argc)
      fps = std::stod(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::stoi(argv[++i]));
    else {
      std::fprintf(stderr,
                   "usage: bench_missing --labels L.h5 --rig RIG.yaml [--truth T.h5] "
                   "[--target SIM.h5|SCENARIO.yaml] [--fps F] [--repeat N]\n");
      return 2;
    }
  }
  if (labels_path.empty() || rig_path.empty()) {
    std::fprintf(stderr, "bench_missing: --labels and --rig are needed\n");
    return 2;
  }
  QCoreApplication app(argc, argv);
  try {
    const recon::LabelSet labels = recon::ReadLabels(labels_path);
    const calib::Rig rig = calib::ReadRig(rig_path);
    std::vector<int> index;
    for (const std::string& name : labels.cameras) {
      index.push_back(rig.Find(name));
      if (index.back() < 0) throw std::runtime_error(rig_path + ": no camera '" + name + "'");
    }
    gui::MissingKnotsOptions options;
    if (!target_path.empty()) options.target = gui::LoadTarget(target_path, fps);
    gui::Timing(labels, rig, index, options, repeat);
    if (!truth_path.empty()) gui::Truth(labels, rig, index, recon::ReadLabels(truth_path), options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_missing: %s\n", e.what());
    return 1;
  }
  return 0;
}
