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
// Several shots (`netlab fit A.yaml B.yaml --measured a.h5,b.h5`): the material and the drag are
// the same thread and cabin air in every shot, one parameter each; every other parameter is the
// shot's own, one per shot, named with the shot's number: 2:nets.0.velocity.0, 2:time_offset.
//
// A parameter is "identified" by the data when its posterior standard deviation is below half
// its reference spread (the prior's sigma when a prior is given, else `spread` below) and the cost
// is smooth enough along it for that sigma to mean something (shot_fit.h).

#include <string>
#include <vector>

#include "libnetsim/scenario/scenario_override.h"

namespace netlab::netsim {

struct FitParameter {
  enum class Kind { kScenario, kTimeOffset, kFrame };
  std::string name;  // the dotted path (kScenario), "time_offset" or "frame.wx" ...; "2:" first
                     // for a shot's own parameter when there are several shots
  Kind kind = Kind::kScenario;
  int frame_axis = 0;  // kFrame: 0..2 rotation vector (rad), 3..5 translation (m)
  bool log = false;    // fitted as ln(value)
  double start = 0.0;  // the value the fit starts from
  // Without a prior: the spread a value must be known to better than half of, to count as
  // identified (relative for log parameters: 0.5 = 50 %; else in the parameter's units).
  double spread = 0.0;
  std::string units;
  std::string path;  // the scenario's dotted path (kScenario): `name` without the shot's number
  int shot = -1;     // the shot it belongs to (0-based); -1: shared by every shot

  // The value of the fitted coordinate x (exp(x) for log parameters) and back.
  double Value(double x) const;
  double Coordinate(double value) const;
};

// The parameters `free_list` names (comma-separated, see above), their starts read from the
// scenario in `scenario_path` after `set`; time_offset starts at `time_offset_start`. InputError
// naming the entry for an unknown path, a section, a value that is not a number, a log parameter
// that is not positive, or a name given twice.
std::vector<FitParameter> ParseFreeParameters(const std::string& free_list,
                                              const std::vector<std::string>& scenario_paths,
                                              const std::vector<ScenarioOverride>& set,
                                              double time_offset_start);
// One shot.
std::vector<FitParameter> ParseFreeParameters(const std::string& free_list,
                                              const std::string& scenario_path,
                                              const std::vector<ScenarioOverride>& set,
                                              double time_offset_start);

// The scenario overrides that give shot `shot`'s scenario parameters (its own and the shared
// ones) the values of coordinates x (one per parameter, in order; time_offset and frame have
// none).
std::vector<ScenarioOverride> ScenarioOverrides(const std::vector<FitParameter>& parameters,
                                                const std::vector<double>& x, int shot = 0);

// Whether parameter p moves shot `shot`'s simulation or alignment.
inline bool Moves(const FitParameter& p, int shot) { return p.shot < 0 || p.shot == shot; }

}  // namespace netlab::netsim
