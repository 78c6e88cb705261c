#pragma once
// Checked access to YAML files that people edit (scenarios, experiments, boards). Every error names
// the file, the line and the key path, and what was expected:
//   scenarios/pendulum.yaml:14: materials.pp_yarn.bend_stiffness: must be > 0 (got -1)
//
//   YamlMap root(LoadYamlFile(path), path, "");
//   root.AllowOnly({"name", "duration"});
//   double duration = root.Double("duration");

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "common/errors.h"

namespace netlab {

namespace yaml_util_internal {

// The most bytes a YAML file netlab reads may hold: scenarios, experiments and bench tests are
// kilobytes to a few megabytes (yaml-cpp needs some 50 bytes of memory per byte of text); a device
// such as /dev/zero would otherwise be read until memory runs out.
inline constexpr std::uintmax_t kMaxYamlBytes = std::uintmax_t{64} << 20;

inline std::string Line(const std::string& origin, const YAML::Mark& mark) {
  return origin + (mark.line >= 0 ? ":" + std::to_string(mark.line + 1) : std::string()) + ": ";
}

inline std::string Child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// Walks the tree once and refuses what a YAML reader accepts but netlab would misread:
//   - a key given twice in one mapping (yaml-cpp keeps the first silently), naming both lines;
//   - an explicit tag ("!!str 5", "!seconds 3"), which netlab's readers ignore, so the value
//     would be read as if it had none;
//   - aliases that expand to far more values than the text holds (a "billion laughs" of nested
//     aliases), before anything walks the expanded tree. `budget` counts the values visited.
inline void CheckTree(const YAML::Node& node, const std::string& origin, const std::string& path,
                      std::size_t& budget) {
  if (budget == 0)
    throw InputError(origin +
                     ": its aliases ('*name') expand to more values than the file's "
                     "text holds; netlab reads no alias bombs");
  --budget;
  const std::string& tag = node.Tag();
  if (!tag.empty() && tag != "?" && tag != "!") {
    const std::string shown = tag.rfind("tag:yaml.org,2002:", 0) == 0 ? "!!" + tag.substr(18) : tag;
    throw InputError(Line(origin, node.Mark()) + (path.empty() ? std::string("(root)") : path) +
                     ": the tag '" + shown +
                     "' is not read by netlab (the value would be read "
                     "as if it had none); remove it");
  }
  if (node.IsMap()) {
    std::vector<std::pair<std::string, int>> seen;  // key, line
    for (auto it = node.begin(); it != node.end(); ++it) {
      // Copies: `it->first` is a member of a temporary the iterator returns.
      const YAML::Node key = it->first, value = it->second;
      const std::string name = key.IsScalar() ? key.Scalar() : std::string("(complex key)");
      if (key.IsScalar())
        for (const auto& [other, line] : seen)
          if (other == name)
            throw InputError(Line(origin, key.Mark()) + Child(path, name) +
                             ": given twice, at lines " + std::to_string(line + 1) + " and " +
                             std::to_string(key.Mark().line + 1) +
                             " (a YAML reader keeps one of them silently); keep one");
      seen.emplace_back(name, key.Mark().line);
      CheckTree(key, origin, Child(path, name), budget);
      CheckTree(value, origin, Child(path, name), budget);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i)
      CheckTree(node[i], origin, path + "[" + std::to_string(i) + "]", budget);
  }
}

}  // namespace yaml_util_internal

// Parses YAML text read from `origin` (a file name, or what the text came from): syntax errors
// become InputError with origin and line, and so do a key given twice in one mapping, an explicit
// tag on a value, a second document after '---', and aliases that expand beyond the text's size
// (yaml_util_internal::CheckTree). An empty text gives a null node.
inline YAML::Node LoadYamlString(const std::string& text, const std::string& origin) {
  using namespace yaml_util_internal;
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(origin + ":" + std::to_string(e.mark.line + 1) +
                     ": YAML syntax error: " + e.msg);
  }
  for (std::size_t i = 1; i < documents.size(); ++i)
    if (!documents[i].IsNull())
      throw InputError(Line(origin, documents[i].Mark()) +
                       "a second YAML document (after a '---' line): netlab reads one document "
                       "per file, and would ignore this one; remove it or the '---'");
  if (documents.empty()) return YAML::Node();
  std::size_t budget = 2 * text.size() + 1000;  // each value takes at least a byte of text
  CheckTree(documents[0], origin, "", budget);
  return documents[0];
}

// The text of a YAML file; a missing or unreadable file, a folder, or one larger than 64 MiB (a
// device such as /dev/zero) becomes InputError naming it: "x.yaml: cannot open <kind>".
inline std::string ReadYamlText(const std::string& path, const std::string& kind = "file") {
  using namespace yaml_util_internal;
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (fs::is_directory(status)) throw InputError(path + ": is a folder, not a YAML " + kind);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open " + kind);
  std::string text;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxYamlBytes)
      throw InputError(path + ": more than 64 MiB; not a YAML file netlab reads (a device?)");
  }
  if (in.bad()) throw InputError(path + ": cannot read " + kind);
  return text;
}

// Reads and parses a YAML file: ReadYamlText, then LoadYamlString.
inline YAML::Node LoadYamlFile(const std::string& path) {
  return LoadYamlString(ReadYamlText(path), path);
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
    if (!(allow_zero ? v >= 0.0 : v > 0.0))
      Fail(key,
           std::string("must be ") + (allow_zero ? ">= 0" : "> 0") + " (got " + Number(v) + ")");
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

  // A value as an error message quotes it: whole up to 60 characters, else its start and length.
  static std::string Shown(const std::string& text) {
    if (text.size() <= 60) return text;
    return text.substr(0, 40) + "... (" + std::to_string(text.size()) + " characters)";
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
    if (!value.IsScalar()) throw InputError(Location(value) + what + ": expected a number");
    double v;
    try {
      v = value.as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(Location(value) + what + ": expected a number, got '" +
                       Shown(value.Scalar()) + "'");
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
