#include "libnetsim/sweep/sweep_sensitivity.h"

#include <cmath>
#include <limits>

namespace netlab::netsim {

int GridIndex(const std::vector<SweepParameter>& parameters, const std::vector<int>& value_index) {
  int index = 0;
  for (size_t q = 0; q < parameters.size(); ++q)
    index = index * parameters[q].count + value_index[q];
  return index;
}

std::vector<std::vector<Sensitivity>> ComputeSensitivities(
    const std::vector<SweepParameter>& parameters, const std::vector<SweepRun>& runs) {
  std::vector<int> centre(parameters.size());
  for (size_t q = 0; q < parameters.size(); ++q) centre[q] = (parameters[q].count - 1) / 2;
  std::vector<std::vector<Sensitivity>> table(kSweepOutputs.size());
  for (size_t o = 0; o < kSweepOutputs.size(); ++o) {
    const auto field = kSweepOutputs[o].field;
    for (size_t q = 0; q < parameters.size(); ++q) {
      Sensitivity s;
      const int n = parameters[q].count;
      if (n < 2 || parameters[q].from == parameters[q].to) {
        s.why_not = "one value";
        table[o].push_back(s);
        continue;
      }
      const std::vector<double> values = parameters[q].Values();
      const int lo = n % 2 == 1 ? centre[q] - 1 : n / 2 - 1;
      const int hi = lo + (n % 2 == 1 ? 2 : 1);
      std::vector<int> at = centre;
      at[q] = lo;
      s.run_low = GridIndex(parameters, at);
      at[q] = hi;
      s.run_high = GridIndex(parameters, at);
      at[q] = centre[q];
      const int mid = GridIndex(parameters, at);
      const bool ok =
          runs[s.run_low].ok() && runs[s.run_high].ok() && (n % 2 == 0 || runs[mid].ok());
      if (!ok) {
        s.why_not = "a run failed";
        table[o].push_back(s);
        continue;
      }
      const double o_lo = runs[s.run_low].outputs.*field, o_hi = runs[s.run_high].outputs.*field;
      const double p = n % 2 == 1 ? values[centre[q]] : 0.5 * (values[lo] + values[hi]);
      const double o_c = n % 2 == 1 ? runs[mid].outputs.*field : 0.5 * (o_lo + o_hi);
      if (!std::isfinite(o_lo) || !std::isfinite(o_hi) || !std::isfinite(o_c)) {
        s.why_not = "no value";
      } else if (o_c == 0.0) {
        s.why_not = "0 at the centre";
      } else {
        s.value = (o_hi - o_lo) / (values[hi] - values[lo]) * p / o_c;
      }
      table[o].push_back(s);
    }
  }
  return table;
}

}  // namespace netlab::netsim
