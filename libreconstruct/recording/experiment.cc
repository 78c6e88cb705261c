#include "libreconstruct/recording/experiment.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "common/files.h"
#include "common/yaml_util.h"

namespace netlab::recon {
namespace {

std::string Resolve(const std::string& base_dir, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || base_dir.empty()) return path;
  return (std::filesystem::path(base_dir) / p).string();
}

// A string as a YAML scalar, quoted where plain YAML would misread it ("%06d.tif", "a: b").
std::string Scalar(const std::string& text) {
  YAML::Emitter out;
  out << text;
  return out.c_str();
}

// A resolved path (absolute, or relative to the working folder) as an experiment file at `file`
// must spell it so that LoadExperiment resolves it back: relative to the file's folder when inside
// it, else absolute.
std::string PathFrom(const std::string& file, const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path target = fs::absolute(path).lexically_normal();
  const fs::path folder = fs::absolute(file).parent_path().lexically_normal();
  const fs::path relative = target.lexically_relative(folder);
  if (relative.empty() || *relative.begin() == "..") return target.string();
  return relative.string();
}

}  // namespace

std::string BlackLevelProblem(double black_level, int bit_depth) {
  // At or above the white level every pixel would correct to zero or less: no image is left.
  const double white = std::ldexp(1.0, bit_depth) - 1.0;
  if (black_level < white) return "";
  std::ostringstream os;
  os << black_level << " is " << (black_level > white ? "above" : "at") << " the " << bit_depth
     << "-bit white level " << white << " (no signal would remain)";
  return os.str();
}

int Experiment::Find(const std::string& camera) const {
  for (size_t i = 0; i < cameras.size(); ++i)
    if (cameras[i].name == camera) return static_cast<int>(i);
  return -1;
}

Experiment ParseExperiment(const std::string& text, const std::string& origin,
                           const std::string& base_dir) {
  const YamlMap root(LoadYamlString(text, origin), origin, "");
  root.AllowOnly({"experiment", "fps", "cameras"});
  Experiment e;
  e.path = origin;
  e.base_dir = base_dir;
  e.name = root.String("experiment");
  e.fps = root.Positive("fps");
  const YAML::Node list = root.Get("cameras");
  if (!list.IsSequence() || list.size() == 0) root.Fail("cameras", "expected a list of cameras");
  for (size_t i = 0; i < list.size(); ++i) {
    const YamlMap m(list[i], origin, "cameras[" + std::to_string(i) + "]");
    m.AllowOnly(
        {"name", "frames", "bayer", "timestamps", "bit_depth", "black_level", "white_balance"});
    CameraSpec c;
    c.name = m.String("name");
    if (e.Find(c.name) >= 0) m.Fail("name", "camera '" + c.name + "' is listed twice");
    c.frames = m.String("frames");
    const std::string bayer = m.String("bayer", "none");
    if (!ParseBayerPattern(bayer, &c.bayer))
      m.Fail("bayer", "expected RGGB, BGGR, GRBG, GBRG or none, got '" + bayer + "'");
    if (m.Has("timestamps")) c.timestamps = Resolve(base_dir, m.String("timestamps"));
    if (m.Has("bit_depth")) {
      const int depth = m.Int("bit_depth");
      if (depth != 8 && depth != 10 && depth != 12 && depth != 16)
        m.Fail("bit_depth", "expected 8, 10, 12 or 16, got " + std::to_string(depth));
      c.bit_depth = depth;
    }
    c.black_level = m.Positive("black_level", 0.0, true);
    if (m.Has("black_level")) c.black_level_where = m.Where("black_level");
    if (c.bit_depth) {
      if (const std::string why = BlackLevelProblem(c.black_level, *c.bit_depth); !why.empty())
        m.Fail("black_level", why);
    }
    if (m.Has("white_balance")) {
      const std::vector<double> wb = m.Doubles("white_balance");
      if (wb.size() != 3 || !(wb[0] > 0 && wb[1] > 0 && wb[2] > 0))
        m.Fail("white_balance", "expected three positive gains [r, g, b]");
      c.white_balance_rgb = {wb[0], wb[1], wb[2]};
    }
    e.cameras.push_back(c);
  }
  return e;
}

Experiment LoadExperiment(const std::string& path) {
  return ParseExperiment(ReadYamlText(path, "experiment file"), path,
                         std::filesystem::path(path).parent_path().string());
}

void WriteExperiment(const std::string& path, const Experiment& e) {
  std::ostringstream os;
  os << std::setprecision(10);
  os << "experiment: " << Scalar(e.name) << "\nfps: " << e.fps << "\ncameras:\n";
  for (const CameraSpec& c : e.cameras) {
    os << "  - name: " << Scalar(c.name) << "\n    frames: " << Scalar(c.frames)
       << "\n    bayer: " << BayerPatternName(c.bayer) << "\n";
    if (!c.timestamps.empty())
      os << "    timestamps: " << Scalar(PathFrom(path, c.timestamps)) << "\n";
    if (c.bit_depth) os << "    bit_depth: " << *c.bit_depth << "\n";
    if (c.black_level != 0.0) os << "    black_level: " << c.black_level << "\n";
    if (c.white_balance_rgb != std::array<double, 3>{1.0, 1.0, 1.0})
      os << "    white_balance: [" << c.white_balance_rgb[0] << ", " << c.white_balance_rgb[1]
         << ", " << c.white_balance_rgb[2] << "]\n";
  }
  WriteTextFile(path, os.str());
}

std::map<int, double> ReadTimestamps(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open timestamps file");
  std::map<int, double> times;
  std::string line;
  int number = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    double index, time;
    std::string extra;
    if (!(is >> index >> time) || (is >> extra)) {
      if (first) {  // a header line
        first = false;
        continue;
      }
      throw InputError(path + ":" + std::to_string(number) +
                       ": expected 'frame_index,time_s', got '" + line + "'");
    }
    first = false;
    if (index != std::floor(index) || !std::isfinite(time))
      throw InputError(path + ":" + std::to_string(number) +
                       ": frame index must be an integer "
                       "and the time finite");
    if (!times.emplace(static_cast<int>(index), time).second)
      throw InputError(path + ":" + std::to_string(number) + ": frame " +
                       std::to_string(static_cast<int>(index)) + " listed twice");
  }
  return times;
}

}  // namespace netlab::recon
