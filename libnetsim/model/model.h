#pragma once
// The fixed data of a simulation (Model) and the data that changes each step (State), after
// MuJoCo's split: functions take (const Model&, State&).
//
// A rod (paper section 2, CoRdE [9]) is a chain of centreline nodes x_0..x_n and one orientation
// quaternion per segment (see rotation.h for the convention). A net is a square mesh of knots;
// each link between two adjacent knots is a rod of `segments_per_link` segments whose end nodes
// are the knots themselves. Links hinge freely at knots: a knot transmits forces, not moments.
//
// Node order of a net: the rows*cols knots first (row-major), then the interior nodes of each link
// in link order. Link order: the horizontal links (r,c)-(r,c+1) row by row, then the vertical
// links (r,c)-(r+1,c) row by row. Node order of a rod: start to end.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "libnetsim/model/material.h"

namespace netlab::netsim {

using Eigen::Quaterniond;
using Eigen::Vector3d;

// One rod element between two nodes, carrying one orientation.
struct Segment {
  int node_a = 0;                  // start node; d3 points from node_a towards node_b
  int node_b = 0;                  // end node
  int material = 0;                // index into Model::materials
  double rest_length = 0.0;        // m
  double inv_rest_length = 0.0;    // 1/m
  double stretch_stiffness = 0.0;  // EA, N
  double stretch_damping = 0.0;    // c_s, N s
  double coupling_stiffness =
      0.0;                // kappa, N: penalty tying d3 to the tangent (forces/segment_force.h)
  double diameter = 0.0;  // m
};

// The joint between two consecutive segments of one rod: bending and torsion live here.
struct BendPair {
  int segment_a = 0;                      // the earlier segment along the rod
  int segment_b = 0;                      // the next one
  double inv_length = 0.0;                // 1 / (mean rest length of the two), 1/m
  Vector3d stiffness = Vector3d::Zero();  // (EI, EI, GJ), N m^2
  Vector3d damping = Vector3d::Zero();    // (c_b, c_b, c_t), N m^2 s
  Vector3d rest_phi = Vector3d::Zero();   // rest relative rotation vector, rad (0: straight)
};

// The joint between a clamped rod end and its fixed frame. Bending and torsion act over half the
// end segment (from the clamped node to the segment's centre), so the curvature at the clamp is
// resolved like any other joint's and the discretisation stays second order.
struct AnchorJoint {
  int segment = 0;                              // the rod's end segment
  Quaterniond frame = Quaterniond::Identity();  // the clamp's fixed orientation
  double inv_length = 0.0;                      // 2 / rest length of the segment, 1/m
  Vector3d stiffness = Vector3d::Zero();        // (EI, EI, GJ), N m^2
  Vector3d damping = Vector3d::Zero();          // (c_b, c_b, c_t), N m^2 s
};

struct RodInfo {
  std::string name;
  int material = 0;
  int first_node = 0;
  int num_nodes = 0;
  int first_segment = 0;
  int num_segments = 0;
};

struct NetInfo {
  std::string name;
  int material = 0;
  int rows = 0;
  int cols = 0;
  int segments_per_link = 0;
  double mesh = 0.0;   // link rest length, m
  int first_knot = 0;  // index into Model::knots; knot (r, c) is first_knot + r * cols + c
  int first_node = 0;
  int num_nodes = 0;
  int first_segment = 0;
  int num_segments = 0;

  int num_horizontal_links() const { return rows * (cols - 1); }
  int num_links() const { return rows * (cols - 1) + (rows - 1) * cols; }
};

// A knot of a net, addressed by its grid coordinate.
struct Knot {
  int net = 0;
  int row = 0;
  int col = 0;
  int node = 0;
};

struct Model {
  // Nodes.
  std::vector<double> node_mass;      // kg, including knot and corner masses
  std::vector<double> node_inv_mass;  // 1/kg; 0 for pinned nodes
  std::vector<double> node_radius;    // m, contact radius

  // Segments and the joints between them.
  std::vector<Segment> segments;
  std::vector<Vector3d> segment_inertia;      // body-frame principal moments (I1, I2, I3), kg m^2
  std::vector<Vector3d> segment_inv_inertia;  // 1/(kg m^2); 0 for clamped segments
  std::vector<BendPair> bend_pairs;
  std::vector<AnchorJoint> anchors;  // clamped rod ends

  std::vector<Material> materials;
  std::vector<RodInfo> rods;
  std::vector<NetInfo> nets;
  std::vector<Knot> knots;

  int num_nodes() const { return static_cast<int>(node_mass.size()); }
  int num_segments() const { return static_cast<int>(segments.size()); }
  int num_knots() const { return static_cast<int>(knots.size()); }

  // Human-readable place of a node or segment, for error messages:
  // "rod 'yarn' node 7", "net 'net' knot (2,3)", "net 'net' link (2,3)-(2,4) node 2".
  std::string DescribeNode(int node) const;
  std::string DescribeSegment(int segment) const;

  // Index of a rod or net by name, or -1.
  int FindRod(const std::string& name) const;
  int FindNet(const std::string& name) const;
  // Node of knot (row, col) of net `net`; -1 when outside the grid.
  int KnotNode(int net, int row, int col) const;
};

struct State {
  double time = 0.0;           // s
  std::vector<Vector3d> x;     // node positions, m, simulation frame
  std::vector<Vector3d> v;     // node velocities, m/s
  std::vector<Quaterniond> q;  // segment orientations (body to world)
  std::vector<Vector3d> w;     // segment angular velocities, body frame, rad/s
};

}  // namespace netlab::netsim
