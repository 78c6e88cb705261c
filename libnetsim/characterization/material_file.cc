#include "libnetsim/characterization/material_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>

#include "common/files.h"
#include "common/yaml_util.h"

namespace netlab::netsim {

double MaterialValue(const Material& m, std::string_view key) {
  const std::pair<std::string_view, double> values[] = {{"diameter", m.diameter},
                                                        {"linear_density", m.linear_density},
                                                        {"stretch_stiffness", m.stretch_stiffness},
                                                        {"stretch_damping", m.stretch_damping},
                                                        {"bend_stiffness", m.bend_stiffness},
                                                        {"bend_damping", m.bend_damping},
                                                        {"twist_stiffness", m.twist_stiffness},
                                                        {"twist_damping", m.twist_damping}};
  for (const auto& [name, value] : values)
    if (name == key) return value;
  throw std::invalid_argument("'" + std::string(key) + "' is not a material key");
}
namespace {

template <size_t N>
bool Contains(const std::array<std::string_view, N>& list, const std::string& name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

template <size_t N>
std::string Listed(const std::array<std::string_view, N>& list) {
  std::string text;
  for (std::string_view item : list) text += (text.empty() ? "" : ", ") + std::string(item);
  return text;
}

// The keys of a YAML map, in file order.
std::vector<std::string> Keys(const YamlMap& map) {
  std::vector<std::string> keys;
  for (auto it = map.node().begin(); it != map.node().end(); ++it)
    keys.push_back(it->first.as<std::string>());
  return keys;
}

// One material's values (`materials.<name>`), each checked to be a known key and a number.
void ReadValues(const YamlMap& values, const std::string& name,
                std::vector<ParameterEstimate>* out) {
  for (const std::string& key : Keys(values))
    if (!Contains(kMaterialKeys, key))
      values.Fail(key, "unknown material key (allowed: " + Listed(kMaterialKeys) + ")");
  for (std::string_view key : kMaterialKeys) {
    if (!values.Has(std::string(key))) continue;
    ParameterEstimate e;
    e.material = name;
    e.key = key;
    e.value = values.Double(e.key);
    out->push_back(e);
  }
}

// The uncertainty entry of one value: `uncertainty.<material>.<key>: {sigma, test, source}`.
void ReadUncertainty(const YamlMap& entry, ParameterEstimate* e) {
  entry.AllowOnly({"sigma", "test", "source"});
  e->sigma = entry.Positive("sigma", /*allow_zero=*/true);
  e->test = entry.String("test");
  if (!Contains(kBenchTests, e->test))
    entry.Fail("test", "unknown test '" + e->test + "' (allowed: " + Listed(kBenchTests) + ")");
  e->source = entry.String("source");
}

// %.9g: enough digits that a value read back is the value written to ~1e-9.
std::string Format(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return buffer;
}

// A YAML scalar that reads back as the same string (test file names may hold ':' or '#').
std::string QuotedIfNeeded(const std::string& text) {
  YAML::Emitter emitter;
  emitter << text;
  return emitter.c_str();
}

void CheckEstimates(const std::vector<ParameterEstimate>& estimates) {
  std::map<std::pair<std::string, std::string>, int> seen;
  for (const ParameterEstimate& e : estimates) {
    if (!Contains(kMaterialKeys, e.key))
      throw std::invalid_argument("material file: unknown material key '" + e.key + "'");
    if (!Contains(kBenchTests, e.test))
      throw std::invalid_argument("material file: unknown test '" + e.test + "'");
    if (seen[{e.material, e.key}]++)
      throw std::invalid_argument("material file: " + e.material + "." + e.key + " given twice");
  }
}

// The estimates of one material in kMaterialKeys' order.
std::vector<const ParameterEstimate*> OfMaterial(const std::vector<ParameterEstimate>& estimates,
                                                 const std::string& material) {
  std::vector<const ParameterEstimate*> out;
  for (std::string_view key : kMaterialKeys)
    for (const ParameterEstimate& e : estimates)
      if (e.material == material && e.key == key) out.push_back(&e);
  return out;
}

std::string MaterialFileText(const std::vector<ParameterEstimate>& estimates,
                             const std::string& header_comment) {
  std::ostringstream text;
  std::istringstream header(header_comment);
  for (std::string line; std::getline(header, line);) text << "# " << line << "\n";
  std::vector<std::string> materials;
  for (const ParameterEstimate& e : estimates)
    if (std::find(materials.begin(), materials.end(), e.material) == materials.end())
      materials.push_back(e.material);
  text << "materials:\n";
  for (const std::string& m : materials) {
    text << "  " << QuotedIfNeeded(m) << ": {";
    const char* separator = "";
    for (const ParameterEstimate* e : OfMaterial(estimates, m)) {
      text << separator << e->key << ": " << Format(e->value);
      separator = ", ";
    }
    text << "}\n";
  }
  text << "uncertainty:\n";
  for (const std::string& m : materials) {
    text << "  " << QuotedIfNeeded(m) << ":\n";
    for (const ParameterEstimate* e : OfMaterial(estimates, m))
      text << "    " << e->key << ": {sigma: " << Format(e->sigma) << ", test: " << e->test
           << ", source: " << QuotedIfNeeded(e->source) << "}\n";
  }
  return text.str();
}

}  // namespace

std::vector<ParameterEstimate> ReadMaterialFile(const std::string& path) {
  const YamlMap root(LoadYamlFile(path), path, "");
  root.AllowOnly({"materials", "uncertainty"});
  const YamlMap materials = root.Map("materials");
  const YamlMap uncertainty = root.Map("uncertainty");
  std::vector<ParameterEstimate> estimates;
  for (const std::string& name : Keys(materials)) ReadValues(materials.Map(name), name, &estimates);
  for (ParameterEstimate& e : estimates) {
    if (!uncertainty.Has(e.material))
      uncertainty.Fail(e.material, "missing: every material needs its uncertainty entries");
    const YamlMap of_material = uncertainty.Map(e.material);
    if (!of_material.Has(e.key))
      of_material.Fail(e.key, "missing: every value needs {sigma, test, source}");
    ReadUncertainty(of_material.Map(e.key), &e);
  }
  // Every uncertainty entry belongs to a value.
  for (const std::string& name : Keys(uncertainty)) {
    if (!materials.Has(name)) uncertainty.Fail(name, "no such material in 'materials'");
    const YamlMap of_material = uncertainty.Map(name);
    for (const std::string& key : Keys(of_material))
      if (!materials.Map(name).Has(key))
        of_material.Fail(key, "no such value in materials." + name);
  }
  return estimates;
}

void WriteMaterialFile(const std::string& path, const std::vector<ParameterEstimate>& estimates,
                       const std::string& header_comment) {
  CheckEstimates(estimates);
  WriteTextFile(path, MaterialFileText(estimates, header_comment));
}

}  // namespace netlab::netsim
