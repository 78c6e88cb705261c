#pragma once
// The free parameters of `netlab fit`: what `--free` names, expanded to scalars, with the start of
// each and how it is fitted.
//
//   materials.<name>.<key>, drag.<key>   a positive scale: fitted as ln(value)
//   any other scalar of the scenario     e.g. nets.0.corner_mass, fitted as is
//   a list of numbers                    one parameter per item: nets.0.velocity ->
//                                        nets.0.velocity.0 .. .2 (lists of lists recursively:
//                                        nets.0.corner_velocities.2.1)
//   time_offset                          s, t_sim = t_meas + time_offset (the launch time)
//   frame                                the rigid correction x_meas = Exp(w) x_sim + t:
//                                        frame.wx .. frame.wz (rad), frame.tx .. frame.tz (m)
//
// A parameter is "identified" by the data when its posterior standard deviation is below half
// its reference spread: the prior's sigma when a prior is given, else `spread` below.

#include <string>
#include <vector>

#include "libnetsim/scenario/scenario_override.h"

namespace netlab::netsim {

struct FitParameter {
  enum class Kind { kScenario, kTimeOffset, kFrame };
  std::string name;   // the dotted path (kScenario), "time_offset" or "frame.wx" ...
  Kind kind = Kind::kScenario;
  int frame_axis = 0;  // kFrame: 0..2 rotation vector (rad), 3..5 translation (m)
  bool log = false;    // fitted as ln(value)
  double start = 0.0;  // the value the fit starts from
  // Without a prior: the spread a value must be known to better than half of, to count as
  // identified (relative for log parameters: 0.5 = 50 %; else in the parameter's units).
  double spread = 0.0;
  std::string units;

  // The value of the fitted coordinate x (exp(x) for log parameters) and back.
  double Value(double x) const;
  double Coordinate(double value) const;
};

// The parameters `free_list` names (comma-separated, see above), their starts read from the
// scenario in `scenario_path` after `set`; time_offset starts at `time_offset_start`. InputError
// naming the entry for an unknown path, a section, a value that is not a number, a log parameter
// that is not positive, or a name given twice.
std::vector<FitParameter> ParseFreeParameters(const std::string& free_list,
                                              const std::string& scenario_path,
                                              const std::vector<ScenarioOverride>& set,
                                              double time_offset_start);

// The scenario overrides that give the scenario parameters the values of coordinates x (one per
// parameter, in order; time_offset and frame have none).
std::vector<ScenarioOverride> ScenarioOverrides(const std::vector<FitParameter>& parameters,
                                                const std::vector<double>& x);

}  // namespace netlab::netsim
