// netlab calibrate --board BOARD --images NAME=GLOB [--images NAME=GLOB ...] --out rig.yaml
//                  [--json] [--fix-intrinsics rig.yaml] [--rational] [--truth rig.yaml] [--quiet]

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <optional>

#include "app/cli/commands.h"
#include "app/cli/json_writer.h"
#include "app/cli/progress_bar.h"
#include "app/command_line/command_line.h"
#include "calibration/calibrate.h"
#include "calibration/rig_compare.h"
#include "common/output_paths.h"

namespace netlab::app {
namespace {

constexpr char kHelp[] =
    "usage: netlab calibrate --board BOARD --images NAME=GLOB [--images NAME=GLOB ...]\n"
    "                        --out rig.yaml [--json] [--fix-intrinsics rig.yaml] [--rational]\n"
    "                        [--truth rig.yaml]\n\n"
    "Calibrates the cameras into one world frame from images of a target (docs/calibration.md).\n"
    "Images are matched across cameras by their sorted order (the frame index).\n\n"
    "BOARD:\n"
    "  chessboard:COLSxROWS:SQUARE               inner corners (odd x even), square in m\n"
    "  charuco:COLSxROWS:SQUARE:MARKER:DICT      squares, lengths in m, e.g. DICT_5X5_100\n"
    "  FILE.yaml                                 a board, a double-sided foil or a marker map\n\n"
    "options:\n"
    "  --images NAME=GLOB     a camera and its images (repeat per camera; quote the glob)\n"
    "  --out FILE             rig file, OpenCV FileStorage YAML (written via FILE.partial)\n"
    "  --fix-intrinsics FILE  keep the intrinsics of the cameras in this rig file\n"
    "  --rational             estimate the rational distortion terms k4..k6 too\n"
    "  --truth FILE           the true rig (synthetic experiments): compare the calibrated rig\n"
    "                         with it after a rigid alignment of the world frames: per camera\n"
    "                         centre (m), rotation (deg), fx, fy, cx, cy and image errors (px),\n"
    "                         and the scale error; on stderr, and as \"truth\" with --json.\n"
    "                         Cameras match by name; true ones not calibrated are ignored\n"
    "  --json                 print one JSON summary object on stdout as the last output\n"
    "  --quiet                no progress on stderr\n";

// The "truth" object of the --json summary.
void WriteTruthJson(JsonWriter& json, const calib::RigComparison& comparison) {
  json.BeginObject();
  json.Key("cameras").BeginArray();
  for (const calib::CameraComparison& c : comparison.cameras) {
    json.BeginObject();
    json.Key("name").String(c.name);
    json.Key("centre_error_m").Number(c.centre_error_m);
    json.Key("rotation_error_deg").Number(c.rotation_error_deg);
    json.Key("fx_error_px").Number(c.fx_error_px);
    json.Key("fy_error_px").Number(c.fy_error_px);
    json.Key("cx_error_px").Number(c.cx_error_px);
    json.Key("cy_error_px").Number(c.cy_error_px);
    json.Key("image_error_rms_px").Number(c.image_error_rms_px);
    json.Key("image_error_max_px").Number(c.image_error_max_px);
    json.EndObject();
  }
  json.EndArray();
  json.Key("max_centre_error_m").Number(comparison.max_centre_error_m());
  json.Key("max_rotation_error_deg").Number(comparison.max_rotation_error_deg());
  json.Key("scale_error").Number(comparison.scale_error);
  json.EndObject();
}

// `comparison`: with --truth, else null.
void PrintJson(const calib::CalibrationResult& result, const calib::RigComparison* comparison) {
  const calib::CalibrationSummary& s = result.summary;
  JsonWriter json;
  json.BeginObject();
  json.Key("rms_px").Number(s.rms_px);
  json.Key("points").Int(s.observations);
  json.Key("outliers").Int(s.outliers);
  json.Key("cameras").BeginArray();
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    const calib::CameraReport& r = s.cameras[c];
    const calib::CameraIntrinsics& k = result.rig.cameras[c].intrinsics;
    json.BeginObject();
    json.Key("name").String(r.name);
    json.Key("rms_px").Number(r.rms_px);
    json.Key("views").Int(r.views);
    json.Key("fx").Number(k.fx);
    json.Key("fy").Number(k.fy);
    json.Key("cx").Number(k.cx);
    json.Key("cy").Number(k.cy);
    json.Key("coverage").Number(r.coverage);
    json.Key("centre_sigma_m").Number(r.position_sigma_m);
    json.EndObject();
  }
  json.EndArray();
  json.Key("baselines").BeginObject();
  for (const calib::PairCheck& p : s.pairs) json.Key(p.a + "-" + p.b).Number(p.baseline_m);
  json.EndObject();
  json.Key("metric_check").BeginArray();
  for (const calib::PairCheck& p : s.pairs) {
    if (p.segments == 0) continue;
    json.BeginObject();
    json.Key("pair").String(p.a + "-" + p.b);
    json.Key("segments").Int(p.segments);
    json.Key("mean_length_mm").Number(p.mean_length_mm);
    json.Key("nominal_length_mm").Number(p.nominal_length_mm);
    json.Key("rms_error_mm").Number(p.rms_error_mm);
    json.EndObject();
  }
  json.EndArray();
  json.Key("warnings").BeginArray();
  for (const std::string& w : s.warnings) json.String(w);
  json.EndArray();
  json.Key("wall_s").Number(s.wall_s);
  if (comparison != nullptr) {
    json.Key("truth");
    WriteTruthJson(json, *comparison);
  }
  json.EndObject();
  std::cout << json.str() << std::endl;
}

}  // namespace

int RunCalibrate(const std::vector<std::string>& args) {
  return RunGuarded("calibrate", [&] {
    const CommandLine cl(args, {"json", "quiet", "help", "rational"},
                         {"board", "images", "out", "fix-intrinsics", "truth"});
    if (cl.Flag("help")) {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (!cl.positional().empty())
      throw UsageError("unexpected argument '" + cl.positional()[0] + "'");
    const std::string out = cl.Required("out");
    const auto target = calib::CalibrationTarget::Parse(cl.Required("board"));
    const auto start = std::chrono::steady_clock::now();

    std::vector<std::string> names;
    std::vector<std::vector<std::string>> files;
    for (const std::string& spec : cl.Options("images")) {
      const size_t eq = spec.find('=');
      if (eq == std::string::npos || eq == 0)
        throw UsageError("--images expects NAME=GLOB, got '" + spec + "'");
      const std::string name = spec.substr(0, eq), pattern = spec.substr(eq + 1);
      if (std::find(names.begin(), names.end(), name) != names.end())
        throw UsageError("camera '" + name + "' given twice");
      std::vector<std::string> matched = calib::ImagesMatching(pattern);
      if (matched.empty())
        throw std::runtime_error("--images " + spec + ": the pattern matches no file");
      names.push_back(name);
      files.push_back(std::move(matched));
    }
    if (names.empty()) throw UsageError("--images NAME=GLOB is required (once per camera)");
    // Before any work: the rig is not written over an image, the board file or a rig read.
    std::vector<NamedPath> inputs = {{"--board", cl.Required("board")},
                                     {"--fix-intrinsics", cl.Option("fix-intrinsics").value_or("")},
                                     {"--truth", cl.Option("truth").value_or("")}};
    for (size_t c = 0; c < names.size(); ++c)
      for (const std::string& file : files[c]) inputs.push_back({"--images " + names[c], file});
    CheckOutputPaths(inputs, {{"--out", out}});

    calib::CalibrationOptions options;
    options.rational = cl.Flag("rational");
    if (const auto fixed = cl.Option("fix-intrinsics")) {
      const calib::Rig known = calib::ReadRig(*fixed);
      for (const std::string& name : names) {
        const int i = known.Find(name);
        if (i < 0) throw std::runtime_error(*fixed + ": no camera named '" + name + "'");
        options.fixed_intrinsics[name] = known.cameras[i].intrinsics;
      }
    }

    // The true rig, restricted to the calibrated cameras in their order; read before the slow
    // part so that a wrong file fails at once.
    std::optional<calib::Rig> truth;
    if (const auto path = cl.Option("truth")) {
      const calib::Rig all = calib::ReadRig(*path);
      truth.emplace();
      for (const std::string& name : names) {
        const int i = all.Find(name);
        if (i < 0) throw std::runtime_error(*path + ": no camera named '" + name + "'");
        truth->cameras.push_back(all.cameras[i]);
      }
    }

    ProgressBar bar("calibrate", !cl.Flag("quiet"));
    const calib::CalibrationInput input =
        calib::DetectInImages(names, files, target, bar.Reporter(), 2);
    bar.Break();
    calib::CalibrationResult result = calib::CalibrateRig(target, input, options);
    result.summary.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    calib::WriteRig(out, result.rig);
    if (!cl.Flag("quiet") || !cl.Flag("json")) std::cerr << result.summary.BriefReport();
    if (!cl.Flag("quiet")) std::cerr << "rig written to " << out << "\n";
    std::optional<calib::RigComparison> comparison;
    if (truth) {
      // A marker map puts the rig in the map's frame, the true world: nothing to align.
      comparison = calib::CompareRigs(result.rig, *truth,
                                      target.kind == calib::CalibrationTarget::Kind::kMarkerMap);
      if (!cl.Flag("quiet")) std::cerr << comparison->Report();
    }
    if (cl.Flag("json")) PrintJson(result, comparison ? &*comparison : nullptr);
    return 0;
  });
}

}  // namespace netlab::app
