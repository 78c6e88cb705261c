#pragma once
// The command tests' small shot (tests/app/cli/small_shot.h) as the window's tests film it: made
// to last longer, simulated, coloured and rendered by the netlab command.

#include <fstream>
#include <sstream>
#include <string>

#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {

// The small shot's scenario lasting `seconds` instead of 0.06 s.
inline std::string SmallShotLasting(double seconds) {
  std::string scenario = kSmallShotScenario;
  const std::string from = "duration: 0.06";
  std::ostringstream to;
  to << "duration: " << seconds;
  return scenario.replace(scenario.find(from), from.size(), to.str());
}

// `scenario` written to DIR/shot.yaml, simulated into DIR/sim.h5, its net coloured into
// DIR/coloring.yaml (6 x 6 knots) and rendered into DIR/shot, frames 0..last_frame, without
// calibration images (`render_options`: more of netlab render's, e.g. "--scale 0.25"). The
// first step that fails, or the render's result.
inline NetlabResult FilmSmallShot(const std::string& dir, const std::string& scenario,
                                  int last_frame, const std::string& render_options = "") {
  std::ofstream(dir + "/shot.yaml") << scenario;
  for (const std::string& step :
       {"simulate " + dir + "/shot.yaml --out " + dir + "/sim.h5 --quiet",
        "color-net --knots 6x6 --out " + dir + "/coloring.yaml --quiet"}) {
    NetlabResult r = RunNetlab(step);
    if (r.status != 0) return r;
  }
  return RunNetlab("render --sim " + dir + "/sim.h5 --out " + dir +
                   "/shot --frames 0:" + std::to_string(last_frame) + " " + render_options +
                   " --calibration-views 0 --coloring " + dir + "/coloring.yaml --quiet");
}

}  // namespace netlab::testing
