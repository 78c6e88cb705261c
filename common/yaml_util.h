#pragma once
// Checked access to YAML files that people edit (scenarios, experiments, boards). Every error names
// the file, the line and the key path, and what was expected:
//   scenarios/pendulum.yaml:14: materials.pp_yarn.bend_stiffness: must be > 0 (got -1)
//
//   YamlMap root(YAML::LoadFile(path), path, "");
//   root.AllowOnly({"name", "duration"});
//   double duration = root.Double("duration");

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdio>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace netlab {

// A bad input file: the message names file, line and key.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Loads a YAML file; syntax errors and missing files become InputError with file and line.
inline YAML::Node LoadYamlFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
}

inline YAML::Node LoadYamlString(const std::string& text, const std::string& origin) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(origin + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " +
                     e.msg);
  }
}

class YamlMap {
 public:
  // `path` is the dotted key path of `node` in its file ("" for the root).
  YamlMap(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
    if (!node_.IsMap()) {
      if (node_.IsNull() && path_.empty()) throw InputError(file_ + ": file is empty");
      Fail(node_, "expected a mapping of keys");
    }
  }

  const YAML::Node& node() const { return node_; }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

  // Throws InputError at the first key not in `allowed`, naming it and listing the allowed ones.
  void AllowOnly(std::initializer_list<std::string_view> allowed) const {
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      const std::string key = it->first.as<std::string>();
      bool ok = false;
      for (std::string_view a : allowed) ok = ok || key == a;
      if (ok) continue;
      std::string list;
      for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      throw InputError(Location(it->first) + Join(key) + ": unknown key (allowed: " + list + ")");
    }
  }

  bool Has(const std::string& key) const { return static_cast<bool>(node_[key]); }

  YAML::Node Get(const std::string& key) const {
    YAML::Node value = node_[key];
    if (!value) throw InputError(Location(node_) + Join(key) + ": missing (required)");
    return value;
  }

  YamlMap Map(const std::string& key) const { return YamlMap(Get(key), file_, Join(key)); }

  double Double(const std::string& key) const { return ToDouble(Get(key), Join(key)); }
  double Double(const std::string& key, double fallback) const {
    return Has(key) ? Double(key) : fallback;
  }
  // A value that must be > 0 (or >= 0 with allow_zero).
  double Positive(const std::string& key, bool allow_zero = false) const {
    const double v = Double(key);
    if (!(allow_zero ? v >= 0.0 : v > 0.0)) Fail(key, std::string("must be ") + (allow_zero ? ">= 0" : "> 0") + " (got " + Number(v) + ")");
    return v;
  }
  double Positive(const std::string& key, double fallback, bool allow_zero = false) const {
    return Has(key) ? Positive(key, allow_zero) : fallback;
  }
  int Int(const std::string& key) const { return ToInt(Get(key), Join(key)); }
  int Int(const std::string& key, int fallback) const { return Has(key) ? Int(key) : fallback; }
  bool Bool(const std::string& key, bool fallback) const {
    if (!Has(key)) return fallback;
    try {
      return Get(key).as<bool>();
    } catch (const YAML::Exception&) {
      Fail(key, "expected true or false");
    }
  }
  std::string String(const std::string& key) const {
    const YAML::Node value = Get(key);
    if (!value.IsScalar()) Fail(key, "expected a string");
    return value.as<std::string>();
  }
  std::string String(const std::string& key, const std::string& fallback) const {
    return Has(key) ? String(key) : fallback;
  }
  std::array<double, 3> Vec3(const std::string& key) const {
    const std::vector<double> v = Doubles(key);
    if (v.size() != 3) Fail(key, "expected 3 numbers [x, y, z], got " + std::to_string(v.size()));
    return {v[0], v[1], v[2]};
  }
  std::vector<double> Doubles(const std::string& key) const {
    const YAML::Node value = Get(key);
    if (!value.IsSequence()) Fail(key, "expected a list of numbers");
    std::vector<double> out;
    for (size_t i = 0; i < value.size(); ++i)
      out.push_back(ToDouble(value[i], Join(key) + "[" + std::to_string(i) + "]"));
    return out;
  }
  std::vector<int> Ints(const std::string& key) const {
    const YAML::Node value = Get(key);
    if (!value.IsSequence()) Fail(key, "expected a list of integers");
    std::vector<int> out;
    for (size_t i = 0; i < value.size(); ++i)
      out.push_back(ToInt(value[i], Join(key) + "[" + std::to_string(i) + "]"));
    return out;
  }

  // "file:line: " of the value at `key` (or of the map when the key is absent).
  std::string Where(const std::string& key) const {
    const YAML::Node value = node_[key];
    return Location(value ? value : node_) + Join(key);
  }
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const {
    throw InputError(Where(key) + ": " + message);
  }
  [[noreturn]] void Fail(const YAML::Node& at, const std::string& message) const {
    throw InputError(Location(at) + (path_.empty() ? std::string("(root)") : path_) + ": " +
                     message);
  }
  std::string Join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  std::string Location(const YAML::Node& at) const {
    const YAML::Mark mark = at.Mark();
    return file_ + (mark.line >= 0 ? ":" + std::to_string(mark.line + 1) : std::string()) + ": ";
  }

  static std::string Number(double v) {
    std::string s = std::to_string(v);
    if (std::abs(v) < 1e-3 && v != 0.0) {
      char buffer[32];
      std::snprintf(buffer, sizeof(buffer), "%g", v);
      s = buffer;
    }
    return s;
  }

 private:
  double ToDouble(const YAML::Node& value, const std::string& what) const {
    if (!value.IsScalar())
      throw InputError(Location(value) + what + ": expected a number");
    double v;
    try {
      v = value.as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(Location(value) + what + ": expected a number, got '" +
                       value.as<std::string>() + "'");
    }
    if (!std::isfinite(v)) throw InputError(Location(value) + what + ": must be finite");
    return v;
  }
  int ToInt(const YAML::Node& value, const std::string& what) const {
    const double v = ToDouble(value, what);
    if (v != std::floor(v) || std::abs(v) > 1e9)
      throw InputError(Location(value) + what + ": expected an integer, got " + Number(v));
    return static_cast<int>(v);
  }

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

}  // namespace netlab
