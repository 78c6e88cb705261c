#include "libnetsim/scenario/scenario.h"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <tuple>

#include "common/memory.h"
#include "common/yaml_util.h"
#include "libnetsim/forces/bend_twist_force.h"
#include "libnetsim/forces/gravity_force.h"
#include "libnetsim/forces/rotating_frame_force.h"
#include "libnetsim/forces/segment_force.h"

namespace netlab::netsim {
namespace {

// The largest stiffness (EA in N, EI and GJ in N m^2) a material may have.
constexpr double kMaxStiffness = 1e12;

std::string Short(double v) {
  std::ostringstream os;
  os << std::setprecision(3) << v;
  return os.str();
}

Vector3d ToVector(const std::array<double, 3>& a) { return Vector3d(a[0], a[1], a[2]); }

std::string Resolve(const std::string& base_dir, const std::string& file) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || base_dir.empty()) return file;
  return (std::filesystem::path(base_dir) / p).string();
}

TimeSeries3 ReadSeries(const YamlMap& map, const std::string& base_dir) {
  const std::string file = Resolve(base_dir, map.String("file"));
  // A folder or a device (/dev/zero was read as one endless line for a minute, until memory
  // ran out) is named before it is read; no time series netlab reads is near 64 MiB.
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(file, error);
  if (std::filesystem::is_directory(status))
    map.Fail("file", file + ": is a folder, not a CSV time series");
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    map.Fail("file", file + ": not a regular file (a device?), not a CSV time series");
  if (std::filesystem::is_regular_file(status) &&
      std::filesystem::file_size(file, error) > (std::uintmax_t{64} << 20))
    map.Fail("file", file + ": more than 64 MiB; not a CSV time series netlab reads");
  try {
    return TimeSeries3::ReadCsv(file);
  } catch (const std::exception& e) {
    map.Fail("file", e.what());
  }
}

// The parts of a scenario parsed with knowledge of what came before (materials, rods, nets).
class Parser {
 public:
  Parser(std::string origin, std::string base_dir)
      : origin_(std::move(origin)), base_dir_(std::move(base_dir)) {}

  Scenario Parse(const YAML::Node& tree, const std::string& text) {
    YamlMap root(tree, origin_, "");
    root.AllowOnly({"name", "description", "duration", "output_interval", "integrator", "gravity",
                    "drag", "rotating_frame", "materials", "rods", "nets", "bodies", "loads",
                    "probes", "store_nodes"});
    Scenario s;
    s.text = text;
    s.name = root.String("name");
    s.description = root.String("description", "");
    s.duration = root.Positive("duration");
    s.output_interval = root.Positive("output_interval");
    if (s.output_interval > s.duration) root.Fail("output_interval", "is longer than duration");
    s.store_nodes = root.Bool("store_nodes", true);
    if (root.Has("integrator")) ParseIntegrator(root.Map("integrator"), &s);
    if (root.Has("gravity")) ParseGravity(root, &s);
    if (root.Has("drag")) ParseDrag(root.Map("drag"), &s);
    if (root.Has("rotating_frame")) ParseRotatingFrame(root.Map("rotating_frame"), &s);
    ParseMaterials(root.Map("materials"), &s);
    if (!root.Has("rods") && !root.Has("nets"))
      root.Fail(root.node(), "needs at least one of rods or nets");
    if (root.Has("rods")) ForEach(root, "rods", [&](const YamlMap& m) { ParseRod(m, &s); });
    if (root.Has("nets")) ForEach(root, "nets", [&](const YamlMap& m) { ParseNet(m, &s); });
    if (root.Has("bodies")) ForEach(root, "bodies", [&](const YamlMap& m) { ParseBody(m, &s); });
    if (root.Has("loads")) ForEach(root, "loads", [&](const YamlMap& m) { ParseLoad(m, &s); });
    if (root.Has("probes")) ParseProbes(root.Map("probes"), &s);
    return s;
  }

 private:
  template <typename F>
  void ForEach(const YamlMap& root, const std::string& key, F&& f) {
    const YAML::Node list = root.Get(key);
    if (!list.IsSequence()) root.Fail(key, "expected a list");
    for (size_t i = 0; i < list.size(); ++i)
      f(YamlMap(list[i], origin_, key + "[" + std::to_string(i) + "]"));
  }

  void ParseIntegrator(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"type", "dt", "safety", "rotational_inertia", "coupling_stiffness_ratio",
                 "contact_frequency_ratio", "kinetic_damping", "max_speed", "threads",
                 "stretching"});
    SimulationOptions& o = s->simulation;
    const std::string type = m.String("type", "explicit");
    if (!ParseIntegratorType(type, &o.integrator))
      m.Fail("type", "unknown integrator '" + type + "' (expected explicit, verlet or implicit)");
    if (m.Has("dt")) {
      const YAML::Node dt = m.Get("dt");
      if (dt.IsScalar() && dt.as<std::string>() == "auto") {
        o.dt = 0.0;
      } else {
        o.dt = m.Positive("dt");
      }
    }
    if (m.Has("safety")) {
      o.safety = m.Positive("safety");
      if (o.safety > 1.0) m.Fail("safety", "must be in (0, 1]");
    }
    const std::string inertia = m.String("rotational_inertia", "scaled");
    if (inertia != "scaled" && inertia != "physical")
      m.Fail("rotational_inertia", "expected scaled or physical, got '" + inertia + "'");
    o.scale_rotational_inertia = inertia == "scaled";
    s->model.coupling_stiffness_ratio =
        m.Positive("coupling_stiffness_ratio", s->model.coupling_stiffness_ratio);
    o.contact_frequency_ratio = m.Positive("contact_frequency_ratio", o.contact_frequency_ratio);
    if (o.contact_frequency_ratio > 1.0) m.Fail("contact_frequency_ratio", "must be in (0, 1]");
    const std::string stretching = m.String("stretching", "backward_euler");
    if (!ParseStretchingScheme(stretching, &o.stretching))
      m.Fail("stretching",
             "unknown stretching step '" + stretching + "' (expected backward_euler or sdirk2)");
    o.kinetic_damping = m.Bool("kinetic_damping", false);
    o.max_speed = m.Positive("max_speed", o.max_speed);
    o.threads = m.Int("threads", o.threads);
    if (o.threads < 1 || o.threads > 256) m.Fail("threads", "must be in 1..256");
    o.align_interval = 0.0;  // set from output_interval in BuildScenario
  }

  void ParseGravity(const YamlMap& root, Scenario* s) {
    const YAML::Node g = root.Get("gravity");
    if (g.IsSequence()) {
      s->gravity = ToVector(root.Vec3("gravity"));
    } else if (g.IsMap()) {
      const YamlMap m = root.Map("gravity");
      m.AllowOnly({"file"});
      s->gravity_series = ReadSeries(m, base_dir_);
    } else {
      root.Fail("gravity", "expected [gx, gy, gz] (m/s^2) or {file: gravity.csv}");
    }
  }

  void ParseDrag(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"air_density", "drag_coefficient", "tangential_coefficient"});
    DragOptions d;
    d.air_density = m.Positive("air_density", true);
    d.drag_coefficient = m.Positive("drag_coefficient", true);
    d.tangential_coefficient = m.Positive("tangential_coefficient", 0.0, true);
    s->drag = d;
  }

  void ParseRotatingFrame(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"angular_velocity", "file"});
    if (m.Has("angular_velocity") == m.Has("file"))
      m.Fail(m.node(), "give exactly one of angular_velocity [rad/s] or file (gyro CSV)");
    if (m.Has("file")) {
      s->frame_rotation_series = ReadSeries(m, base_dir_);
    } else {
      s->frame_rotation = ToVector(m.Vec3("angular_velocity"));
    }
  }

  void ParseMaterials(const YamlMap& materials, Scenario* s) {
    for (auto it = materials.node().begin(); it != materials.node().end(); ++it) {
      const std::string name = it->first.as<std::string>();
      const YamlMap m(it->second, origin_, "materials." + name);
      m.AllowOnly({"diameter", "linear_density", "stretch_stiffness", "stretch_damping",
                   "bend_stiffness", "bend_damping", "twist_stiffness", "twist_damping"});
      Material mat;
      mat.name = name;
      mat.diameter = m.Positive("diameter");
      mat.linear_density = m.Positive("linear_density");
      mat.stretch_stiffness = m.Positive("stretch_stiffness");
      mat.bend_stiffness = m.Positive("bend_stiffness");
      mat.twist_stiffness = m.Positive("twist_stiffness");
      mat.stretch_damping = m.Positive("stretch_damping", 0.0, true);
      mat.bend_damping = m.Positive("bend_damping", 0.0, true);
      mat.twist_damping = m.Positive("twist_damping", 0.0, true);
      // Past any cord or cable (a steel bar 1 m across has EA 1.6e11 N, EI 1e10 N m^2), the
      // forces and energies overflow: 1e300 ran under the implicit step with an elastic energy
      // of 7e273 J, called stable, and blew up at 1e308.
      for (const auto& [key, value, unit] : {std::tuple<const char*, double, const char*>{
                                                 "stretch_stiffness", mat.stretch_stiffness, " N"},
                                             {"bend_stiffness", mat.bend_stiffness, " N m^2"},
                                             {"twist_stiffness", mat.twist_stiffness, " N m^2"}})
        if (value > kMaxStiffness)
          m.Fail(key, Short(value) + unit + " is stiffer than any cord or cable (a steel bar " +
                          "1 m across has EA 1.6e11 N, EI 1e10 N m^2): at most " +
                          Short(kMaxStiffness));
      s->materials.push_back(mat);
    }
    if (s->materials.empty()) materials.Fail(materials.node(), "no materials defined");
  }

  int MaterialIndex(const YamlMap& m, const Scenario& s) {
    const std::string name = m.String("material");
    for (size_t i = 0; i < s.materials.size(); ++i)
      if (s.materials[i].name == name) return static_cast<int>(i);
    std::string known;
    for (const Material& mat : s.materials) known += (known.empty() ? "" : ", ") + mat.name;
    m.Fail("material", "unknown material '" + name + "' (defined: " + known + ")");
  }

  void CheckNewName(const YamlMap& m, const std::string& name) {
    for (const std::string& n : names_)
      if (n == name) m.Fail("name", "the name '" + name + "' is used twice");
    names_.push_back(name);
  }

  static Fixity ParseFixity(const YamlMap& m, const std::string& key) {
    const std::string v = m.String(key, "free");
    if (v == "free") return Fixity::kFree;
    if (v == "pinned") return Fixity::kPinned;
    if (v == "clamped") return Fixity::kClamped;
    m.Fail(key, "expected pinned, clamped or free, got '" + v + "'");
  }

  void ParseRod(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"name", "material", "start", "end", "segments", "fixed", "velocity", "tip"});
    RodSpec r;
    r.name = m.String("name");
    CheckNewName(m, r.name);
    r.material = MaterialIndex(m, *s);
    r.start = ToVector(m.Vec3("start"));
    r.end = ToVector(m.Vec3("end"));
    if ((r.end - r.start).norm() <= 0.0) m.Fail("end", "coincides with start");
    r.segments = m.Int("segments");
    if (r.segments < 1) m.Fail("segments", "must be >= 1");
    if (m.Has("fixed")) {
      const YamlMap f = m.Map("fixed");
      f.AllowOnly({"start", "end"});
      r.fix_start = ParseFixity(f, "start");
      r.fix_end = ParseFixity(f, "end");
    }
    if (m.Has("velocity")) r.velocity = ToVector(m.Vec3("velocity"));
    if (m.Has("tip")) {
      const YamlMap tip = m.Map("tip");
      tip.AllowOnly({"mass", "inertia"});
      r.tip_mass = tip.Positive("mass", 0.0, /*allow_zero=*/true);
      if (tip.Has("inertia")) r.tip_inertia = ToVector(tip.Vec3("inertia"));
      if (r.tip_inertia.minCoeff() < 0.0) tip.Fail("inertia", "must be >= 0 each");
    }
    s->rods.push_back(r);
  }

  void ParseNet(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"name", "material", "knots", "mesh", "segments_per_link", "center", "normal",
                 "x_axis", "knot_mass", "corner_mass", "corner_radius", "velocity",
                 "angular_velocity", "corner_velocities", "spread"});
    NetSpec n;
    n.name = m.String("name");
    CheckNewName(m, n.name);
    n.material = MaterialIndex(m, *s);
    const std::vector<int> knots = m.Ints("knots");
    if (knots.size() != 2 || knots[0] < 2 || knots[1] < 2)
      m.Fail("knots", "expected [rows, cols], each >= 2");
    n.rows = knots[0];
    n.cols = knots[1];
    n.mesh = m.Positive("mesh");
    n.segments_per_link = m.Int("segments_per_link", 1);
    if (n.segments_per_link < 1) m.Fail("segments_per_link", "must be >= 1");
    n.center = ToVector(m.Vec3("center"));
    if (m.Has("normal")) n.normal = ToVector(m.Vec3("normal"));
    if (!(n.normal.norm() > 0.0)) m.Fail("normal", "must be a non-zero vector");
    if (m.Has("x_axis")) n.x_axis = ToVector(m.Vec3("x_axis"));
    if (std::abs(n.x_axis.normalized().dot(n.normal.normalized())) > 1.0 - 1e-9) {
      // The default x axis may be parallel to a chosen normal: fall back to y.
      if (m.Has("x_axis")) m.Fail("x_axis", "is parallel to the normal");
      n.x_axis = Vector3d::UnitY();
    }
    n.knot_mass = m.Positive("knot_mass", 0.0, true);
    n.corner_mass = m.Positive("corner_mass", 0.0, true);
    n.corner_radius = m.Positive("corner_radius", 0.0, true);
    if (m.Has("velocity")) n.velocity = ToVector(m.Vec3("velocity"));
    if (m.Has("angular_velocity")) n.angular_velocity = ToVector(m.Vec3("angular_velocity"));
    if (m.Has("corner_velocities")) {
      const YAML::Node list = m.Get("corner_velocities");
      if (!list.IsSequence() || list.size() != 4)
        m.Fail("corner_velocities",
               "expected 4 velocities [[vx,vy,vz], ...] for the corners "
               "(0,0), (0,cols-1), (rows-1,0), (rows-1,cols-1)");
      for (size_t i = 0; i < 4; ++i) {
        YAML::Node holder;
        holder["v"] = list[i];
        n.corner_velocities[i] =
            ToVector(YamlMap(holder, origin_, m.Join("corner_velocities")).Vec3("v"));
      }
    }
    n.spread = m.Positive("spread", 1.0);
    if (n.spread > 1.0) m.Fail("spread", "must be in (0, 1]");
    if (n.spread < 1.0 && n.spread <= MinimumSpread(n.segments_per_link))
      m.Fail("spread", "links of " + std::to_string(n.segments_per_link) +
                           " segments fold to no less than " +
                           YamlMap::Number(MinimumSpread(n.segments_per_link)) +
                           " of their length (use more segments_per_link)");
    s->nets.push_back(n);
  }

  void ParseBody(const YamlMap& m, Scenario* s) {
    RigidBody b;
    b.name = m.String("name");
    const std::string shape = m.String("shape");
    if (shape == "sphere") {
      m.AllowOnly({"name", "shape", "center", "radius", "velocity", "friction", "stiffness",
                   "damping_ratio"});
      b.shape = RigidBody::Shape::kSphere;
      b.center = ToVector(m.Vec3("center"));
      b.radius = m.Positive("radius");
    } else if (shape == "box") {
      m.AllowOnly({"name", "shape", "center", "size", "orientation", "velocity", "friction",
                   "stiffness", "damping_ratio"});
      b.shape = RigidBody::Shape::kBox;
      b.center = ToVector(m.Vec3("center"));
      const Vector3d size = ToVector(m.Vec3("size"));
      if (!(size.minCoeff() > 0.0)) m.Fail("size", "every edge length must be > 0");
      b.half_extents = 0.5 * size;
      if (m.Has("orientation")) {
        const std::vector<double> q = m.Doubles("orientation");
        if (q.size() != 4) m.Fail("orientation", "expected a quaternion [x, y, z, w]");
        b.orientation = Quaterniond(q[3], q[0], q[1], q[2]);
        if (!(b.orientation.norm() > 0.0)) m.Fail("orientation", "must not be zero");
        b.orientation.normalize();
      }
    } else if (shape == "plane") {
      m.AllowOnly({"name", "shape", "point", "normal", "velocity", "friction", "stiffness",
                   "damping_ratio"});
      b.shape = RigidBody::Shape::kPlane;
      b.center = ToVector(m.Vec3("point"));
      b.normal = ToVector(m.Vec3("normal"));
      if (!(b.normal.norm() > 0.0)) m.Fail("normal", "must be a non-zero vector");
      b.normal.normalize();
    } else {
      m.Fail("shape", "unknown shape '" + shape + "' (expected sphere, box or plane)");
    }
    if (m.Has("velocity")) b.velocity = ToVector(m.Vec3("velocity"));
    b.friction = m.Positive("friction", 0.0, true);
    b.stiffness = m.Positive("stiffness", 0.0, true);
    b.damping_ratio = m.Positive("damping_ratio", b.damping_ratio, true);
    s->bodies.push_back(b);
  }

  // rod + node, or net + knot.
  NodeRef ParseNodeRef(const YamlMap& m, const Scenario& s) {
    NodeRef ref;
    if (m.Has("rod") == m.Has("net")) m.Fail(m.node(), "give exactly one of rod or net");
    if (m.Has("rod")) {
      const std::string name = m.String("rod");
      for (size_t i = 0; i < s.rods.size(); ++i)
        if (s.rods[i].name == name) ref.rod = static_cast<int>(i);
      if (ref.rod < 0) m.Fail("rod", "unknown rod '" + name + "'");
      const int last = s.rods[ref.rod].segments;
      const YAML::Node node = m.Get("node");
      if (!node.IsScalar()) m.Fail("node", "expected start, end or a node index");
      const std::string text = node.as<std::string>();
      if (text == "start") {
        ref.index = 0;
      } else if (text == "end") {
        ref.index = last;
      } else {
        ref.index = m.Int("node");
        if (ref.index < 0 || ref.index > last)
          m.Fail("node", "index " + std::to_string(ref.index) + " outside 0.." +
                             std::to_string(last) + " (or use start / end)");
      }
    } else {
      const std::string name = m.String("net");
      for (size_t i = 0; i < s.nets.size(); ++i)
        if (s.nets[i].name == name) ref.net = static_cast<int>(i);
      if (ref.net < 0) m.Fail("net", "unknown net '" + name + "'");
      const std::vector<int> knot = m.Ints("knot");
      const NetSpec& net = s.nets[ref.net];
      if (knot.size() != 2 || knot[0] < 0 || knot[0] >= net.rows || knot[1] < 0 ||
          knot[1] >= net.cols)
        m.Fail("knot", "expected [row, col] inside the " + std::to_string(net.rows) + " x " +
                           std::to_string(net.cols) + " grid");
      ref.row = knot[0];
      ref.col = knot[1];
    }
    return ref;
  }

  void ParseLoad(const YamlMap& m, Scenario* s) {
    m.AllowOnly({"type", "rod", "net", "node", "knot", "vector"});
    LoadSpec load;
    const std::string type = m.String("type");
    if (type == "force") {
      load.kind = PointLoad::Kind::kForce;
    } else if (type == "moment") {
      load.kind = PointLoad::Kind::kMoment;
    } else {
      m.Fail("type", "expected force or moment, got '" + type + "'");
    }
    load.where = ParseNodeRef(m, *s);
    if (load.kind == PointLoad::Kind::kMoment && load.where.net >= 0)
      m.Fail("net", "a moment needs a rod node (a knot has no orientation of its own)");
    load.vector = ToVector(m.Vec3("vector"));
    s->loads.push_back(load);
  }

  void ParseProbes(const YamlMap& probes, Scenario* s) {
    for (auto it = probes.node().begin(); it != probes.node().end(); ++it) {
      const std::string name = it->first.as<std::string>();
      const YamlMap m(it->second, origin_, "probes." + name);
      m.AllowOnly({"rod", "net", "node", "knot"});
      for (const ProbeSpec& p : s->probes)
        if (p.name == name) m.Fail(m.node(), "probe name used twice");
      s->probes.push_back(ProbeSpec{name, ParseNodeRef(m, *s)});
    }
  }

  std::string origin_;
  std::string base_dir_;
  std::vector<std::string> names_;
};

}  // namespace

std::string ReadScenarioText(const std::string& path) {
  return ReadYamlText(path, "scenario file");
}

Scenario LoadScenario(const std::string& path) {
  Scenario s = ParseScenario(ReadScenarioText(path), path,
                             std::filesystem::path(path).parent_path().string());
  s.source_path = path;
  return s;
}

Scenario ParseScenario(const std::string& text, const std::string& origin,
                       const std::string& base_dir) {
  return Parser(origin, base_dir).Parse(LoadYamlString(text, origin), text);
}

Scenario ParseScenarioTree(const YAML::Node& tree, const std::string& text,
                           const std::string& origin, const std::string& base_dir) {
  return Parser(origin, base_dir).Parse(tree, text);
}

int ResolveNode(const Model& model, const NodeRef& ref) {
  if (ref.rod >= 0) return model.rods[ref.rod].first_node + ref.index;
  return model.KnotNode(ref.net, ref.row, ref.col);
}

namespace {

// Sizes the model before building it: a net of 20000 x 20000 knots would overflow the model's
// 32-bit indices and ask for terabytes, and a std::bad_alloc says neither. A run holds ~810 bytes
// per segment (peak RSS of `netlab simulate` over Net A's net at 60 to 240 knots a side, nodes,
// frames, forces and the implicit solve included); 1 kB is asked for.
void CheckModelSize(const Scenario& s, const std::string& origin) {
  double segments = 0.0, nodes = 0.0, largest = 0.0;
  std::string largest_what;
  for (size_t i = 0; i < s.rods.size(); ++i) {
    const RodSpec& r = s.rods[i];
    segments += r.segments;
    nodes += r.segments + 1.0;
    if (r.segments > largest) {
      largest = r.segments;
      largest_what = "rods." + std::to_string(i) + " ('" + r.name +
                     "'): " + std::to_string(r.segments) + " segments";
    }
  }
  for (size_t i = 0; i < s.nets.size(); ++i) {
    const NetSpec& n = s.nets[i];
    std::ostringstream what;
    what << std::setprecision(3);
    const double knots = static_cast<double>(n.rows) * n.cols;
    const double links =
        static_cast<double>(n.rows) * (n.cols - 1) + static_cast<double>(n.cols) * (n.rows - 1);
    const double net_segments = links * n.segments_per_link;
    segments += net_segments;
    nodes += knots + links * (n.segments_per_link - 1);
    if (net_segments > largest) {
      largest = net_segments;
      what << "nets." << i << " ('" << n.name << "'): " << n.rows << "x" << n.cols << " knots, "
           << n.segments_per_link << " segments per link = " << net_segments << " segments";
      largest_what = what.str();
    }
  }
  constexpr double kIndexable = 2147483647.0;  // the model's 32-bit node and segment indices
  std::ostringstream os;
  os << std::setprecision(3);
  if (segments > kIndexable || nodes > kIndexable) {
    os << origin << ": " << largest_what << ": the model would have " << segments
       << " segments and " << nodes << " nodes, more than the " << kIndexable << " it can index";
    throw InputError(os.str());
  }
  constexpr double kBytesPerSegment = 1000.0;
  if (const std::string shortfall = MemoryShortfall(kBytesPerSegment * segments);
      !shortfall.empty()) {
    os << origin << ": " << largest_what << ": a model of " << segments << " segments "
       << shortfall;
    throw InputError(os.str());
  }
}

}  // namespace

std::pair<Model, State> BuildModel(const Scenario& s) {
  const std::string origin = s.source_path.empty() ? s.name : s.source_path;
  CheckModelSize(s, origin);
  ModelBuilder builder(s.model);
  try {
    for (const Material& m : s.materials) builder.AddMaterial(m);
    for (const RodSpec& r : s.rods) builder.AddRod(r);
    for (const NetSpec& n : s.nets) builder.AddNet(n);
    return std::move(builder).Build();
  } catch (const std::invalid_argument& e) {
    throw InputError(origin + ": " + e.what());
  }
}

BuiltScenario BuildScenario(const Scenario& s) {
  const std::string origin = s.source_path.empty() ? s.name : s.source_path;
  auto [model, state] = BuildModel(s);

  // The forces this scene uses, and only those.
  std::vector<std::unique_ptr<Force>> forces;
  const bool drag = s.drag && s.drag->air_density > 0.0 &&
                    (s.drag->drag_coefficient > 0.0 || s.drag->tangential_coefficient > 0.0);
  forces.push_back(std::make_unique<SegmentForce>(
      true, true, drag ? std::optional<DragOptions>(*s.drag) : std::nullopt));
  if (!model.bend_pairs.empty() || !model.anchors.empty())
    forces.push_back(std::make_unique<BendTwistForce>(model));
  if (s.gravity_series) {
    forces.push_back(std::make_unique<GravityForce>(*s.gravity_series));
  } else if (s.gravity && s.gravity->squaredNorm() > 0.0) {
    forces.push_back(std::make_unique<GravityForce>(*s.gravity));
  }
  if (s.frame_rotation_series) {
    forces.push_back(std::make_unique<RotatingFrameForce>(*s.frame_rotation_series));
  } else if (s.frame_rotation && s.frame_rotation->squaredNorm() > 0.0) {
    forces.push_back(std::make_unique<RotatingFrameForce>(*s.frame_rotation));
  }
  if (!s.loads.empty()) {
    std::vector<PointLoad> loads;
    for (const LoadSpec& spec : s.loads) {
      PointLoad load;
      load.kind = spec.kind;
      load.vector = spec.vector;
      const int node = ResolveNode(model, spec.where);
      if (spec.kind == PointLoad::Kind::kForce) {
        load.index = node;
      } else {
        // A moment acts on the segment starting at the node (the last one at the rod's end).
        const RodInfo& rod = model.rods[spec.where.rod];
        load.index = rod.first_segment + std::min(spec.where.index, rod.num_segments - 1);
      }
      loads.push_back(load);
    }
    forces.push_back(std::make_unique<PointLoadForce>(std::move(loads)));
  }
  if (!s.bodies.empty()) forces.push_back(std::make_unique<ContactForce>(s.bodies));

  BuiltScenario built;
  for (const Knot& k : model.knots) {
    built.knot_nodes.push_back(k.node);
    built.knot_grid.push_back({k.row, k.col});
    built.knot_net.push_back(k.net);
  }
  for (const NetInfo& n : model.nets) built.net_names.push_back(n.name);
  for (const ProbeSpec& p : s.probes) {
    built.probe_names.push_back(p.name);
    built.probe_nodes.push_back(ResolveNode(model, p.where));
  }
  SimulationOptions options = s.simulation;
  options.align_interval = s.output_interval;
  try {
    built.simulation = std::make_unique<Simulation>(std::move(model), std::move(state),
                                                    std::move(forces), options);
  } catch (const std::invalid_argument& e) {
    throw InputError(origin + ": " + e.what());
  }
  return built;
}

}  // namespace netlab::netsim
