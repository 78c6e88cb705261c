// netlab color-net --knots ROWSxCOLS [--rule set|multiset|cyclic] [--distance D] [--radius R]
//                  [--palette FILE] --out coloring.yaml [--json]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <new>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/command_line/command_line.h"
#include "common/memory.h"
#include "common/output_paths.h"
#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/coloring/net_coloring.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab color-net --knots ROWSxCOLS [--rule set|multiset|cyclic] [--distance D]\n"
    "                        [--radius R] [--adjacent-distinct] [--palette FILE]\n"
    "                        --out coloring.yaml [--json]\n\n"
    "Colours the links of a square net so that every knot is identified by the colours of its\n"
    "2-4 links, with the fewest colours (docs/coloring.md).\n\n"
    "options:\n"
    "  --knots ROWSxCOLS    the net's knots, e.g. 11x11\n"
    "  --rule R             a knot's code: set (distinct colours), multiset (with repeats) or\n"
    "                       cyclic (the order around the knot, up to rotation and mirror);\n"
    "                       default set\n"
    "  --distance D         codes of knots of one degree differ in at least D link colours\n"
    "                       (2: one misread colour is detected, never taken for another knot)\n"
    "  --radius R           uniqueness only among knots within R links (0: the whole net)\n"
    "  --adjacent-distinct  the links of one knot all differ (visual separation)\n"
    "  --palette FILE       candidate yarn colours (name,r,g,b per line, sRGB): the colours\n"
    "                       used are chosen from them to differ most (CIEDE2000)\n"
    "                       (default: 16 common yarn dyes, when the colouring needs no more)\n"
    "  --background B       black, white or none: the scene behind the net, which the dyes must\n"
    "                       also differ from (default black)\n"
    "  --time-limit S       seconds at most (default 30). The search is budgeted by its own\n"
    "                       steps, so one net and options give one colouring every run; a run\n"
    "                       this limit cuts short says so and may differ between runs\n"
    "  --out FILE           coloring.yaml: the palette and every link's colour\n"
    "  --json               print one JSON summary object on stdout as the last output\n\n"
    "exit status: 0 coloured, 1 bad input or no colouring within the limits, 2 usage error.\n";

}  // namespace

int RunColorNet(const std::vector<std::string>& args) {
  return RunGuarded("color-net", [&] {
    const CommandLine cl(
        args, {"json", "quiet", "help", "adjacent-distinct"},
        {"knots", "rule", "distance", "radius", "palette", "out", "time-limit", "background"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    int rows = 0, cols = 0;
    cl.Knots("knots", &rows, &cols);
    const std::string out = cl.Required("out");
    recon::ColoringOptions options;
    const std::string rule = cl.Option("rule").value_or("set");
    if (!recon::ParseCodeRule(rule, &options.rule))
      throw UsageError("--rule expects set, multiset or cyclic, got '" + rule + "'");
    options.min_distance = cl.IntOption("distance", 1, 1, 4);
    options.radius = cl.IntOption("radius", 0, 0, 10000);
    options.adjacent_distinct = cl.Flag("adjacent-distinct");
    options.time_limit_s = cl.DoubleOption("time-limit", 30.0, 0.0, 86400.0);
    CheckOutputPaths({{"--palette", cl.Option("palette").value_or("")}}, {{"--out", out}});

    // Size before allocating: the search's memory grows with the net and, with a radius, with
    // the knots within it (docs/coloring.md).
    std::string what = "--knots " + std::to_string(rows) + "x" + std::to_string(cols);
    if (options.radius > 0) what += " --radius " + std::to_string(options.radius);
    const double needed = recon::EstimateColoringBytes(rows, cols, options);
    if (const std::string shortfall = MemoryShortfall(needed); !shortfall.empty())
      throw std::runtime_error(what + ": the colouring search " + shortfall);
    const auto start = std::chrono::steady_clock::now();
    recon::NetColoring coloring;
    try {
      coloring = recon::SolveColoring(rows, cols, options);
    } catch (const std::bad_alloc&) {
      throw std::runtime_error(what + ": the colouring search ran out of memory (estimated ~" +
                               FormatBytes(needed) + ")");
    }
    if (coloring.method == "infeasible")
      throw std::runtime_error(what + ": no palette of at most " +
                               std::to_string(options.max_colors) +
                               " colours can identify every "
                               "knot under rule " +
                               rule + ", distance " + std::to_string(options.min_distance) +
                               " (lower bound " + std::to_string(coloring.lower_bound) +
                               "); try --rule cyclic, a --radius, or a smaller --distance");
    std::vector<std::array<int, 3>> srgb;
    double min_delta_e = 0.0;
    // The physical palette: from the given candidates, else from common yarn dyes when there
    // are enough of them.
    std::vector<recon::Candidate> candidates;
    std::string source = "the default yarn dyes";
    if (const auto palette = cl.Option("palette")) {
      candidates = recon::LoadCandidates(*palette);
      source = *palette;
      if (static_cast<int>(candidates.size()) < coloring.colors)
        throw std::runtime_error(*palette + ": " + std::to_string(candidates.size()) +
                                 " candidate colours, the colouring needs " +
                                 std::to_string(coloring.colors));
    } else {
      candidates = recon::DefaultYarnCandidates();
      if (static_cast<int>(candidates.size()) < coloring.colors) {
        source = "none: " + std::to_string(coloring.colors) + " colours are more than the " +
                 std::to_string(candidates.size()) + " default yarn dyes (give --palette FILE)";
        candidates.clear();
      }
    }
    recon::Lighting lighting;  // white-balanced daylight
    const std::string background = cl.Option("background").value_or("black");
    if (background == "black")
      lighting.background = recon::Colour(0.f, 0.f, 0.f);
    else if (background == "white")
      lighting.background = recon::Colour(1.f, 1.f, 1.f);
    else if (background != "none")
      throw UsageError("--background expects black, white or none, got '" + background + "'");
    if (coloring.colors > 0 && !candidates.empty()) {
      const std::vector<int> chosen =
          recon::ChoosePalette(candidates, coloring.colors, lighting, &min_delta_e);
      coloring.palette_names.clear();
      for (int i : chosen) {
        coloring.palette_names.push_back(candidates[i].name);
        srgb.push_back({static_cast<int>(std::lround(candidates[i].srgb[0])),
                        static_cast<int>(std::lround(candidates[i].srgb[1])),
                        static_cast<int>(std::lround(candidates[i].srgb[2]))});
      }
    }
    if (coloring.colors == 0)
      throw std::runtime_error(
          what + ": no colouring found " +
          (coloring.time_limited ? "within --time-limit " + cl.Option("time-limit").value_or("30") +
                                       " s; try a larger --time-limit"
                                 : "within the search's budget; try a smaller --distance or a "
                                   "--radius"));
    coloring.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::string why;
    if (!recon::VerifyColoring(coloring, &why))
      throw std::runtime_error("internal error: the colouring fails verification: " + why);
    recon::WriteColoring(out, coloring, srgb);
    if (!cl.Flag("quiet")) {
      char delta[32];
      std::snprintf(delta, sizeof delta, "%.1f", min_delta_e);
      const std::string dyes =
          srgb.empty() ? "dyes " + source
                       : "dyes from " + source + " (least CIEDE2000 difference " + delta + ")";
      std::string notes;
      if (coloring.exact_skipped)
        notes += "; no exact search (more than " + std::to_string(recon::kExactSearchMaxKnots) +
                 " knots)";
      if (coloring.time_limited) notes += "; cut short by --time-limit, so another run may differ";
      std::fprintf(stderr,
                   "%dx%d knots, rule %s, distance %d, radius %d%s: %d colours (lower bound %d, "
                   "%s, %s) in %.2f s%s; %s; written to %s\n",
                   rows, cols, recon::CodeRuleName(options.rule).c_str(), options.min_distance,
                   options.radius, options.adjacent_distinct ? ", adjacent distinct" : "",
                   coloring.colors, coloring.lower_bound,
                   coloring.optimal ? "optimal" : "not proven optimal", coloring.method.c_str(),
                   coloring.wall_s, notes.c_str(), dyes.c_str(), out.c_str());
    }
    if (cl.Flag("json")) {
      JsonWriter json;
      json.BeginObject();
      json.Key("knots").String(std::to_string(rows) + "x" + std::to_string(cols));
      json.Key("colors").Int(coloring.colors);
      json.Key("lower_bound").Int(coloring.lower_bound);
      json.Key("optimal").Bool(coloring.optimal);
      json.Key("method").String(coloring.method);
      json.Key("rule").String(recon::CodeRuleName(options.rule));
      json.Key("min_distance").Int(options.min_distance);
      json.Key("radius").Int(options.radius);
      json.Key("adjacent_distinct").Bool(options.adjacent_distinct);
      if (!srgb.empty()) json.Key("min_delta_e").Number(min_delta_e);
      json.Key("wall_s").Number(coloring.wall_s);
      json.Key("time_limited").Bool(coloring.time_limited);
      json.Key("exact_search").Bool(!coloring.exact_skipped);
      json.EndObject();
      std::cout << json.str() << std::endl;
    }
    return 0;
  });
}

}  // namespace netlab::app
