#include "libnetsim/characterization/bench_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "common/yaml_util.h"

namespace netlab::netsim {
namespace {

std::string Line(const YAML::Node& node) {
  return node.Mark().line >= 0 ? ":" + std::to_string(node.Mark().line + 1) : "";
}

std::string Short(double v) {
  std::ostringstream os;
  os << std::setprecision(3) << v;
  return os.str();
}

// A series `key` of rows of `columns` numbers; with `timed`, the first column must increase.
Series ReadSeries(const YamlMap& m, const std::string& key, int columns, bool timed, int min_rows) {
  const YAML::Node list = m.Get(key);
  Series series;
  series.where = m.Where(key);
  if (!list.IsSequence())
    m.Fail(key, "expected a list of rows [" + std::to_string(columns) + " numbers each]");
  for (size_t i = 0; i < list.size(); ++i) {
    const YAML::Node row = list[i];
    const std::string at =
        m.file() + Line(row) + ": " + m.Join(key) + "[" + std::to_string(i) + "]";
    if (!row.IsSequence() || static_cast<int>(row.size()) != columns)
      throw InputError(at + ": expected a row of " + std::to_string(columns) + " numbers");
    std::vector<double> values;
    for (const YAML::Node& cell : row) {
      double v = NAN;
      try {
        v = cell.as<double>();
      } catch (const YAML::Exception&) {
        throw InputError(at + ": expected numbers, got '" + cell.as<std::string>("?") + "'");
      }
      if (!std::isfinite(v)) throw InputError(at + ": must be finite");
      values.push_back(v);
    }
    if (timed && !series.rows.empty() && !(values[0] > series.rows.back()[0]))
      throw InputError(at + ": time " + YamlMap::Number(values[0]) +
                       " does not increase (previous " + YamlMap::Number(series.rows.back()[0]) +
                       ")");
    series.rows.push_back(std::move(values));
  }
  if (series.size() < min_rows)
    m.Fail(key, "too few points: " + std::to_string(series.size()) + " (at least " +
                    std::to_string(min_rows) + " needed)");
  return series;
}

Weighing ReadWeighing(const YamlMap& m) {
  m.AllowOnly({"mass", "mass_sigma", "length", "length_sigma"});
  Weighing w;
  w.mass = m.Positive("mass");
  w.mass_sigma = m.Positive("mass_sigma", /*allow_zero=*/true);
  w.length = m.Positive("length");
  w.length_sigma = m.Positive("length_sigma", /*allow_zero=*/true);
  return w;
}

void ReadTensile(const YamlMap& m, TensileTest* t) {
  m.AllowOnly(
      {"test", "material", "description", "weighing", "gauge_length", "max_force", "samples"});
  t->gauge_length = m.Positive("gauge_length");
  if (m.Has("max_force")) t->max_force = m.Positive("max_force");
  t->samples = ReadSeries(m, "samples", 3, true, kMinTensileSamples);
}

void ReadCantilever(const YamlMap& m, CantileverTest* c) {
  m.AllowOnly({"test", "material", "description", "weighing", "length", "gravity", "shape",
               "tip_deflection", "oscillation"});
  c->length = m.Positive("length");
  c->gravity = m.Positive("gravity", 9.81);
  if (m.Has("shape") == m.Has("tip_deflection"))
    m.Fail("shape", "give either the shape (points along the thread) or tip_deflection");
  if (!m.Has("weighing"))
    m.Fail("weighing",
           "missing: the cantilever bends under its own weight, so its linear "
           "density is needed ({mass, mass_sigma, length, length_sigma})");
  if (m.Has("shape")) c->shape = ReadSeries(m, "shape", 2, false, kMinShapePoints);
  if (m.Has("tip_deflection")) {
    c->shape.where = m.Where("tip_deflection");  // errors of the fit name the deflection
    const YamlMap tip = m.Map("tip_deflection");
    tip.AllowOnly({"vertical", "sigma"});
    c->tip_deflection = tip.Positive("vertical");
    c->tip_deflection_sigma = tip.Positive("sigma");
    if (*c->tip_deflection >= c->length)
      tip.Fail("vertical", "must be below the length " + YamlMap::Number(c->length));
  }
  for (const std::vector<double>& p : c->shape.rows)
    if (std::hypot(p[0], p[1]) > 1.001 * c->length)
      m.Fail("shape",
             "a point lies farther from the clamp than the length " + YamlMap::Number(c->length));
  // A thread clamped horizontally hangs below the clamp and runs away from it: its angle below
  // the horizontal grows from 0 towards (never past) 90 degrees, so y never rises above 0 and x
  // never falls back. A shape that does either (y measured downward, the rows out of order, the
  // clamp at the other end) was fitted without a word. 2 % of the length allows for the
  // measurement's noise.
  const double slack = 0.02 * c->length;
  const YAML::Node rows = m.Has("shape") ? m.Get("shape") : YAML::Node();
  double farthest = 0.0;
  for (size_t i = 0; i < c->shape.rows.size(); ++i) {
    const double x = c->shape.rows[i][0], y = c->shape.rows[i][1];
    const std::string at =
        m.file() + Line(rows[i]) + ": " + m.Join("shape") + "[" + std::to_string(i) + "]: ";
    if (y > slack)
      throw InputError(at + "y " + Short(y) +
                       " m is above the clamp: y is up, and a thread clamped horizontally bends "
                       "down under its weight (give the drop as negative y)");
    if (x < farthest - slack)
      throw InputError(
          at + "x " + Short(x) +
          (farthest > 0.0 ? " m runs back towards the clamp (x " + Short(farthest) + " m before it)"
                          : " m is behind the clamp") +
          ": a thread hanging from a horizontal clamp runs away from it; give the "
          "points from the clamp to the tip, x away from the clamp");
    farthest = std::max(farthest, x);
  }
  if (m.Has("oscillation"))
    c->oscillation = ReadSeries(m, "oscillation", 2, true, kMinOscillationSamples);
}

void ReadTorsion(const YamlMap& m, TorsionTest* t) {
  m.AllowOnly({"test", "material", "description", "weighing", "length", "inertia", "inertia_sigma",
               "samples"});
  t->length = m.Positive("length");
  t->inertia = m.Positive("inertia");
  t->inertia_sigma = m.Positive("inertia_sigma", 0.0, /*allow_zero=*/true);
  t->samples = ReadSeries(m, "samples", 2, true, kMinOscillationSamples);
}

BenchTest ReadTree(const YAML::Node& tree, const std::string& origin) {
  const YamlMap root(tree, origin, "");
  BenchTest test;
  test.path = origin;
  test.source = std::filesystem::path(origin).filename().string();
  const std::string kind = root.String("test");
  test.material = root.String("material");
  if (test.material.empty()) root.Fail("material", "must not be empty");
  test.description = root.String("description", "");
  if (root.Has("weighing")) test.weighing = ReadWeighing(root.Map("weighing"));
  if (kind == "tensile") {
    test.kind = BenchKind::kTensile;
    ReadTensile(root, &test.tensile);
  } else if (kind == "cantilever") {
    test.kind = BenchKind::kCantilever;
    ReadCantilever(root, &test.cantilever);
  } else if (kind == "torsion") {
    test.kind = BenchKind::kTorsion;
    ReadTorsion(root, &test.torsion);
  } else {
    root.Fail("test", "expected tensile, cantilever or torsion, got '" + kind + "'");
  }
  return test;
}

std::string Format(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", v);
  return buffer;
}

void WriteSeries(std::ostream& out, const std::string& key, const std::string& columns,
                 const Series& series) {
  out << key << ":  # " << columns << "\n";
  for (const std::vector<double>& row : series.rows) {
    out << "  - [";
    for (size_t c = 0; c < row.size(); ++c) out << (c ? ", " : "") << Format(row[c]);
    out << "]\n";
  }
}

void WriteTestKeys(std::ostream& out, const BenchTest& t) {
  if (t.kind == BenchKind::kTensile) {
    out << "gauge_length: " << Format(t.tensile.gauge_length) << "  # m\n";
    if (t.tensile.max_force) out << "max_force: " << Format(*t.tensile.max_force) << "  # N\n";
    WriteSeries(out, "samples", "[time s, extension m, force N]", t.tensile.samples);
  } else if (t.kind == BenchKind::kCantilever) {
    const CantileverTest& c = t.cantilever;
    out << "length: " << Format(c.length) << "  # m\ngravity: " << Format(c.gravity)
        << "  # m/s^2\n";
    if (c.tip_deflection)
      out << "tip_deflection: {vertical: " << Format(*c.tip_deflection)
          << ", sigma: " << Format(*c.tip_deflection_sigma) << "}  # m\n";
    else
      WriteSeries(out, "shape", "[x m, y m] from the clamp, y up", c.shape);
    if (c.oscillation.size() > 0)
      WriteSeries(out, "oscillation", "[time s, tip y m]", c.oscillation);
  } else {
    out << "length: " << Format(t.torsion.length) << "  # m\ninertia: " << Format(t.torsion.inertia)
        << "  # kg m^2\n";
    if (t.torsion.inertia_sigma > 0)
      out << "inertia_sigma: " << Format(t.torsion.inertia_sigma) << "  # kg m^2\n";
    WriteSeries(out, "samples", "[time s, angle rad]", t.torsion.samples);
  }
}

}  // namespace

double Weighing::LinearDensitySigma() const {
  return LinearDensity() * std::hypot(mass_sigma / mass, length_sigma / length);
}

std::vector<double> Series::Column(int c) const {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const std::vector<double>& row : rows) out.push_back(row[c]);
  return out;
}

std::string BenchKindName(BenchKind kind) {
  switch (kind) {
    case BenchKind::kTensile: return "tensile";
    case BenchKind::kCantilever: return "cantilever";
    case BenchKind::kTorsion: return "torsion";
  }
  return "?";
}

BenchTest ReadBenchTest(const std::string& path) { return ReadTree(LoadYamlFile(path), path); }

BenchTest ParseBenchTest(const std::string& text, const std::string& origin) {
  return ReadTree(LoadYamlString(text, origin), origin);
}

std::string BenchTestText(const BenchTest& test, const std::string& comment) {
  std::ostringstream out;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  out << "test: " << BenchKindName(test.kind) << "\nmaterial: " << test.material << "\n";
  if (!test.description.empty()) out << "description: " << test.description << "\n";
  if (test.weighing) {
    const Weighing& w = *test.weighing;
    out << "weighing: {mass: " << Format(w.mass) << ", mass_sigma: " << Format(w.mass_sigma)
        << ", length: " << Format(w.length) << ", length_sigma: " << Format(w.length_sigma)
        << "}  # kg, m\n";
  }
  WriteTestKeys(out, test);
  return out.str();
}

}  // namespace netlab::netsim
