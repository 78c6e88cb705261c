#pragma once
// The parameter grid of a sweep (`netlab sweep --vary PATH=a:b:n`): each varied parameter is one
// value of the scenario, named by the dotted path of `simulate --set` (scenario_override.h), and
// takes n evenly spaced values from a to b. Several parameters make the full grid; run i is one
// override set, the first parameter varying slowest (row-major over the parameters' indices).

#include <string>
#include <vector>

#include "libnetsim/scenario/scenario_override.h"

namespace netlab::netsim {

struct SweepParameter {
  std::string path;  // dotted, as for --set: materials.nylon_1mm.bend_stiffness
  double from = 0.0;
  double to = 0.0;
  int count = 1;      // values from `from` to `to` inclusive; 1: `from` alone
  std::string given;  // the --vary argument as given ("" when made in code)

  // The count values, evenly spaced: from + i (to - from) / (count - 1) rounded to 12
  // significant digits (1e-4:4e-4:4 gives 2e-4, not 0.00019999999999999998), the ends exactly
  // `from` and `to`.
  std::vector<double> Values() const;
  std::string Text() const;  // "PATH=a:b:n": `given`, or made from the values
};

// "PATH=a:b:n" as given to --vary. InputError naming the argument when there is no '=', a or b is
// not a finite number, n is not an integer >= 1 (at most 10000), or n is 1 and a differs from b.
SweepParameter ParseVary(const std::string& arg);

// A value as override text: the shortest decimal that reads back as the same double, so that
// `simulate --set PATH=<text>` runs with exactly the value the sweep ran.
std::string ValueText(double value);

// Checks that every parameter's path leads to a number of the scenario in `scenario_path` (as
// `--set` checks it; the values' ranges are checked per run). InputError naming the --vary and
// the key otherwise, and when two parameters name the same path.
void CheckSweepParameters(const std::string& scenario_path,
                          const std::vector<ScenarioOverride>& fixed,
                          const std::vector<SweepParameter>& parameters);

// One run of the grid: its index, each parameter's value index and value, and the overrides that
// make it (the fixed ones first, then one per parameter).
struct SweepPoint {
  int index = 0;
  std::vector<int> value_index;  // [P]
  std::vector<double> values;    // [P]
  std::vector<ScenarioOverride> overrides;
};

// The full grid: prod(count) points, the first parameter slowest. InputError when it would
// exceed 100000 runs.
std::vector<SweepPoint> SweepGrid(const std::vector<ScenarioOverride>& fixed,
                                  const std::vector<SweepParameter>& parameters);

// An ensemble of `runs` runs (`netlab sweep --ensemble N`): runs of one model differing only in
// what it cannot know, for `netlab score --sim-ensemble`. Each parameter takes one of its count
// values per run, each value equally often (within one) and in an order shuffled with a fixed seed
// per parameter, so the parameters are drawn independently and the same command gives the same
// runs. InputError when runs is below 2 or above 100000.
std::vector<SweepPoint> SweepEnsemble(const std::vector<ScenarioOverride>& fixed,
                                      const std::vector<SweepParameter>& parameters, int runs);

}  // namespace netlab::netsim
