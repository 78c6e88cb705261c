#include "libreconstruct/labeling/label_journal.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>
#include <utility>

#include "common/errors.h"

namespace netlab::recon {
namespace {

constexpr char kJournalMagic[] = "netlab-journal";

const char* ChangeName(LabelStore::Change change) {
  switch (change) {
    case LabelStore::Change::kApplied: return "applied";
    case LabelStore::Change::kUndone: return "undone";
    case LabelStore::Change::kRedone: return "redone";
  }
  return "?";
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "nan";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

}  // namespace

std::string LabelJournalPath(const std::string& labels_path) { return labels_path + ".journal"; }

std::string LabelJournalHeader(const LabelSet& set) {
  std::string cameras;
  for (const std::string& c : set.cameras) cameras += (cameras.empty() ? "" : ",") + c;
  return std::string(kJournalMagic) + " 1 " + std::to_string(set.rows) + " " +
         std::to_string(set.cols) + " " + std::to_string(set.frames()) + " " + cameras;
}

void WriteLabelJournalStep(std::ostream& out, LabelStore::Change change, const std::string& step,
                           const std::vector<LabelEdit>& now) {
  out << "step " << ChangeName(change) << " " << step << "\n";
  for (const LabelEdit& e : now)
    out << e.camera << " " << e.t << " " << e.knot << " " << Number(e.label.px.x()) << " "
        << Number(e.label.px.y()) << " " << static_cast<int>(e.label.source) << " "
        << Number(e.label.confidence) << " " << static_cast<int>(e.label.state) << "\n";
  out << "end\n";
}

std::vector<LabelEdit> ReadLabelJournal(const std::string& path, const LabelSet& set) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the journal");
  std::string line;
  std::getline(in, line);
  if (line != LabelJournalHeader(set))
    throw InputError(path + ":1: the journal is of another label set (" + line + ", this is " +
                     LabelJournalHeader(set) + ")");
  // Every complete step's labels as they ended up; a step cut short by the crash is left out.
  std::map<LabelAddress, Label> last;
  std::vector<std::pair<LabelAddress, Label>> pending;
  for (int line_no = 2; std::getline(in, line); ++line_no) {
    if (line.rfind("step ", 0) == 0) {
      pending.clear();
    } else if (line == "end") {
      for (const auto& [key, label] : pending) last[key] = label;
      pending.clear();
    } else {
      std::istringstream fields(line);
      int c, t, k, source, state;
      std::string x, y, confidence;
      if (!(fields >> c >> t >> k >> x >> y >> source >> confidence >> state) || c < 0 ||
          c >= static_cast<int>(set.cameras.size()) || t < 0 || t >= set.frames() || k < 0 ||
          k >= set.knots())
        throw InputError(path + ":" + std::to_string(line_no) +
                         ": not a label of this set: " + line);
      Label label;
      label.px = {std::stod(x), std::stod(y)};
      label.source = static_cast<LabelSource>(source);
      label.confidence = std::stof(confidence);
      label.state = static_cast<LabelState>(state);
      // A source, state or hidden mark no label can have: the journal is damaged.
      if (source < 0 || source > static_cast<int>(LabelSource::kProjected) || state < 0 ||
          state > static_cast<int>(LabelState::kHidden) ||
          (label.hidden() && !(std::isnan(label.px.x()) && std::isnan(label.px.y()))))
        throw InputError(
            path + ":" + std::to_string(line_no) +
            ": not a label (source, state, or a hidden mark with a position): " + line);
      pending.emplace_back(LabelAddress{c, t, k}, label);
    }
  }
  std::vector<LabelEdit> edits;
  for (const auto& [key, label] : last) edits.push_back({key.camera, key.t, key.knot, label});
  return edits;
}

}  // namespace netlab::recon
