// netlab: the experiment-side workstation for validating throw-net simulations.
// `netlab <subcommand> --help` documents each subcommand.

#include <cstdio>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/gui/gui_command.h"

namespace netlab::app {

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"calibrate", "calibrate the cameras into one world frame from target images", RunCalibrate},
      {"characterize", "material parameters with uncertainties from a bench test", RunCharacterize},
      {"color-net", "colour a net's yarns so every knot is known by its links' colours",
       RunColorNet},
      {"fit", "identify a shot's parameters from its measured tracks, with uncertainties", RunFit},
      {"gui", "the labeling workstation: four views, the tools, review, undo", gui::RunGui},
      {"ingest", "check the synchronized camera recordings or convert them to HDF5", RunIngest},
      {"label", "label the knots automatically from seed labels (Find Path, tracking)", RunLabel},
      {"render", "film a simulated shot with a virtual camera rig, with ground truth", RunRender},
      {"score", "score a simulation against measured knot tracks: error, d2, a verdict", RunScore},
      {"simulate", "run a Cosserat-rod net simulation from a scenario file", RunSimulate},
      {"sweep", "vary scenario parameters over a grid: runs, sensitivities, a report", RunSweep},
      {"triangulate", "3D knot tracks from 2D labels of calibrated cameras", RunTriangulate},
  };
  return commands;
}

namespace {

void PrintUsage(std::FILE* out) {
  std::fprintf(out,
               "usage: netlab <subcommand> [options]\n\n"
               "netlab calibrates the cameras of a throw-net experiment, helps label the net's\n"
               "knots, reconstructs their 3D tracks and scores simulations against them.\n\n"
               "subcommands:\n");
  for (const Command& c : Commands()) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(
      out,
      "\n`netlab <subcommand> --help` for the options of each.\n"
      "exit status, every subcommand: 0 done, 1 bad input or a failed run (the error names\n"
      "it), 2 usage error, 3 internal error (netlab's fault), 130 cancelled (Ctrl+C).\n");
}

}  // namespace
}  // namespace netlab::app

int main(int argc, char** argv) {
  using netlab::app::Commands;
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    netlab::app::PrintUsage(stderr);
    return 2;
  }
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    netlab::app::PrintUsage(stdout);
    return 0;
  }
  if (args[0] == "--version") {
    std::printf("netlab 0.1.0\n");
    return 0;
  }
  for (const auto& command : Commands())
    if (args[0] == command.name) return command.run({args.begin() + 1, args.end()});
  std::fprintf(stderr, "netlab: unknown subcommand '%s'\n\n", args[0].c_str());
  netlab::app::PrintUsage(stderr);
  return 2;
}
