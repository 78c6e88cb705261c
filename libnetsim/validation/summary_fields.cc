#include "libnetsim/validation/summary_fields.h"

#include <array>
#include <sstream>
#include <stdexcept>

namespace netlab::netsim {
namespace {

SummaryValue Number(double value) {
  SummaryValue v;
  v.number = value;
  return v;
}

SummaryValue Text(std::string text) {
  SummaryValue v;
  v.text = std::move(text);
  return v;
}

using K = SummaryKind;
constexpr unsigned kJson = kInJson, kFile = kInFile, kBoth = kInJson | kInFile;

// The JSON summary's order; score.h5's /summary holds the kInFile ones (h5dump lists them by
// name). Values are in the key's unit: rms_mm is rms_m x 1e3.
const std::array kFields = {
    SummaryField{"frames", K::kInt, "1", "", kBoth,
                 [](const ScoreSummary& s) { return Number(s.frames); }},
    SummaryField{"knots", K::kInt, "1", "", kBoth,
                 [](const ScoreSummary& s) { return Number(s.knots); }},
    SummaryField{"points", K::kInt, "knot-frames", "", kBoth,
                 [](const ScoreSummary& s) { return Number(s.points); }},
    SummaryField{"masked", K::kInt, "knot-frames", "", kJson,
                 [](const ScoreSummary& s) { return Number(s.masked); }},
    SummaryField{"rms_mm", K::kNumber, "mm", "RMS", kBoth,
                 [](const ScoreSummary& s) { return Number(s.rms_m * 1e3); }},
    SummaryField{"rms_percent_of_side", K::kNumber, "%", "RMS", kBoth,
                 [](const ScoreSummary& s) { return Number(s.rms_percent_of_side); }},
    SummaryField{"side_m", K::kNumber, "m", "side", kBoth,
                 [](const ScoreSummary& s) { return Number(s.side_m); }},
    SummaryField{"max_mm", K::kNumber, "mm", "largest", kBoth,
                 [](const ScoreSummary& s) { return Number(s.max_m * 1e3); }},
    SummaryField{"headline", K::kText, "", "", kBoth,
                 [](const ScoreSummary& s) { return Text(s.headline); }},
    SummaryField{"left_out_points", K::kInt, "knot-frames", "left out", kBoth,
                 [](const ScoreSummary& s) { return Number(s.left_out); }},
    SummaryField{"left_out_max_sigma_mm", K::kNumber, "mm", "largest sigma left out", kJson,
                 [](const ScoreSummary& s) { return Number(s.left_out_max_sigma_m * 1e3); }},
    SummaryField{"sigma_bound_mm", K::kNumber, "mm", "sigma bound", kBoth,
                 [](const ScoreSummary& s) { return Number(s.sigma_bound_m * 1e3); }},
    SummaryField{"sigma_bound_from", K::kText, "", "sigma bound from", kJson,
                 [](const ScoreSummary& s) { return Text(s.sigma_bound_from); }},
    SummaryField{"median_sigma_mm", K::kNumber, "mm", "median sigma", kJson,
                 [](const ScoreSummary& s) { return Number(s.median_sigma_m * 1e3); }},
    SummaryField{"weighted_rms_mm", K::kNumber, "mm", "covariance-weighted RMS", kBoth,
                 [](const ScoreSummary& s) { return Number(s.weighted_rms_m * 1e3); }},
    SummaryField{"sigma_spread", K::kNumber, "1", "sigma spread", kJson,
                 [](const ScoreSummary& s) { return Number(s.sigma_spread); }},
    SummaryField{"degenerate_points", K::kInt, "knot-frames", "degenerate", kBoth,
                 [](const ScoreSummary& s) { return Number(s.degenerate); }},
    SummaryField{"mean_d2", K::kNumber, "1", "mean d2", kBoth,
                 [](const ScoreSummary& s) { return Number(s.mean_d2); }},
    SummaryField{"dof", K::kNumber, "1", "dof", kBoth,
                 [](const ScoreSummary& s) { return Number(s.dof); }},
    SummaryField{"fitted_parameters", K::kInt, "1", "fitted parameters", kJson,
                 [](const ScoreSummary& s) { return Number(s.fitted_parameters); }},
    SummaryField{"tau_int", K::kNumber, "frames", "tau_int", kBoth,
                 [](const ScoreSummary& s) { return Number(s.tau_int); }},
    SummaryField{"design_effect", K::kNumber, "1", "design effect", kBoth,
                 [](const ScoreSummary& s) { return Number(s.design_effect); }},
    SummaryField{"effective_points", K::kNumber, "knot-frames", "effective points", kBoth,
                 [](const ScoreSummary& s) { return Number(s.effective_points); }},
    SummaryField{"p_value", K::kNumber, "1", "p =", kBoth,
                 [](const ScoreSummary& s) { return Number(s.p_value); }},
    SummaryField{"critical_mean_d2", K::kNumber, "1", "rejected above mean d2", kBoth,
                 [](const ScoreSummary& s) { return Number(s.critical_mean_d2); }},
    SummaryField{"margin", K::kNumber, "1", "margin", kBoth,
                 [](const ScoreSummary& s) { return Number(s.margin); }},
    SummaryField{"verdict", K::kText, "", "verdict:", kJson,
                 [](const ScoreSummary& s) { return Text(VerdictName(s.verdict)); }},
    SummaryField{"alignment", K::kText, "", "alignment", kJson,
                 [](const ScoreSummary& s) { return Text(AlignmentName(s.alignment)); }},
    SummaryField{"time_offset_s", K::kNumber, "s", "time offset", kJson,
                 [](const ScoreSummary& s) { return Number(s.time_offset_s); }},
    SummaryField{"time_offset_sigma_s", K::kNumber, "s", "+-", kJson,
                 [](const ScoreSummary& s) { return Number(s.time_offset_sigma_s); }},
    SummaryField{"translation", K::kVector3, "m", "translation", kJson,
                 [](const ScoreSummary& s) {
                   SummaryValue v;
                   v.vector = s.translation;
                   return v;
                 }},
    SummaryField{"sim_uncertainty", K::kText, "", "Sigma_sim", kBoth,
                 [](const ScoreSummary& s) { return Text(s.sim_uncertainty); }},
    SummaryField{"sim_too_sparse", K::kFlag, "", "simulation too sparse", kJson,
                 [](const ScoreSummary& s) { return Number(s.sim_too_sparse ? 1.0 : 0.0); }},
    SummaryField{"interpolation_rms_mm", K::kNumber, "mm", "interpolation RMS", kBoth,
                 [](const ScoreSummary& s) { return Number(s.interpolation_rms_m * 1e3); }},
    SummaryField{"skill", K::kNumber, "1", "skill", kBoth,
                 [](const ScoreSummary& s) { return Number(s.skill); }},
    SummaryField{"baseline_rms_mm", K::kNumber, "mm", "straight-line flight RMS", kBoth,
                 [](const ScoreSummary& s) { return Number(s.baseline_rms_m * 1e3); }},
    SummaryField{"per_class", K::kRows, "mm", "corner/edge/inner RMS", kJson,
                 [](const ScoreSummary& s) {
                   SummaryValue v;
                   v.rows = s.per_class;
                   return v;
                 }},
    SummaryField{"per_phase", K::kRows, "mm", "RMS per phase", kJson,
                 [](const ScoreSummary& s) {
                   SummaryValue v;
                   v.rows = s.per_phase;
                   return v;
                 }},
    SummaryField{"phases", K::kPhases, "", "phases", kJson,
                 [](const ScoreSummary& s) {
                   SummaryValue v;
                   v.rows = s.per_phase;
                   return v;
                 }},
    SummaryField{"ensemble_members", K::kInt, "1", "ensemble members", kJson,
                 [](const ScoreSummary& s) { return Number(s.ensemble_members); }},
    SummaryField{"contact_time_s", K::kNumber, "s", "contact at", kBoth,
                 [](const ScoreSummary& s) { return Number(s.contact_time_s); }},
    SummaryField{"contact_from", K::kText, "", "contact from", kBoth,
                 [](const ScoreSummary& s) { return Text(ContactFromName(s.contact_from)); }},
    SummaryField{"max_area_measured_m2", K::kNumber, "m^2", "largest measured area", kBoth,
                 [](const ScoreSummary& s) { return Number(s.max_area_measured_m2); }},
    SummaryField{"max_area_time_measured_s", K::kNumber, "s", "at", kFile,
                 [](const ScoreSummary& s) { return Number(s.max_area_time_measured_s); }},
    SummaryField{"max_area_simulated_m2", K::kNumber, "m^2", "largest simulated area", kBoth,
                 [](const ScoreSummary& s) { return Number(s.max_area_simulated_m2); }},
    SummaryField{"max_area_time_simulated_s", K::kNumber, "s", "at", kFile,
                 [](const ScoreSummary& s) { return Number(s.max_area_time_simulated_s); }},
    SummaryField{"notes", K::kLines, "", "note:", kJson,
                 [](const ScoreSummary& s) {
                   SummaryValue v;
                   v.lines = s.notes;
                   return v;
                 }},
    SummaryField{"output", K::kText, "", "wrote", kJson,
                 [](const ScoreSummary& s) { return Text(s.output_path); }},
    SummaryField{"report", K::kText, "", "and", kJson,
                 [](const ScoreSummary& s) { return Text(s.report_path); }},
    SummaryField{"wall_s", K::kNumber, "s", "wall time", kJson,
                 [](const ScoreSummary& s) { return Number(s.wall_s); }},
};

// A value as the text summary prints it: a count whole, a number with 4 significant digits.
std::string Format(const SummaryField& field, double value) {
  std::ostringstream o;
  o.precision(4);
  if (field.kind == SummaryKind::kInt)
    o << static_cast<long long>(value);
  else
    o << value;
  return o.str();
}

// The text of one placeholder, "key", "key@ms" or "key.row"; `line` for a kLines field.
std::string Expand(std::string_view spec, bool with_label, const ScoreSummary& s,
                   const std::string* line) {
  std::string_view key = spec, row, unit;
  if (const size_t at = spec.find('@'); at != std::string_view::npos) {
    key = spec.substr(0, at);
    unit = spec.substr(at + 1);
  } else if (const size_t dot = spec.find('.'); dot != std::string_view::npos) {
    key = spec.substr(0, dot);
    row = spec.substr(dot + 1);
  }
  const SummaryField& field = FindSummaryField(key);
  const SummaryValue value = field.value(s);
  std::string text;
  switch (field.kind) {
    case SummaryKind::kInt:
    case SummaryKind::kNumber: {
      double number = value.number;
      if (unit == "ms" && field.unit == "s")
        number = value.number * 1e3;
      else if (!unit.empty())
        throw std::logic_error("summary text: {" + std::string(spec) + "}: no such unit");
      text = Format(field, number);
      break;
    }
    case SummaryKind::kText: text = value.text; break;
    case SummaryKind::kRows:
      for (const ScoreRow& r : value.rows)
        if (r.name == row) text = Format(field, r.rms_m * 1e3);
      if (text.empty())
        throw std::logic_error("summary text: {" + std::string(spec) + "}: no such row");
      break;
    case SummaryKind::kLines: text = line != nullptr ? *line : ""; break;
    default: throw std::logic_error("summary text: {" + std::string(spec) + "} has no text form");
  }
  return with_label ? std::string(field.label) + " " + text : text;
}

// One line of the template, its placeholders filled (`line`: the kLines field's line, if any).
std::string FillLine(std::string_view text, const ScoreSummary& s, const std::string* line) {
  std::string out;
  for (size_t i = 0; i < text.size();) {
    const char open = text[i];
    if (open != '{' && open != '[') {
      out += text[i++];
      continue;
    }
    const size_t end = text.find(open == '{' ? '}' : ']', i);
    if (end == std::string_view::npos)
      throw std::logic_error("summary text: unclosed " + std::string(1, open));
    out += Expand(text.substr(i + 1, end - i - 1), open == '[', s, line);
    i = end + 1;
  }
  return out;
}

// The kLines field a template line names, or nullptr.
const SummaryField* LinesField(std::string_view text) {
  for (const SummaryField& field : kFields)
    if (field.kind == SummaryKind::kLines &&
        (text.find("{" + std::string(field.key) + "}") != std::string_view::npos ||
         text.find("[" + std::string(field.key) + "]") != std::string_view::npos))
      return &field;
  return nullptr;
}

}  // namespace

std::span<const SummaryField> SummaryFields() { return kFields; }

const SummaryField& FindSummaryField(std::string_view key) {
  for (const SummaryField& field : kFields)
    if (field.key == key) return field;
  throw std::logic_error("score summary: no field '" + std::string(key) + "'");
}

std::string FillSummaryText(std::string_view text, const ScoreSummary& summary) {
  std::string out;
  while (!text.empty()) {
    const size_t newline = text.find('\n');
    const size_t length = newline == std::string_view::npos ? text.size() : newline + 1;
    const std::string_view line = text.substr(0, length);
    text.remove_prefix(length);
    if (const SummaryField* lines = LinesField(line)) {
      for (const std::string& item : lines->value(summary).lines)
        out += FillLine(line, summary, &item);
    } else {
      out += FillLine(line, summary, nullptr);
    }
  }
  return out;
}

}  // namespace netlab::netsim
