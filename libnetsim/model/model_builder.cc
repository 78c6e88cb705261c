#include "libnetsim/model/model_builder.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "libnetsim/model/rotation.h"

namespace netlab::netsim {
namespace {

[[noreturn]] void Fail(const std::string& what, const std::string& message) {
  throw std::invalid_argument(what + ": " + message);
}

bool AllFinite(const Vector3d& v) { return v.allFinite(); }

// Segment angles of a folded link: theta_k = theta_max cos(pi (k + 1/2) / n), a symmetric bump
// whose chord is sum cos(theta_k) / n of its length.
double FoldedChordRatio(int n, double theta_max) {
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    sum += std::cos(theta_max * std::cos(std::numbers::pi * (k + 0.5) / n));
  return sum / n;
}

// theta_max for which the chord is `ratio` of the length (bisection; the chord ratio falls
// monotonically in theta_max on [0, pi/2]).
double FoldAngle(int n, double ratio) {
  double lo = 0.0, hi = 0.5 * std::numbers::pi;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (FoldedChordRatio(n, mid) > ratio ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double MinimumSpread(int segments_per_link) {
  if (segments_per_link < 2) return 1.0;
  return FoldedChordRatio(segments_per_link, 0.5 * std::numbers::pi);
}

ModelBuilder::ModelBuilder(ModelBuilderOptions options) : options_(options) {
  if (!(options_.coupling_stiffness_ratio > 0.0) ||
      !std::isfinite(options_.coupling_stiffness_ratio))
    Fail("coupling_stiffness_ratio", "must be > 0");
}

int ModelBuilder::AddMaterial(const Material& material) {
  std::string error;
  if (!material.IsValid(&error)) Fail("material '" + material.name + "'", error);
  if (FindMaterial(material.name) >= 0) Fail("material '" + material.name + "'", "defined twice");
  model_.materials.push_back(material);
  return static_cast<int>(model_.materials.size()) - 1;
}

int ModelBuilder::FindMaterial(const std::string& name) const {
  for (size_t i = 0; i < model_.materials.size(); ++i)
    if (model_.materials[i].name == name) return static_cast<int>(i);
  return -1;
}

void ModelBuilder::CheckMaterial(int material, const std::string& what) const {
  if (material < 0 || material >= static_cast<int>(model_.materials.size()))
    Fail(what, "unknown material index " + std::to_string(material));
}

int ModelBuilder::AddNode(const Vector3d& x, const Vector3d& v, double mass, double radius) {
  model_.node_mass.push_back(mass);
  model_.node_inv_mass.push_back(0.0);  // set in Build() from the final mass
  model_.node_radius.push_back(radius);
  state_.x.push_back(x);
  state_.v.push_back(v);
  return static_cast<int>(model_.node_mass.size()) - 1;
}

void ModelBuilder::AddChain(const std::vector<int>& nodes, int material) {
  const Material& m = model_.materials[material];
  const int first_segment = model_.num_segments();
  const double bend_max = std::max(m.bend_stiffness, m.twist_stiffness);
  Quaterniond frame;
  for (size_t k = 0; k + 1 < nodes.size(); ++k) {
    const Vector3d e = state_.x[nodes[k + 1]] - state_.x[nodes[k]];
    const double length = e.norm();
    Segment s;
    s.node_a = nodes[k];
    s.node_b = nodes[k + 1];
    s.material = material;
    s.rest_length = length;
    s.inv_rest_length = 1.0 / length;
    s.stretch_stiffness = m.stretch_stiffness;
    s.stretch_damping = m.stretch_damping;
    s.coupling_stiffness = options_.coupling_stiffness_ratio * bend_max / (length * length);
    s.diameter = m.diameter;
    model_.segments.push_back(s);

    // Frames: the first from the tangent, the next ones parallel-transported (no initial twist).
    const Vector3d t = e / length;
    if (k == 0) {
      frame = FrameFromTangent(t);
    } else {
      frame = (MinimalRotation(Director3(frame), t) * frame).normalized();
    }
    state_.q.push_back(frame);
    state_.w.push_back(Vector3d::Zero());

    // Lumped masses: half of the segment's thread to each end node.
    const double half_mass = 0.5 * m.linear_density * length;
    model_.node_mass[nodes[k]] += half_mass;
    model_.node_mass[nodes[k + 1]] += half_mass;

    // Physical cross-section inertia of a solid circular thread: mu l (r^2/4, r^2/4, r^2/2).
    const double r2 = 0.25 * m.diameter * m.diameter;
    const double ml = m.linear_density * length;
    model_.segment_inertia.push_back(Vector3d(0.25 * ml * r2, 0.25 * ml * r2, 0.5 * ml * r2));
    model_.segment_inv_inertia.push_back(model_.segment_inertia.back().cwiseInverse());
  }
  for (int j = first_segment; j + 1 < model_.num_segments(); ++j) {
    BendPair p;
    p.segment_a = j;
    p.segment_b = j + 1;
    p.inv_length = 2.0 / (model_.segments[j].rest_length + model_.segments[j + 1].rest_length);
    p.stiffness = Vector3d(m.bend_stiffness, m.bend_stiffness, m.twist_stiffness);
    p.damping = Vector3d(m.bend_damping, m.bend_damping, m.twist_damping);
    // Rest shape straight and untwisted: rest_phi stays 0 even when the initial shape is folded.
    model_.bend_pairs.push_back(p);
  }
}

int ModelBuilder::AddRod(const RodSpec& spec) {
  const std::string what = "rod '" + spec.name + "'";
  CheckMaterial(spec.material, what);
  if (spec.segments < 1) Fail(what, "segments must be >= 1");
  if (!AllFinite(spec.start) || !AllFinite(spec.end) || !AllFinite(spec.velocity))
    Fail(what, "start, end and velocity must be finite");
  if (!(spec.tip_mass >= 0.0) || !std::isfinite(spec.tip_mass) || !AllFinite(spec.tip_inertia) ||
      spec.tip_inertia.minCoeff() < 0.0)
    Fail(what, "tip mass and inertia must be finite and >= 0");
  if ((spec.end - spec.start).norm() <= 0.0) Fail(what, "start and end coincide");
  if (model_.FindRod(spec.name) >= 0 || model_.FindNet(spec.name) >= 0)
    Fail(what, "name used twice");

  RodInfo info;
  info.name = spec.name;
  info.material = spec.material;
  info.first_node = model_.num_nodes();
  info.first_segment = model_.num_segments();
  const double radius = 0.5 * model_.materials[spec.material].diameter;
  std::vector<int> nodes;
  for (int i = 0; i <= spec.segments; ++i) {
    const double s = static_cast<double>(i) / spec.segments;
    nodes.push_back(AddNode(spec.start + s * (spec.end - spec.start), spec.velocity, 0.0, radius));
  }
  AddChain(nodes, spec.material);
  // The tip body turns with the last segment and moves with the last node.
  model_.node_mass[nodes.back()] += spec.tip_mass;
  Vector3d& tip_segment_inertia = model_.segment_inertia.back();
  tip_segment_inertia += spec.tip_inertia;
  model_.segment_inv_inertia.back() = tip_segment_inertia.cwiseInverse();
  info.num_nodes = spec.segments + 1;
  info.num_segments = spec.segments;
  model_.rods.push_back(info);

  // Boundary conditions: an infinite mass (inverse 0) holds a node; a clamp adds a bending joint
  // between the end segment and the fixed initial frame of that segment.
  auto fix = [&](Fixity fixity, int node, int segment) {
    if (fixity == Fixity::kFree) return;
    model_.node_inv_mass[node] = -1.0;  // marker, resolved in Build()
    state_.v[node].setZero();
    if (fixity == Fixity::kClamped) {
      const Material& m = model_.materials[spec.material];
      AnchorJoint anchor;
      anchor.segment = segment;
      anchor.frame = state_.q[segment];
      anchor.inv_length = 2.0 / model_.segments[segment].rest_length;
      anchor.stiffness = Vector3d(m.bend_stiffness, m.bend_stiffness, m.twist_stiffness);
      anchor.damping = Vector3d(m.bend_damping, m.bend_damping, m.twist_damping);
      model_.anchors.push_back(anchor);
    }
  };
  fix(spec.fix_start, info.first_node, info.first_segment);
  fix(spec.fix_end, info.first_node + spec.segments, info.first_segment + spec.segments - 1);
  return static_cast<int>(model_.rods.size()) - 1;
}

int ModelBuilder::AddNet(const NetSpec& spec) {
  const std::string what = "net '" + spec.name + "'";
  CheckMaterial(spec.material, what);
  if (spec.rows < 2 || spec.cols < 2) Fail(what, "knots must be at least 2 x 2");
  if (spec.segments_per_link < 1) Fail(what, "segments_per_link must be >= 1");
  if (!(spec.mesh > 0.0) || !std::isfinite(spec.mesh)) Fail(what, "mesh must be > 0");
  if (!(spec.knot_mass >= 0.0) || !(spec.corner_mass >= 0.0) || !(spec.corner_radius >= 0.0))
    Fail(what, "knot_mass, corner_mass and corner_radius must be >= 0");
  if (!(spec.spread > 0.0 && spec.spread <= 1.0)) Fail(what, "spread must be in (0, 1]");
  if (spec.spread < 1.0 && spec.spread < MinimumSpread(spec.segments_per_link) + 1e-9)
    Fail(what, "spread " + std::to_string(spec.spread) + " is below what " +
                   std::to_string(spec.segments_per_link) + " segments per link can fold to (" +
                   std::to_string(MinimumSpread(spec.segments_per_link)) + ")");
  if (model_.FindRod(spec.name) >= 0 || model_.FindNet(spec.name) >= 0)
    Fail(what, "name used twice");
  const Vector3d normal = spec.normal.normalized();
  if (!normal.allFinite()) Fail(what, "normal must be a non-zero vector");
  Vector3d u = spec.x_axis - spec.x_axis.dot(normal) * normal;
  if (!(u.norm() > 1e-9)) Fail(what, "x_axis must not be parallel to the normal");
  u.normalize();
  const Vector3d v = normal.cross(u);

  NetInfo info;
  info.name = spec.name;
  info.material = spec.material;
  info.rows = spec.rows;
  info.cols = spec.cols;
  info.segments_per_link = spec.segments_per_link;
  info.mesh = spec.mesh;
  info.first_knot = model_.num_knots();
  info.first_node = model_.num_nodes();
  info.first_segment = model_.num_segments();
  const int net_index = static_cast<int>(model_.nets.size());
  const Material& m = model_.materials[spec.material];
  const double thread_radius = 0.5 * m.diameter;

  // Initial velocity of a point of the net: translation plus rotation about the centre.
  auto velocity_at = [&](const Vector3d& x) {
    return Vector3d(spec.velocity + spec.angular_velocity.cross(x - spec.center));
  };

  // Knots.
  const double pitch = spec.spread * spec.mesh;
  const double r_mid = 0.5 * (spec.rows - 1), c_mid = 0.5 * (spec.cols - 1);
  for (int r = 0; r < spec.rows; ++r) {
    for (int c = 0; c < spec.cols; ++c) {
      const Vector3d x = spec.center + pitch * ((c - c_mid) * u + (r - r_mid) * v);
      const int node = AddNode(x, velocity_at(x), spec.knot_mass, thread_radius);
      model_.knots.push_back(Knot{net_index, r, c, node});
    }
  }
  const int corners[4] = {0, spec.cols - 1, (spec.rows - 1) * spec.cols, spec.rows * spec.cols - 1};
  for (int i = 0; i < 4; ++i) {
    const int node = model_.knots[info.first_knot + corners[i]].node;
    model_.node_mass[node] += spec.corner_mass;
    model_.node_radius[node] = std::max(thread_radius, spec.corner_radius);
    state_.v[node] += spec.corner_velocities[i];
  }

  // Links: interior nodes on a straight line (spread 1) or on a length-preserving bump.
  const int n = spec.segments_per_link;
  const double seg_len = spec.mesh / n;
  const double theta_max = spec.spread < 1.0 ? FoldAngle(n, spec.spread) : 0.0;
  auto add_link = [&](int knot0, int knot1) {
    const int a = model_.knots[info.first_knot + knot0].node;
    const int b = model_.knots[info.first_knot + knot1].node;
    const Vector3d chord = state_.x[b] - state_.x[a];
    const Vector3d dir = chord.normalized();
    std::vector<int> nodes = {a};
    Vector3d p = state_.x[a];
    for (int k = 0; k + 1 < n; ++k) {
      const double theta = theta_max * std::cos(std::numbers::pi * (k + 0.5) / n);
      p += seg_len * (std::cos(theta) * dir + std::sin(theta) * normal);
      nodes.push_back(AddNode(p, velocity_at(p), 0.0, thread_radius));
    }
    nodes.push_back(b);
    AddChain(nodes, spec.material);
  };
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c + 1 < spec.cols; ++c) add_link(r * spec.cols + c, r * spec.cols + c + 1);
  for (int r = 0; r + 1 < spec.rows; ++r)
    for (int c = 0; c < spec.cols; ++c) add_link(r * spec.cols + c, (r + 1) * spec.cols + c);

  info.num_nodes = model_.num_nodes() - info.first_node;
  info.num_segments = model_.num_segments() - info.first_segment;
  // Segments turn with the net's initial angular velocity (body frame).
  for (int j = info.first_segment; j < model_.num_segments(); ++j)
    state_.w[j] = state_.q[j].conjugate() * spec.angular_velocity;
  model_.nets.push_back(info);
  return net_index;
}

std::pair<Model, State> ModelBuilder::Build() && {
  for (int i = 0; i < model_.num_nodes(); ++i) {
    const bool pinned = model_.node_inv_mass[i] < 0.0;
    if (!(model_.node_mass[i] > 0.0))
      Fail(model_.DescribeNode(i), "has no mass (is it attached to a segment?)");
    model_.node_inv_mass[i] = pinned ? 0.0 : 1.0 / model_.node_mass[i];
  }
  state_.time = 0.0;
  return {std::move(model_), std::move(state_)};
}

}  // namespace netlab::netsim
