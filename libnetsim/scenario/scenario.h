#pragma once
// Scenario files: a simulation described as data (YAML), never compiled in. The keys are a
// contract (docs/scenarios.md lists them all, with units). LoadScenario checks everything it can
// before building: unknown keys, missing fields, out-of-range numbers, unknown materials, rods,
// nets and nodes are InputErrors naming the file, the line and the key.

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libnetsim/forces/contact_force.h"
#include "libnetsim/forces/drag_force.h"
#include "libnetsim/forces/point_load_force.h"
#include "libnetsim/model/model_builder.h"
#include "libnetsim/model/time_series.h"
#include "libnetsim/simulation/simulation.h"

namespace YAML {
class Node;
}

namespace netlab::netsim {

// A node named in a scenario: a rod node (by index, "start" is 0 and "end" the last) or a knot.
struct NodeRef {
  int rod = -1;   // index into Scenario::rods, or -1
  int net = -1;   // index into Scenario::nets, or -1
  int index = 0;  // rod node index
  int row = 0;    // knot grid coordinate
  int col = 0;
};

struct LoadSpec {
  PointLoad::Kind kind = PointLoad::Kind::kForce;
  NodeRef where;
  Vector3d vector = Vector3d::Zero();  // N or N m
};

struct ProbeSpec {
  std::string name;
  NodeRef where;
};

struct Scenario {
  std::string name;
  std::string description;
  std::string source_path;  // file read, or "" when parsed from text
  std::string text;         // the YAML source, stored with the results

  double duration = 0.0;         // s
  double output_interval = 0.0;  // s
  bool store_nodes = true;       // write /nodes/position
  SimulationOptions simulation;
  ModelBuilderOptions model;

  std::optional<Vector3d> gravity;            // m/s^2, constant
  std::optional<TimeSeries3> gravity_series;  // or measured
  std::optional<DragOptions> drag;
  std::optional<Vector3d> frame_rotation;            // rad/s, constant
  std::optional<TimeSeries3> frame_rotation_series;  // or measured (gyro)

  std::vector<Material> materials;
  std::vector<RodSpec> rods;  // RodSpec::material indexes `materials`
  std::vector<NetSpec> nets;
  std::vector<RigidBody> bodies;
  std::vector<LoadSpec> loads;
  std::vector<ProbeSpec> probes;
};

// Reads and checks a scenario file; relative data files are resolved against its folder.
Scenario LoadScenario(const std::string& path);
// The text of a scenario file, unchecked; InputError naming it when it cannot be opened.
std::string ReadScenarioText(const std::string& path);
// Parses scenario text; `origin` names it in errors, `base_dir` resolves relative file names.
Scenario ParseScenario(const std::string& text, const std::string& origin,
                       const std::string& base_dir);
// The same from its YAML tree (scenario_override.h); `text` is stored as the scenario's source.
Scenario ParseScenarioTree(const YAML::Node& tree, const std::string& text,
                           const std::string& origin, const std::string& base_dir);

// A scenario turned into a runnable simulation.
struct BuiltScenario {
  std::unique_ptr<Simulation> simulation;
  std::vector<int> knot_nodes;  // node of each knot, in Model::knots order
  std::vector<std::array<int, 2>> knot_grid;
  std::vector<int> knot_net;
  std::vector<std::string> net_names;
  std::vector<std::string> probe_names;
  std::vector<int> probe_nodes;
};

// Builds the model, the forces the scene uses (and only those) and the simulation.
BuiltScenario BuildScenario(const Scenario& scenario);
// Only the model and its initial state: the geometry, without the forces or the simulation's
// stability and contact set-up (what reading a result back needs; `netlab render` of a net with
// segments_per_link 1 has no bending stiffness to size the contact from, yet draws fine).
std::pair<Model, State> BuildModel(const Scenario& scenario);

// Node index in the built model of a NodeRef.
int ResolveNode(const Model& model, const NodeRef& ref);

}  // namespace netlab::netsim
