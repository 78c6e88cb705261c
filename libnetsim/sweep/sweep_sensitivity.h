#pragma once
// The sensitivities of a sweep's outputs to its parameters: normalised derivatives (elasticities)
//
//   S = d ln(output) / d ln(parameter) = (p / o) do/dp,
//
// "a 1 % larger parameter changes the output by S %". Taken at the centre of the grid by a
// central difference along the parameter's axis, every other parameter at its middle value (the
// lower of the two middle values for an even count):
//
//   odd count n:  runs at values i-1 and i+1 around the middle i = (n-1)/2; p and o of run i
//   even count n: the two middle runs i = n/2-1 and i+1; p and o the means of the two
//
//   S = (o_hi - o_lo) / (p_hi - p_lo) * p / o
//
// For n = 2 that is the difference across the whole range. Undefined (NaN, with the reason) when
// the parameter has one value, a run it needs failed or lacks the output, or o is 0 at the
// centre.

#include <limits>
#include <string>
#include <vector>

#include "libnetsim/sweep/sweep_grid.h"
#include "libnetsim/sweep/sweep_runner.h"

namespace netlab::netsim {

struct Sensitivity {
  double value = std::numeric_limits<double>::quiet_NaN();  // S; NaN when undefined
  int run_low = -1;  // the runs of the difference (indices into the grid)
  int run_high = -1;
  std::string why_not;  // when NaN: the reason, for the report
};

// The run index of a point of the grid given each parameter's value index (sweep_grid.h's order).
int GridIndex(const std::vector<SweepParameter>& parameters, const std::vector<int>& value_index);

// [output (kSweepOutputs order)][parameter]. `runs` are the grid's runs, by index.
std::vector<std::vector<Sensitivity>> ComputeSensitivities(
    const std::vector<SweepParameter>& parameters, const std::vector<SweepRun>& runs);

}  // namespace netlab::netsim
