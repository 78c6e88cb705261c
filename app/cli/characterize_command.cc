// netlab characterize TEST.yaml --out material.yaml [--json]

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/command_line/command_line.h"
#include "common/errors.h"
#include "common/output_paths.h"
#include "libnetsim/characterization/bench_file.h"
#include "libnetsim/characterization/characterize.h"
#include "libnetsim/characterization/material_file.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab characterize TEST.yaml --out MATERIAL.yaml [--json]\n\n"
    "Fits one bench test of a thread (docs/characterize.md) and writes the material parameters\n"
    "it measures, each with its standard uncertainty and the test it came from:\n"
    "  tensile     force-extension cycle: stretch_stiffness (linear at low force) and\n"
    "              stretch_damping (Kelvin-Voigt, from the hysteresis)\n"
    "  cantilever  shape or tip deflection under its own weight: bend_stiffness (the heavy\n"
    "              elastica); with a tip oscillation: bend_damping\n"
    "  torsion     torsion pendulum's angle series: twist_stiffness and twist_damping\n"
    "  weighing    (a block in any test) linear_density\n"
    "MATERIAL.yaml holds the scenario's `materials` block plus an `uncertainty` block (the prior\n"
    "of `netlab fit`). A summary goes to stdout.\n\n"
    "options:\n"
    "  --out FILE   the material file (written to FILE.partial, renamed when complete)\n"
    "  --json       print one JSON object on stdout as the last output: material, test,\n"
    "               parameters {key: {value, sigma, test, source}}, fit {residual RMS, points,\n"
    "               frequency_hz, damping_ratio, ...}\n\n"
    "exit status: 0 fitted, 1 bad test file or a series that cannot be fitted (the error names\n"
    "the file, line and key), 2 usage error.\n";

void PrintJson(const netsim::Characterization& c, const std::string& out) {
  JsonWriter json;
  json.BeginObject();
  json.Key("material").String(c.material);
  json.Key("test").String(c.test);
  json.Key("source").String(c.source);
  json.Key("parameters").BeginObject();
  for (const netsim::ParameterEstimate& e : c.estimates) {
    json.Key(e.key).BeginObject();
    json.Key("value").Number(e.value);
    json.Key("sigma").Number(e.sigma);
    json.Key("test").String(e.test);
    json.Key("source").String(e.source);
    json.EndObject();
  }
  json.EndObject();
  json.Key("fit").BeginObject();
  for (const netsim::FitDiagnostic& d : c.diagnostics) json.Key(d.name).Number(d.value);
  json.EndObject();
  json.Key("output").String(out);
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunCharacterize(const std::vector<std::string>& args) {
  return RunGuarded("characterize", [&] {
    const CommandLine cl(args, {"json", "help"}, {"out"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (cl.positional().size() != 1) throw UsageError("expected one TEST.yaml");
    const std::string out = cl.Required("out");
    CheckOutputPaths({{"test", cl.positional()[0]}}, {{"--out", out}});
    const netsim::BenchTest test = netsim::ReadBenchTest(cl.positional()[0]);
    const netsim::Characterization c = netsim::Characterize(test);
    // A fit that overflowed (forces of 1e300 N) would write .nan into the material file.
    for (const netsim::ParameterEstimate& e : c.estimates)
      if (!std::isfinite(e.value) || !std::isfinite(e.sigma))
        throw InputError(test.path + ": samples: cannot be fitted: " + e.key + " comes out as " +
                         std::to_string(e.value) + " +- " + std::to_string(e.sigma) +
                         " (are the samples in SI units, within a physical range?)");
    netsim::WriteMaterialFile(out, c.estimates,
                              "netlab characterize: " + netsim::BenchKindName(test.kind) +
                                  " test from " + test.path + "\nmaterial " + test.material +
                                  "; sigma: standard uncertainty, test: where the value came from");
    std::cout << c.BriefReport() << "wrote " << out << "\n";
    if (cl.Flag("json")) PrintJson(c, out);
    return 0;
  });
}

}  // namespace netlab::app
