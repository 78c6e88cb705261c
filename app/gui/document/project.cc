#include "app/gui/document/project.h"

#include <filesystem>
#include <fstream>
#include <set>

#include "common/files.h"
#include "common/yaml_util.h"
#include "libreconstruct/coloring/net_coloring.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

std::string Resolve(const fs::path& folder, const std::string& file) {
  if (file.empty()) return "";
  const fs::path p(file);
  return (p.is_absolute() ? p : folder / p).lexically_normal().string();
}

// `file` relative to `folder` when it lies below it, else absolute.
std::string Relative(const fs::path& folder, const std::string& file) {
  if (file.empty()) return "";
  const fs::path rel = fs::absolute(file).lexically_normal().lexically_relative(folder);
  if (rel.empty() || *rel.begin() == "..") return fs::absolute(file).lexically_normal().string();
  return rel.string();
}

// A key given twice in a mapping: YAML readers keep one of them silently, so the project would
// name a file the person did not mean.
void RefuseDuplicateKeys(const YAML::Node& map, const std::string& file, const std::string& in) {
  std::set<std::string> seen;
  for (auto it = map.begin(); it != map.end(); ++it) {
    const std::string key = it->first.as<std::string>();
    if (!seen.insert(key).second)
      throw InputError(file + ":" + std::to_string(it->first.Mark().line + 1) + ": " + in + key +
                       ": given twice (keep one)");
  }
}

}  // namespace

Project LoadProject(const std::string& path) {
  const YamlMap root(LoadYamlFile(path), path, "");
  RefuseDuplicateKeys(root.node(), path, "");
  if (root.node()["net"] && root.node()["net"].IsMap())
    RefuseDuplicateKeys(root.node()["net"], path, "net.");
  root.AllowOnly({"netlab_project", "experiment", "rig", "coloring", "target", "labels", "net",
                  "illumination", "tracks", "simulations", "scores", "fits"});
  if (root.Int("netlab_project") != 1)
    throw InputError(root.Where("netlab_project") + ": version 1 expected");
  Project p;
  p.path = fs::absolute(path).lexically_normal().string();
  const fs::path folder = fs::path(p.path).parent_path();
  p.experiment = Resolve(folder, root.String("experiment"));
  p.rig = Resolve(folder, root.String("rig"));
  p.coloring = Resolve(folder, root.String("coloring", ""));
  p.target = Resolve(folder, root.String("target", ""));
  p.labels = Resolve(folder, root.String("labels"));
  p.tracks = Resolve(folder, root.String("tracks", ""));
  if (root.Has("simulations")) {
    const YAML::Node list = root.Get("simulations");
    if (!list.IsSequence())
      throw InputError(root.Where("simulations") +
                       ": a list of knot-track files expected ([sim.h5, sim_no_drag.h5])");
    for (const YAML::Node& item : list) {
      if (!item.IsScalar() || item.as<std::string>().empty())
        throw InputError(root.Where("simulations") + ": each entry must be a file name");
      p.simulations.push_back(Resolve(folder, item.as<std::string>()));
    }
  }
  if (root.Has("scores")) {
    const YAML::Node list = root.Get("scores");
    if (!list.IsSequence())
      throw InputError(root.Where("scores") +
                       ": a list of {simulation: sim.h5, score: score_sim.h5, report: "
                       "score_sim.html} expected");
    for (const YAML::Node& item : list) {
      if (!item.IsMap() || !item["simulation"] || !item["score"])
        throw InputError(root.Where("scores") +
                         ": each entry needs simulation and score ({simulation: sim.h5, score: "
                         "score_sim.h5, report: score_sim.html})");
      const YamlMap entry(item, path, "scores");
      entry.AllowOnly({"simulation", "score", "report"});
      p.scores.push_back({Resolve(folder, entry.String("simulation")),
                          Resolve(folder, entry.String("score")),
                          Resolve(folder, entry.String("report", ""))});
    }
  }
  if (root.Has("fits")) {
    const YAML::Node list = root.Get("fits");
    if (!list.IsSequence())
      throw InputError(root.Where("fits") + ": a list of netlab fit files expected ([fit.yaml])");
    for (const YAML::Node& item : list) {
      if (!item.IsScalar() || item.as<std::string>().empty())
        throw InputError(root.Where("fits") + ": each entry must be a file name");
      p.fits.push_back(Resolve(folder, item.as<std::string>()));
    }
  }
  if (root.Has("illumination")) {
    p.illumination = root.Positive("illumination", recon::kRenderIllumination, false);
    if (p.illumination > 100.0)
      throw InputError(root.Where("illumination") + ": " + std::to_string(p.illumination) +
                       " is not an exposure (a white dye reads 0.85 of sensor white under "
                       "netlab render's lights)");
  }
  if (root.Has("net")) {
    const YamlMap net = root.Map("net");
    net.AllowOnly({"rows", "cols", "mesh", "knotless"});
    p.rows = net.Int("rows");
    p.cols = net.Int("cols");
    p.mesh_m = net.Positive("mesh", 0.0, true);
    p.knotless = net.Bool("knotless", false);
    if (p.rows < 2 || p.cols < 2 || p.rows > 1000 || p.cols > 1000)
      throw InputError(net.Where("rows") + ": the net needs 2..1000 rows and columns (got " +
                       std::to_string(p.rows) + "x" + std::to_string(p.cols) + ")");
  } else if (!p.coloring.empty()) {
    const recon::NetColoring coloring = recon::ReadColoring(p.coloring);
    p.rows = coloring.rows, p.cols = coloring.cols;
  } else {
    throw InputError(root.Where("net") + ": the net's grid is needed (net: {rows, cols}) when " +
                     "there is no coloring");
  }
  return p;
}

void SaveProject(const Project& project, const std::string& path) {
  const fs::path folder = fs::absolute(path).lexically_normal().parent_path();
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "netlab_project" << YAML::Value << 1;
  out << YAML::Key << "experiment" << YAML::Value << Relative(folder, project.experiment);
  out << YAML::Key << "rig" << YAML::Value << Relative(folder, project.rig);
  if (!project.coloring.empty())
    out << YAML::Key << "coloring" << YAML::Value << Relative(folder, project.coloring);
  if (!project.target.empty())
    out << YAML::Key << "target" << YAML::Value << Relative(folder, project.target);
  out << YAML::Key << "labels" << YAML::Value << Relative(folder, project.labels);
  if (!project.tracks.empty())
    out << YAML::Key << "tracks" << YAML::Value << Relative(folder, project.tracks);
  if (!project.simulations.empty()) {
    out << YAML::Key << "simulations" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& s : project.simulations) out << Relative(folder, s);
    out << YAML::EndSeq;
  }
  if (!project.scores.empty()) {
    out << YAML::Key << "scores" << YAML::Value << YAML::BeginSeq;
    for (const ProjectScore& s : project.scores) {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "simulation" << YAML::Value << Relative(folder, s.simulation);
      out << YAML::Key << "score" << YAML::Value << Relative(folder, s.score);
      if (!s.report.empty())
        out << YAML::Key << "report" << YAML::Value << Relative(folder, s.report);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (!project.fits.empty()) {
    out << YAML::Key << "fits" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& f : project.fits) out << Relative(folder, f);
    out << YAML::EndSeq;
  }
  out << YAML::Key << "net" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "rows" << YAML::Value << project.rows;
  out << YAML::Key << "cols" << YAML::Value << project.cols;
  if (project.mesh_m > 0) out << YAML::Key << "mesh" << YAML::Value << project.mesh_m;
  if (project.knotless) out << YAML::Key << "knotless" << YAML::Value << true;
  out << YAML::EndMap;
  out << YAML::Key << "illumination" << YAML::Value << project.illumination;
  out << YAML::EndMap;
  const std::string partial = path + ".partial";
  {
    std::ofstream file(partial);
    file << out.c_str() << "\n";
    if (!file) throw std::runtime_error(path + ": cannot write " + partial);
  }
  RenameInto(partial, path);
}

Project MakeProject(const std::string& experiment, const std::string& rig,
                    const std::string& coloring, const std::string& labels, int rows, int cols) {
  Project p;
  p.experiment = fs::absolute(experiment).lexically_normal().string();
  p.rig = fs::absolute(rig).lexically_normal().string();
  p.coloring = coloring.empty() ? "" : fs::absolute(coloring).lexically_normal().string();
  p.labels = fs::absolute(labels).lexically_normal().string();
  p.rows = rows, p.cols = cols;
  if ((rows <= 0 || cols <= 0) && !coloring.empty()) {
    const recon::NetColoring c = recon::ReadColoring(coloring);
    p.rows = c.rows, p.cols = c.cols;
  }
  if (p.rows < 2 || p.cols < 2)
    throw InputError("the net's grid is unknown: give --coloring or --knots ROWSxCOLS");
  return p;
}

}  // namespace netlab::gui
