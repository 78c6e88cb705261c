#include "libnetsim/identification/fit_file.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/files.h"

namespace netlab::netsim {
namespace {

// A YAML double-quoted scalar: quotes and backslashes escaped.
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string FitNumber(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

std::string FitYaml(const std::vector<std::string>& scenarios,
                    const std::vector<std::string>& measured, const FitResult& r) {
  std::ostringstream o;
  o << "# netlab fit: " << scenarios[0] << " against " << measured[0];
  if (scenarios.size() > 1) o << " and " << scenarios.size() - 1 << " more shots";
  o << "\n# " << r.parameters.size() << " parameters, " << r.simulations << " simulations, "
    << FitNumber(r.wall_s) << " s. Rerun the fitted shot" << (scenarios.size() > 1 ? "s" : "")
    << ":\n";
  for (size_t k = 0; k < scenarios.size(); ++k) {
    o << "#   netlab simulate " << scenarios[k];
    for (const auto& s : r.fitted_sets[k]) o << " --set " << s.Text();
    o << " --out fitted" << (scenarios.size() > 1 ? std::to_string(k + 1) : "") << ".h5\n";
  }
  o << "scenario: " << Quoted(scenarios[0]) << "\nmeasured: " << Quoted(measured[0]) << "\n";
  o << "parameters:\n";
  for (const auto& p : r.parameters) {
    o << "  " << p.parameter.name << ": {value: " << FitNumber(p.value)
      << ", sigma: " << FitNumber(p.sigma) << ", units: " << Quoted(p.parameter.units)
      << ", start: " << FitNumber(p.parameter.start) << ", data_sigma: " << FitNumber(p.data_sigma)
      << ", identified: " << (p.identified ? "true" : "false")
      << ", rough: " << (p.rough ? "true" : "false")
      << ", ambiguous: " << (p.ambiguous ? "true" : "false")
      << ", alternative: " << FitNumber(p.alternative)
      << ", alternative_rise: " << FitNumber(p.alternative_rise) << ", check: ["
      << FitNumber(p.check[0]) << ", " << FitNumber(p.check[1]) << "]"
      << ", determined_by: " << Quoted(DeterminedByName(p.determined_by));
    if (p.has_prior)
      o << ", prior: {value: " << FitNumber(p.prior_value)
        << ", sigma: " << FitNumber(p.prior_sigma) << "}";
    o << "}\n";
  }
  o << "# correlation of the fitted coordinates (ln(value) for materials and drag), rows and\n"
    << "# columns in the order of `parameters`\ncorrelation:\n";
  for (int i = 0; i < r.correlation.rows(); ++i) {
    o << "  - [";
    for (int j = 0; j < r.correlation.cols(); ++j)
      o << (j ? ", " : "") << FitNumber(r.correlation(i, j));
    o << "]\n";
  }
  o << "cost_initial: " << FitNumber(r.cost_initial) << "\ncost_final: " << FitNumber(r.cost_final)
    << "\nresiduals: " << r.residuals << "\ninflation: " << FitNumber(r.inflation)
    << "\nsimulations: " << r.simulations << "\niterations: " << r.iterations
    << "\nwall_s: " << FitNumber(r.wall_s) << "\nduration_s: " << FitNumber(r.duration_s)
    << "\ndt_s: " << FitNumber(r.dt_s) << "  # the automatic step held for every run; 0: the "
    << "scenario's own\n";
  o << "score: {rms_mm: " << FitNumber(r.score.rms_m * 1e3)
    << ", mean_d2: " << FitNumber(r.score.mean_d2) << ", p_value: " << FitNumber(r.score.p_value)
    << ", verdict: " << VerdictName(r.score.verdict) << "}\n";
  o << "set:\n";
  for (const auto& s : r.fitted_set) o << "  - " << Quoted(s.Text()) << "\n";
  o << "notes:" << (r.notes.empty() ? " []" : "") << "\n";
  for (const auto& note : r.notes) o << "  - " << Quoted(note) << "\n";
  if (scenarios.size() > 1) {
    o << "# every shot (the keys above are the first one's)\nshots:\n";
    for (size_t k = 0; k < scenarios.size(); ++k) {
      const ScoreSummary& sc = r.scores[k];
      o << "  - scenario: " << Quoted(scenarios[k]) << "\n    measured: " << Quoted(measured[k])
        << "\n    score: {rms_mm: " << FitNumber(sc.rms_m * 1e3)
        << ", mean_d2: " << FitNumber(sc.mean_d2) << ", p_value: " << FitNumber(sc.p_value)
        << ", verdict: " << VerdictName(sc.verdict)
        << "}\n    inflation: " << FitNumber(r.inflations[k]) << "\n    set:\n";
      for (const auto& s : r.fitted_sets[k]) o << "      - " << Quoted(s.Text()) << "\n";
    }
  }
  return o.str();
}

void WriteFit(const std::string& path, const std::vector<std::string>& scenarios,
              const std::vector<std::string>& measured, const FitResult& result) {
  WriteTextFile(path, FitYaml(scenarios, measured, result));
}

}  // namespace netlab::netsim
