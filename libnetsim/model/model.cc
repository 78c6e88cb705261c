#include "libnetsim/model/model.h"

#include <sstream>

namespace netlab::netsim {
namespace {

// Grid coordinates of the two knots of link `link` of `net`.
void LinkKnots(const NetInfo& net, int link, int* r0, int* c0, int* r1, int* c1) {
  const int h = net.num_horizontal_links();
  if (link < h) {
    *r0 = link / (net.cols - 1);
    *c0 = link % (net.cols - 1);
    *r1 = *r0;
    *c1 = *c0 + 1;
  } else {
    *r0 = (link - h) / net.cols;
    *c0 = (link - h) % net.cols;
    *r1 = *r0 + 1;
    *c1 = *c0;
  }
}

}  // namespace

std::string Model::DescribeNode(int node) const {
  std::ostringstream os;
  for (const RodInfo& rod : rods) {
    if (node >= rod.first_node && node < rod.first_node + rod.num_nodes) {
      os << "rod '" << rod.name << "' node " << node - rod.first_node;
      return os.str();
    }
  }
  for (const NetInfo& net : nets) {
    if (node < net.first_node || node >= net.first_node + net.num_nodes) continue;
    const int local = node - net.first_node;
    const int num_knots = net.rows * net.cols;
    if (local < num_knots) {
      os << "net '" << net.name << "' knot (" << local / net.cols << "," << local % net.cols << ")";
    } else {
      const int interior = net.segments_per_link - 1;
      const int link = (local - num_knots) / interior;
      int r0, c0, r1, c1;
      LinkKnots(net, link, &r0, &c0, &r1, &c1);
      os << "net '" << net.name << "' link (" << r0 << "," << c0 << ")-(" << r1 << "," << c1
         << ") node " << (local - num_knots) % interior + 1;
    }
    return os.str();
  }
  os << "node " << node;
  return os.str();
}

std::string Model::DescribeSegment(int segment) const {
  std::ostringstream os;
  for (const RodInfo& rod : rods) {
    if (segment >= rod.first_segment && segment < rod.first_segment + rod.num_segments) {
      os << "rod '" << rod.name << "' segment " << segment - rod.first_segment;
      return os.str();
    }
  }
  for (const NetInfo& net : nets) {
    if (segment < net.first_segment || segment >= net.first_segment + net.num_segments) continue;
    const int local = segment - net.first_segment;
    const int link = local / net.segments_per_link;
    int r0, c0, r1, c1;
    LinkKnots(net, link, &r0, &c0, &r1, &c1);
    os << "net '" << net.name << "' link (" << r0 << "," << c0 << ")-(" << r1 << "," << c1
       << ") segment " << local % net.segments_per_link;
    return os.str();
  }
  os << "segment " << segment;
  return os.str();
}

int Model::FindRod(const std::string& name) const {
  for (size_t i = 0; i < rods.size(); ++i)
    if (rods[i].name == name) return static_cast<int>(i);
  return -1;
}

int Model::FindNet(const std::string& name) const {
  for (size_t i = 0; i < nets.size(); ++i)
    if (nets[i].name == name) return static_cast<int>(i);
  return -1;
}

int Model::KnotNode(int net, int row, int col) const {
  if (net < 0 || net >= static_cast<int>(nets.size())) return -1;
  const NetInfo& info = nets[net];
  if (row < 0 || row >= info.rows || col < 0 || col >= info.cols) return -1;
  return knots[info.first_knot + row * info.cols + col].node;
}

}  // namespace netlab::netsim
