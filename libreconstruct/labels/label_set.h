#pragma once
// 2D knot labels per camera and frame, and their files: the project's labels file (labels.h5,
// written by the labeling tools, read by `netlab triangulate`) and DLTdv8-style xypts.csv.
//
// labels.h5 (HDF5; every dataset has a "units" attribute):
//   root attributes: "format" = "netlab-labels", "version" = "1", "rows", "cols" (int), and
//                    "cameras" (the camera names, one per line, in the order of /cameras)
//   /frame_index                      [T]      int32    frame number of each row
//   /knots/grid                       [K,2]    int32    (row, col), K = rows * cols, row-major
//   /cameras/<name>/position_px       [T,K,2]  float64  px; NaN where unlabeled
//   /cameras/<name>/source            [T,K]    uint8    LabelSource
//   /cameras/<name>/confidence        [T,K]    float32  0..1
//   /cameras/<name>/state             [T,K]    uint8    LabelState (3, hidden: no position)
//   /review_reasons                   scalar   string   optional: why labels are under review,
//                                                       a line "camera<TAB>t<TAB>knot<TAB>reason"
//                                                       each (camera index, frame row, knot)
// Written to "<path>.partial" and renamed into place.
//
// xypts.csv (DLTdv8 style): a header row, then one row per frame (row i is frame i, from 0);
// columns pt{P}_cam{C}_X, pt{P}_cam{C}_Y for P = 1..K and C = 1..N (P outer, C inner, X before Y),
// "NaN" where unlabeled. Point P is knot (row, col) with P = row * cols + col + 1; camera C is the
// C-th camera of the label set (the rig's order). Pixel convention: OpenCV's (origin at the
// centre of the top-left pixel, y down). Columns may come in any order on reading; every pair must
// be complete.
//
// Pixels and the knot order are the same in both files; a label exists where the position is
// finite. Bad input throws netlab::InputError naming the file, the line or dataset and the field.

#include <Eigen/Core>
#include <cmath>
#include <compare>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace netlab::recon {

enum class LabelSource : uint8_t {
  kNone = 0,
  kManual = 1,
  kFindNode = 2,
  kFindPath = 3,
  kFillGrid = 4,
  kTracked = 5,
  kColour = 6,    // identified by yarn colours
  kImported = 7,  // read from xypts.csv or another tool
  // Placed where the knot's labels in two or more other cameras put it, with its yarns seen
  // there but no junction found (Fill Grid): derived from those labels, so the triangulation
  // of the knot leaves it out.
  kProjected = 8,
};

// kHidden is not a label but the person's word that the knot cannot be seen in that camera and
// frame (behind the target, out of view, behind the net): its position is NaN (not present()),
// the tools never put a label over it, and the review queue does not ask for it. Files written
// before it existed hold states 0..2 only and read as before; an older reader refuses a 3 by name.
enum class LabelState : uint8_t { kNone = 0, kAccepted = 1, kNeedsReview = 2, kHidden = 3 };

struct Label {
  Eigen::Vector2d px{std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::quiet_NaN()};
  LabelSource source = LabelSource::kNone;
  float confidence = 0.0f;
  LabelState state = LabelState::kNone;

  bool present() const { return std::isfinite(px.x()) && std::isfinite(px.y()); }
  bool accepted() const { return present() && state == LabelState::kAccepted; }
  bool hidden() const { return state == LabelState::kHidden; }
  // The person's mark "not visible here" (source: person).
  static Label Hidden() {
    Label l;
    l.source = LabelSource::kManual;
    l.confidence = 1.0f;
    l.state = LabelState::kHidden;
    return l;
  }
};

// Whether two labels are the same: position, source, confidence and state alike, an absent
// position (NaN) equal to an absent one. The label store's steps and the window's session
// compare labels by it.
inline bool SameLabel(const Label& a, const Label& b) {
  const auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return same(a.px.x(), b.px.x()) && same(a.px.y(), b.px.y()) && a.source == b.source &&
         a.confidence == b.confidence && a.state == b.state;
}

// The address of one label: camera index, frame row t (of frame_index), knot, in the order
// LabelSet::at takes them. Ordered camera first; ByFrame orders frame row first (the review
// queue's order).
struct LabelAddress {
  int camera = 0;
  int t = 0;
  int knot = 0;
  auto operator<=>(const LabelAddress&) const = default;
  struct ByFrame {
    bool operator()(const LabelAddress& a, const LabelAddress& b) const {
      return std::tie(a.t, a.camera, a.knot) < std::tie(b.t, b.camera, b.knot);
    }
  };
};

// Per label: why it is under review (the labeling tools' reasons).
using ReviewReasons = std::map<LabelAddress, std::string>;

struct LabelSet {
  int rows = 0, cols = 0;
  std::vector<std::string> cameras;  // names, in the rig's order for xypts.csv
  std::vector<int> frame_index;      // [T] frame numbers
  // labels[c][t * knots() + k] for camera c, row t of frame_index, knot k (row-major).
  std::vector<std::vector<Label>> labels;
  ReviewReasons reasons;  // saved in labels.h5; not in xypts.csv

  int knots() const { return rows * cols; }
  int frames() const { return static_cast<int>(frame_index.size()); }
  // Empty label set of the given shape (every label absent).
  static LabelSet Empty(int rows, int cols, const std::vector<std::string>& cameras,
                        const std::vector<int>& frame_index);
  Label& at(int camera, int t, int knot) {
    return labels[camera][static_cast<size_t>(t) * knots() + knot];
  }
  const Label& at(int camera, int t, int knot) const {
    return labels[camera][static_cast<size_t>(t) * knots() + knot];
  }
  int FindCamera(const std::string& name) const;  // index, or -1
  // Number of present labels (all cameras and frames).
  int64_t CountPresent() const;
};

// labels.h5. Write throws std::runtime_error when the file cannot be written.
void WriteLabels(const std::string& path, const LabelSet& labels);
LabelSet ReadLabels(const std::string& path);

// xypts.csv. Reading needs the net's shape and the camera names (camera C = camera_names[C - 1]);
// a column naming a point beyond rows * cols or a camera beyond camera_names is an error naming
// the column. Every label read is LabelSource::kImported, confidence 1, accepted.
void WriteXyPts(const std::string& path, const LabelSet& labels);
LabelSet ReadXyPts(const std::string& path, int rows, int cols,
                   const std::vector<std::string>& camera_names);

// Either file by its extension (".csv": xypts; otherwise labels.h5). For labels.h5 the net's
// shape must match rows x cols (error naming both otherwise); for xypts.csv the cameras are
// camera_names.
LabelSet ReadLabelsAny(const std::string& path, int rows, int cols,
                       const std::vector<std::string>& camera_names);

}  // namespace netlab::recon
