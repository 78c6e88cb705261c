#pragma once
// Builds a Model and its initial State from rod and net descriptions.
//
//   ModelBuilder builder(ModelBuilderOptions{});
//   int pp = builder.AddMaterial(pp_yarn);
//   builder.AddRod(rod_spec);
//   builder.AddNet(net_spec);
//   auto [model, state] = std::move(builder).Build();
//
// Bad specifications (unknown material, fewer than one segment, a degenerate direction, ...)
// throw std::invalid_argument naming the rod or net and the field.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libnetsim/model/model.h"

namespace netlab::netsim {

enum class Fixity { kFree, kPinned, kClamped };

struct RodSpec {
  std::string name;
  int material = 0;                   // index returned by AddMaterial
  Vector3d start = Vector3d::Zero();  // m
  Vector3d end = Vector3d::UnitX();   // m
  int segments = 1;
  Fixity fix_start = Fixity::kFree;  // pinned: position; clamped: position and orientation
  Fixity fix_end = Fixity::kFree;
  Vector3d velocity = Vector3d::Zero();  // m/s, every free node
  // A rigid body at the end (a torsion pendulum's bob, a weight): its mass (kg) is added to the
  // last node, its principal moments (I1, I2, I3) about (d1, d2, d3) (kg m^2) to the last
  // segment's, which turns with it. The thread's free length then ends at that segment's centre.
  double tip_mass = 0.0;
  Vector3d tip_inertia = Vector3d::Zero();
};

struct NetSpec {
  std::string name;
  int material = 0;
  int rows = 2;       // knots per column
  int cols = 2;       // knots per row
  double mesh = 0.1;  // link rest length, m
  int segments_per_link = 1;
  Vector3d center = Vector3d::Zero();    // m
  Vector3d normal = Vector3d::UnitZ();   // net plane normal
  Vector3d x_axis = Vector3d::UnitX();   // direction of increasing col (projected on the plane)
  double knot_mass = 0.0;                // kg added at every knot (knotted nets)
  double corner_mass = 0.0;              // kg added at each of the four corners
  double corner_radius = 0.0;            // m, contact radius of the corner masses (0: thread)
  Vector3d velocity = Vector3d::Zero();  // m/s, whole net
  Vector3d angular_velocity = Vector3d::Zero();  // rad/s, whole net about `center`
  // Extra velocity of the corner masses (m/s), in the order (0,0), (0,cols-1), (rows-1,0),
  // (rows-1,cols-1): the ejector's corner-mass shot.
  std::array<Vector3d, 4> corner_velocities = {Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(),
                                               Vector3d::Zero()};
  // Knot spacing as a fraction of `mesh` (0 < spread <= 1). Below 1 the links bulge out of the
  // plane along `normal`, keeping their length: a partly folded net as it leaves the ejector.
  double spread = 1.0;
};

struct ModelBuilderOptions {
  // Coupling penalty kappa = ratio * max(EI, GJ) / l^2 per segment (forces/segment_force.h). The
  // shear compliance it leaves is ~1/ratio of the bending compliance at the scale of one segment,
  // and far less at the scale of a link: 100 keeps the Kirchhoff constraint to ~1 %.
  double coupling_stiffness_ratio = 100.0;
};

class ModelBuilder {
 public:
  explicit ModelBuilder(ModelBuilderOptions options = {});

  // Returns the material's index. Throws if the material is invalid or its name is taken.
  int AddMaterial(const Material& material);
  int FindMaterial(const std::string& name) const;

  // Return the index of the new rod / net in Model::rods / Model::nets.
  int AddRod(const RodSpec& spec);
  int AddNet(const NetSpec& spec);

  std::pair<Model, State> Build() &&;

 private:
  // Appends a chain of segments through `nodes` (already added), with frames transported along.
  void AddChain(const std::vector<int>& nodes, int material);
  int AddNode(const Vector3d& x, const Vector3d& v, double mass, double radius);
  void CheckMaterial(int material, const std::string& what) const;

  ModelBuilderOptions options_;
  Model model_;
  State state_;
};

// The smallest `spread` a link of n segments can be folded to by NetSpec's bulge (all segments
// but the middle ones turned towards the normal): below it AddNet throws.
double MinimumSpread(int segments_per_link);

}  // namespace netlab::netsim
