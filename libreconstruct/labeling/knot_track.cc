#include "libreconstruct/labeling/knot_track.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <optional>

namespace netlab::recon {
namespace {

cv::Mat Grey8(const cv::Mat& image) {
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  if (grey.depth() != CV_8U) {
    double max = 0.0;
    cv::minMaxLoc(grey, nullptr, &max);
    grey.convertTo(grey, CV_8U, max > 0 ? 255.0 / max : 1.0);
  }
  return grey;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// One camera's knots tracked from one frame to the next: the state TrackKnots' steps share.
struct KnotTracking {
  const cv::Mat& to;
  const std::vector<std::pair<int, Eigen::Vector2d>>& knots;  // (knot, position in `from`)
  int rows, cols;
  const TrackOptions& options;
  std::vector<cv::Point2f> p0{}, p1{};  // per knot: its position in `from`, its flow's end in `to`
  std::vector<bool> trusted{};          // per knot: its flow passed the forward-backward check
  std::map<int, size_t> index{};        // a knot's index in `knots`
  std::vector<TrackedKnot> out{};       // per knot of `knots`
  std::map<int, KnownMotion> known{};   // knots not tracked whose motion is known

  void Flow(const cv::Mat& from);
  bool Snap(size_t i, const Eigen::Vector2d& predicted, TrackedKnot* t) const;
  std::vector<Eigen::Vector2d> Links(size_t i) const;
  std::optional<Junction> FitAlongLinks(size_t i, int degree,
                                        const Eigen::Vector2d& predicted) const;
  bool YarnsPointAtNeighbours(size_t i, const std::vector<double>& branch_angles_rad) const;
  void SnapTrustedFlow();
  void PredictFromNeighbours();
  void CheckRelativeMotion();
  void RejectSharedJunctions();
};

// Lucas-Kanade flow forwards and back (p0, p1); a knot's flow is trusted when both ways
// succeed and the way back returns within max_fb_error_px.
void KnotTracking::Flow(const cv::Mat& from) {
  // Thin yarns vanish in the flow's coarse pyramid levels: blurred first, they stay visible.
  cv::Mat a, b;
  cv::GaussianBlur(Grey8(from), a, cv::Size(), options.flow_blur_px);
  cv::GaussianBlur(Grey8(to), b, cv::Size(), options.flow_blur_px);
  std::vector<cv::Point2f> back;
  for (const auto& [k, px] : knots)
    p0.emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
  std::vector<uchar> ok_forward, ok_back;
  std::vector<float> err;
  const cv::Size window(options.window_px, options.window_px);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.001);
  cv::calcOpticalFlowPyrLK(a, b, p0, p1, ok_forward, err, window, options.pyramid_levels, stop, 0,
                           options.min_eigenvalue);
  cv::calcOpticalFlowPyrLK(b, a, p1, back, ok_back, err, window, options.pyramid_levels, stop, 0,
                           options.min_eigenvalue);
  // Flow per knot, where trusted.
  trusted.assign(knots.size(), false);
  for (size_t i = 0; i < knots.size(); ++i) {
    index[knots[i].first] = i;
    const double fb = std::hypot(back[i].x - p0[i].x, back[i].y - p0[i].y);
    trusted[i] = ok_forward[i] && ok_back[i] && fb <= options.max_fb_error_px;
  }
}

// The knot detector's brush at a prediction, snap radius wide: true when exactly one junction
// of the knot's degree (2 corner, 3 edge, 4 inner) is there (t->px set to it), else false with
// the reason (t->px the best position there is).
bool KnotTracking::Snap(size_t i, const Eigen::Vector2d& predicted, TrackedKnot* t) const {
  const int k = knots[i].first, r = k / cols, c = k % cols;
  const int degree = (r > 0) + (r + 1 < rows) + (c > 0) + (c + 1 < cols);
  const KnotDetector detector(
      to, FindNodeRegion(predicted, options.snap_radius_px, options.detector), options.detector);
  std::vector<Junction> near =
      FindNode(detector, predicted, options.snap_radius_px, degree == 2).candidates;
  if (near.empty())
    if (const std::optional<Junction> j = FitAlongLinks(i, degree, predicted)) near.push_back(*j);
  t->px = predicted;
  t->predicted = predicted;
  t->one_yarn_short = false;
  t->branch_angles_rad.clear();
  if (near.empty()) {
    if (t->why.empty()) {
      char why[64];
      std::snprintf(why, sizeof why, "no junction within %.1f px of the flow",
                    options.snap_radius_px);
      t->why = why;
    }
    return false;
  }
  if (near.size() > 1) {
    t->why = std::to_string(near.size()) + " junctions within the snap radius";
    return false;
  }
  const Junction& j = near[0];
  // Only a corner knot sits in a blob (its corner mass); elsewhere a blob is yarns bunched in a
  // fold (one once took an inner knot 2.7 px off).
  if (j.solid && degree != 2) {
    t->why = "a blob there, no yarn junction (the knot has no corner mass)";
    return false;
  }
  // A corner mass whose outline is cut (the target's edge across it, a yarn in front of it):
  // its centre is not where the knot is.
  if (j.solid && j.solid_cut) {
    t->px = j.px;
    t->why = "the corner mass's outline is cut (not round): its centre is uncertain";
    return false;
  }
  t->px = j.px;
  t->confidence = j.confidence;
  t->branch_angles_rad = j.solid ? std::vector<double>{} : j.branch_angles_rad;
  // At the edge of a body behind the net (the target's outline), the edge and a yarn make a
  // junction too, and a knot just behind the edge shows the yarns on this side only: there
  // the junction must have the knot's degree, each yarn leading to one of its neighbours.
  if (options.body_edge_px > 0.0 && !j.solid &&
      detector.NearBackgroundEdge(j.px, options.body_edge_px) &&
      (j.branches != degree || !YarnsPointAtNeighbours(i, j.branch_angles_rad))) {
    t->why =
        "at the edge of the target, a yarn short or with a yarn that leads to no "
        "neighbour (it may be behind the target)";
    return false;
  }
  if (j.branches == degree) return true;
  // One yarn short (a dim dye, a yarn that fades against the target) is the knot when each
  // yarn found leads to one of its own neighbours, and, on a knotless net, where its straight
  // pair's colour changes.
  const bool short_one = options.max_yarn_angle_deg > 0 && degree >= 3 &&
                         j.branches == degree - 1 && YarnsPointAtNeighbours(i, j.branch_angles_rad);
  char why[128];
  if (!short_one) {
    std::snprintf(why, sizeof why, "the junction there has %d yarns, the knot %d", j.branches,
                  degree);
    t->why = why;
    return false;
  }
  if (!ColourChangesAt(j, options.edge_colour_step_px)) {
    std::snprintf(why, sizeof why,
                  "the junction there has %d yarns, and the colours of its straight yarns "
                  "change %.1f px from it",
                  j.branches, (j.colour_step - j.px).norm());
    t->why = why;
    return false;
  }
  t->one_yarn_short = true;
  return true;
}

// The image vectors from knot i to each of its grid neighbours, as they lay in `from`; a
// neighbour not labeled there gives none.
std::vector<Eigen::Vector2d> KnotTracking::Links(size_t i) const {
  const auto& [k, px] = knots[i];
  const int r = k / cols, c = k % cols;
  std::vector<Eigen::Vector2d> towards;
  for (const auto& [dr, dc] :
       {std::pair(0, -1), std::pair(0, 1), std::pair(-1, 0), std::pair(1, 0)}) {
    if (r + dr < 0 || r + dr >= rows || c + dc < 0 || c + dc >= cols) continue;
    const int n = (r + dr) * cols + c + dc;
    const auto it = index.find(n);
    const auto kn = known.find(n);
    if (it == index.end() && kn == known.end()) continue;
    towards.push_back((it != index.end() ? knots[it->second].second : kn->second.from) - px);
  }
  return towards;
}

// Knot i's yarns fitted along its links near `predicted`, where every one of its `degree`
// neighbours was labeled in `from` (between frames a mesh turns by a degree or two); within the
// snap radius, or nullopt.
std::optional<Junction> KnotTracking::FitAlongLinks(size_t i, int degree,
                                                    const Eigen::Vector2d& predicted) const {
  const std::vector<Eigen::Vector2d> links = Links(i);
  if (static_cast<int>(links.size()) != degree) return std::nullopt;
  const std::optional<Junction> j =
      recon::FitAlongLinks(to, predicted, links, options.fit_along_gap_px, options.detector);
  if (!j || (j->px - predicted).norm() > options.snap_radius_px) return std::nullopt;
  return j;
}

// Whether every yarn of junction `j` (knot i's, in `to`) leaves towards a different grid
// neighbour of the knot labeled in `from`, within max_yarn_angle_deg (between frames a mesh
// turns by a degree or two). A neighbour not labeled gives no direction: its yarn cannot be
// told from another.
bool KnotTracking::YarnsPointAtNeighbours(size_t i,
                                          const std::vector<double>& branch_angles_rad) const {
  std::vector<double> towards;
  for (const Eigen::Vector2d& d : Links(i)) towards.push_back(std::atan2(d.y(), d.x()));
  std::vector<bool> taken(towards.size(), false);
  const double limit = options.max_yarn_angle_deg * M_PI / 180.0;
  for (const double a : branch_angles_rad) {
    int best = -1;
    double best_off = limit;
    for (size_t n = 0; n < towards.size(); ++n) {
      const double off = std::abs(std::remainder(a - towards[n], 2.0 * M_PI));
      if (!taken[n] && off <= best_off) best = static_cast<int>(n), best_off = off;
    }
    if (best < 0) return false;
    taken[best] = true;
  }
  return true;
}

// Knots with trusted flow: snapped at the flow's end.
void KnotTracking::SnapTrustedFlow() {
  for (size_t i = 0; i < knots.size(); ++i) {
    out[i].knot = knots[i].first;
    if (trusted[i]) out[i].accepted = Snap(i, Eigen::Vector2d(p1[i].x, p1[i].y), &out[i]);
  }
}

// Knots without: predicted from their grid neighbours' motion (an occluded knot moves with
// the net): an accepted neighbour's motion is its junction's, else its trusted flow's. In
// rounds, as knots accepted in one round give the next their motion. Accepted when at least
// two accepted neighbours move as one (within max_neighbour_spread_px of their median).
void KnotTracking::PredictFromNeighbours() {
  std::vector<bool> done(knots.size(), false);
  std::vector<int> last_confirmed(knots.size(), -1);
  for (size_t i = 0; i < knots.size(); ++i) done[i] = trusted[i];
  for (bool progress = true; progress;) {
    progress = false;
    for (size_t i = 0; i < knots.size(); ++i) {
      if (done[i]) continue;
      const auto& [k, px] = knots[i];
      const int r = k / cols;
      std::vector<Eigen::Vector2d> moves, confirmed;
      for (int n : {k - 1, k + 1, k - cols, k + cols}) {
        if (n < 0 || n >= rows * cols || (std::abs(n - k) == 1 && n / cols != r)) continue;
        const auto it = index.find(n);
        if (it == index.end()) {
          const auto kn = known.find(n);
          if (kn != known.end()) {
            moves.push_back(kn->second.to - kn->second.from);
            confirmed.push_back(moves.back());
          }
          continue;
        }
        const size_t j = it->second;
        if (out[j].accepted) {
          moves.push_back(out[j].px - knots[j].second);
          confirmed.push_back(moves.back());
        } else if (trusted[j]) {
          moves.emplace_back(p1[j].x - knots[j].second.x(), p1[j].y - knots[j].second.y());
        }
      }
      if (moves.empty()) {
        out[i].px = px;
        out[i].why = "no trusted flow for the knot or its neighbours";
        continue;
      }
      // Two confirmed motions or more predict alone.
      const std::vector<Eigen::Vector2d>& used = confirmed.size() >= 2 ? confirmed : moves;
      std::vector<double> dx, dy;
      for (const auto& m : used) dx.push_back(m.x()), dy.push_back(m.y());
      const Eigen::Vector2d median(Median(dx), Median(dy));
      double spread = 0.0;
      for (const auto& m : used) spread = std::max(spread, (m - median).norm());
      // Snapped again only when more neighbours are confirmed than the last time.
      if (static_cast<int>(confirmed.size()) == last_confirmed[i]) continue;
      last_confirmed[i] = static_cast<int>(confirmed.size());
      TrackedKnot& t = out[i];
      t = TrackedKnot{};
      t.knot = k;
      t.why = "flow lost (forward-backward check); predicted from the neighbours' motion";
      if (!Snap(i, px + median, &t)) continue;
      if (confirmed.size() >= 2 && options.max_neighbour_spread_px > 0 &&
          spread <= options.max_neighbour_spread_px) {
        t.accepted = true;
        t.why.clear();
        done[i] = progress = true;
      }
    }
  }
}

// Every accepted knot moved as its accepted neighbours did (their motions as they were before
// this check: a knot that fails it does not take its neighbours with it). A knot's
// neighbours make it expect the mean motion of each pair of opposite ones (left and right, up
// and down), of each parallelogram with a diagonal one (right + down - down-right; both exact
// for a net that moves, turns and stretches evenly) and of its side neighbours together
// (where the net only moves). It fails when it is far from all of them: one neighbour off
// leaves another expectation right.
void KnotTracking::CheckRelativeMotion() {
  std::vector<bool> accepted(out.size());
  for (size_t i = 0; i < out.size(); ++i) accepted[i] = out[i].accepted;
  auto motion = [&](int r, int c) -> std::optional<Eigen::Vector2d> {
    if (r < 0 || c < 0 || r >= rows || c >= cols) return std::nullopt;
    const auto it = index.find(r * cols + c);
    if (it == index.end()) {
      const auto kn = known.find(r * cols + c);
      if (kn == known.end()) return std::nullopt;
      return kn->second.to - kn->second.from;
    }
    if (!accepted[it->second]) return std::nullopt;
    return out[it->second].px - knots[it->second].second;
  };
  for (size_t i = 0; i < out.size(); ++i) {
    if (!accepted[i]) continue;
    const int k = knots[i].first, r = k / cols, c = k % cols;
    std::vector<Eigen::Vector2d> expected;
    for (const auto& [one, other] : {std::pair(motion(r, c - 1), motion(r, c + 1)),
                                     std::pair(motion(r - 1, c), motion(r + 1, c))})
      if (one && other) expected.push_back(0.5 * (*one + *other));
    for (int dr : {-1, 1})
      for (int dc : {-1, 1}) {
        const auto up = motion(r + dr, c), side = motion(r, c + dc),
                   diagonal = motion(r + dr, c + dc);
        if (up && side && diagonal) expected.push_back(*up + *side - *diagonal);
      }
    Eigen::Vector2d sides = Eigen::Vector2d::Zero();
    int n = 0;
    for (const auto& m : {motion(r, c - 1), motion(r, c + 1), motion(r - 1, c), motion(r + 1, c)})
      if (m) sides += *m, ++n;
    if (n >= 2) expected.push_back(sides / n);
    // A junction one yarn short is the knot only where its neighbours' motion says so: in the
    // bunched Net B at 0.8 m/s three such junctions, in folds with no accepted neighbour
    // around, were accepted 2.1-2.7 px off.
    if (expected.empty() && out[i].one_yarn_short) {
      out[i].accepted = false;
      out[i].why = "the junction there has a yarn too few, and no accepted neighbour moved with it";
      continue;
    }
    // With nothing to check its motion, a junction's yarns must each lead to one of the knot's
    // neighbours: another layer's yarn crossing the row 2 px from the knot made a junction of
    // the knot's degree in a fold (Net B at 0.8 m/s).
    if (expected.empty()) {
      const std::vector<double>& yarns = out[i].branch_angles_rad;
      if (!yarns.empty() && !YarnsPointAtNeighbours(i, yarns)) {
        out[i].accepted = false;
        out[i].why =
            "no accepted neighbour moved with it, and a yarn of its junction leads to "
            "no neighbour";
      }
      continue;
    }
    const Eigen::Vector2d own = out[i].px - knots[i].second;
    double off = std::numeric_limits<double>::infinity();
    for (const auto& e : expected) off = std::min(off, (own - e).norm());
    if (off <= options.max_relative_motion_px) continue;
    char why[96];
    std::snprintf(why, sizeof why, "moved %.1f px otherwise than its accepted neighbours", off);
    out[i].accepted = false;
    out[i].why = why;
  }
}

// Two knots on one junction: neither is trusted; nor a knot on another's known place.
void KnotTracking::RejectSharedJunctions() {
  for (TrackedKnot& t : out)
    for (const auto& [k, m] : known)
      if (t.accepted && (t.px - m.to).norm() < options.snap_radius_px) {
        t.accepted = false;
        t.why = "another knot's label is there";
      }
  for (size_t i = 0; i < out.size(); ++i)
    for (size_t j = i + 1; j < out.size(); ++j)
      if ((out[i].px - out[j].px).norm() < options.snap_radius_px) {
        for (TrackedKnot* t : {&out[i], &out[j]}) {
          if (t->accepted) t->why = "another knot tracked onto the same place";
          t->accepted = false;
        }
      }
}

}  // namespace

std::vector<TrackedKnot> TrackKnots(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<std::pair<int, Eigen::Vector2d>>& knots,
                                    int rows, int cols, const TrackOptions& options,
                                    const std::vector<KnownMotion>& known) {
  if (knots.empty()) return {};
  KnotTracking tracking{to, knots, rows, cols, options};
  for (const KnownMotion& m : known) tracking.known[m.knot] = m;
  tracking.out.resize(knots.size());
  // The flow, forwards and back.
  tracking.Flow(from);
  // Knots with trusted flow snapped at its end; the others predicted from their neighbours.
  tracking.SnapTrustedFlow();
  tracking.PredictFromNeighbours();
  // The accepted knots checked against their neighbours' motion, and against each other.
  if (options.max_relative_motion_px > 0.0) tracking.CheckRelativeMotion();
  tracking.RejectSharedJunctions();
  return std::move(tracking.out);
}

}  // namespace netlab::recon
