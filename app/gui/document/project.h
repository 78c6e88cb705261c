#pragma once
// The project file of the workstation (project.yaml): what one labeling job is made of. Paths
// are stored relative to the project file's folder (absolute ones stay absolute), so a project
// folder can be moved or copied whole.
//
//   netlab_project: 1
//   experiment: shot/experiment.yaml    # the four camera streams (recording/experiment.h)
//   rig: rig.yaml                       # the calibrated rig; its cameras include the experiment's
//   coloring: coloring.yaml             # optional: the yarn colours (netlab color-net)
//   target: sim.h5                      # optional: the target, so that the knots it hides are
//                                       # not listed missing: the bodies of a scenario (.yaml)
//                                       # or of a netlab simulate result (.h5), in the rig's
//                                       # world frame (a true rig, or one calibrated with the
//                                       # target's marker map)
//   labels: labels.h5                   # created on the first save when it does not exist
//   tracks: tracks.h5                   # optional: the labels triangulated (netlab triangulate
//                                       # --out; the simulation room writes it)
//   simulations: [sim.h5, sim_no_drag.h5]  # optional: netlab simulate results, scored against
//                                       # the tracks in the simulation room
//   scores:                             # optional: each simulation's score as netlab score
//     - {simulation: sim.h5, score: score_sim.h5, report: score_sim.html}  # --out, --report
//                                       # write them (the simulation room writes them)
//   fits: [fit_net.yaml]                # optional: netlab fit --out files (the room's fits)
//   net: {rows: 11, cols: 11, mesh: 0.1}  # the grid; mesh (m, knot to knot) optional; and
//                                       # knotless: true for a net without knot balls (Net B)
//   illumination: 0.85                  # optional: how brightly the yarns are lit, for the colour
//                                       # check (a white dye reads this of sensor white; netlab
//                                       # label's --illumination, default netlab render's 0.85)
//
// Without `net`, the grid is the colouring's. Bad input throws netlab::InputError naming the file,
// line and key.

#include <string>
#include <vector>

#include "libreconstruct/coloring/palette.h"

namespace netlab::gui {

// A simulation's score files: netlab score's --out and --report.
struct ProjectScore {
  std::string simulation, score, report;  // absolute; report "" when none
};

struct Project {
  std::string path;        // the project file itself (absolute)
  std::string experiment;  // absolute paths, resolved against the project's folder
  std::string rig;
  std::string coloring;  // "" when none
  std::string target;    // "" when none
  std::string labels;
  std::string tracks;                    // "" when none
  std::vector<std::string> simulations;  // absolute
  std::vector<ProjectScore> scores;      // absolute, one per simulation at most
  std::vector<std::string> fits;         // absolute
  int rows = 0, cols = 0;                // the net's knots
  double mesh_m = 0.0;                   // link length, m; 0: estimated by the engine
  bool knotless = false;  // no knot balls: an edge knot is where its links' colours change
  double illumination = recon::kRenderIllumination;  // the colour check's exposure (--illumination)

  int knots() const { return rows * cols; }
};

Project LoadProject(const std::string& path);
// Writes `project` to `path` (relative paths where the files lie under its folder) through
// "<path>.partial" and a rename; std::runtime_error when it cannot.
void SaveProject(const Project& project, const std::string& path);

// A project for an experiment: the other files absolute or relative to the working directory;
// the grid from `coloring` when rows/cols are 0. InputError when the colouring cannot be read
// and no grid is given.
Project MakeProject(const std::string& experiment, const std::string& rig,
                    const std::string& coloring, const std::string& labels, int rows, int cols);

}  // namespace netlab::gui
