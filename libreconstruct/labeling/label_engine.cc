#include "libreconstruct/labeling/label_engine.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "libreconstruct/geometry/point_motion.h"
#include "libreconstruct/geometry/triangulation.h"

namespace netlab::recon {
namespace {

Label Made(const Eigen::Vector2d& px, LabelSource source, double confidence, bool accepted) {
  Label l;
  l.px = px;
  l.source = source;
  l.confidence = static_cast<float>(std::clamp(confidence, 0.0, 1.0));
  l.state = accepted ? LabelState::kAccepted : LabelState::kNeedsReview;
  return l;
}

// Whether a tool may put a label where `l` is: no label there, and no hidden mark (the person
// said the knot is not visible there; only the person's own click replaces that).
bool Free(const Label& l) { return !l.present() && !l.hidden(); }

std::optional<std::pair<int, double>> ViewOffTheOthers(const calib::Rig& rig,
                                                       const std::vector<Observation>& obs,
                                                       const TriangulationOptions& topt,
                                                       double tolerance, double sigma);
std::optional<double> OffTheViews(const calib::Rig& rig, const Observation& view,
                                  const std::vector<Observation>& others,
                                  const TriangulationOptions& topt, double tolerance, double sigma);

void Add(EngineCounts* sum, const EngineCounts& n);

// Whether a label is an observation of its own: accepted, and not placed from the other
// cameras' labels (LabelSource::kProjected), which would only repeat them.
bool Observed(const Label& l) { return l.accepted() && l.source != LabelSource::kProjected; }

// A projection's standard deviation along its worst axis for `sigma` px of noise in each view.
double WorstSigma(const ProjectedPoint& q, double sigma) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(q.unit_covariance);
  return sigma * std::sqrt(std::max(0.0, eig.eigenvalues()[1]));
}

// Find Node's junction is confirmed by the knot's path, or by the other cameras' place, only
// where that fixes the knot to this (px; the path and the place's standard deviation).
constexpr double kPathCheckSigmaPx = 1.0;

// The 99.9 % quantile of chi^2 with `dof` degrees of freedom (Wilson and Hilferty's cube-root
// normal approximation, a little above the exact value: 2.3 % at 2 degrees of freedom, 1.0 % at
// 6, 0.3 % at 20). The exact one, netsim::Chi2Quantile, is the score's (libnetsim/validation),
// which labeling may not use.
double Chi2Quantile999(int dof) {
  const double k = dof, z = 3.0902;  // the normal's 99.9 % quantile
  const double c = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * c * c * c;
}

// A distance in px as the messages print it (one decimal).
std::string Px(double px) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", px);
  return text;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The image directions of a knot's links whose direction is known, seen from `at`: towards a
// known neighbour, or away from the known opposite one.
std::vector<double> KnownLinkAngles(const Eigen::Vector2d& at, const NeighbourSlots& slots) {
  std::vector<double> angles;
  for (int s = 0; s < 4; ++s) {
    if (!slots.present[s]) continue;
    const int o = (s + 2) % 4;
    Eigen::Vector2d d;
    if (slots.px[s])
      d = *slots.px[s] - at;
    else if (slots.present[o] && slots.px[o])
      d = at - *slots.px[o];
    else
      continue;
    angles.push_back(std::atan2(d.y(), d.x()));
  }
  return angles;
}

// Whether a junction is the knot, judged by its yarns: as many branches as the knot has links,
// each link's direction (KnownLinkAngles) reached by a branch within `tolerance_deg`, and no
// branch left over where every link's direction is known. A junction that fails is not this
// knot, or not only this knot: a yarn passing the corner of the target box makes a junction of
// yarn and box edges there. With `hidden_yarns` (a person pointed at the knot) fewer branches
// may be seen: a link's yarn may be hidden, but two branches at least must run along known
// links, and no branch elsewhere.
bool BranchesMatchLinks(const Junction& j, const NeighbourSlots& slots, double tolerance_deg,
                        bool hidden_yarns = false) {
  const int degree = static_cast<int>(std::count(slots.present.begin(), slots.present.end(), true));
  const std::vector<double> expected = KnownLinkAngles(j.px, slots);
  const int known = static_cast<int>(expected.size());
  const bool count_ok =
      hidden_yarns ? j.branches >= 2 && j.branches <= degree : j.branches == degree;
  if (!count_ok || known < 2) return false;
  const double tol = tolerance_deg * M_PI / 180.0;
  auto gap = [](double a, double b) { return std::abs(std::remainder(a - b, 2.0 * M_PI)); };
  if (!hidden_yarns)
    for (double e : expected) {
      double best = M_PI;
      for (double b : j.branch_angles_rad) best = std::min(best, gap(b, e));
      if (best > tol) return false;
    }
  int unmatched = 0;
  for (double b : j.branch_angles_rad) {
    double best = M_PI;
    for (double e : expected) best = std::min(best, gap(b, e));
    unmatched += best > tol;
  }
  if (hidden_yarns && j.branches - unmatched < 2) return false;
  return unmatched <= degree - known;
}

}  // namespace

LabelEngine::LabelEngine(LabelStore* store, const calib::Rig* rig, ImageSource images,
                         LabelEngineOptions options)
    : store_(store), rig_(rig), images_(std::move(images)), o_(std::move(options)) {
  const LabelSet& set = store_->labels();
  rig_index_.assign(set.cameras.size(), -1);
  if (rig_)
    for (size_t c = 0; c < set.cameras.size(); ++c) {
      rig_index_[c] = rig_->Find(set.cameras[c]);
      if (rig_index_[c] < 0)
        throw std::invalid_argument("the rig has no camera '" + set.cameras[c] + "'");
    }
  link_length_m_ = o_.link_length_m;
  // A knotless net's edge colour check, in every tool's detector and in tracking.
  if (o_.edge_colour_step_px > 0.0) {
    o_.detector.colour_step = o_.track.detector.colour_step = true;
    if (!(o_.track.edge_colour_step_px > 0.0))
      o_.track.edge_colour_step_px = o_.edge_colour_step_px;
  }
}

const cv::Mat& LabelEngine::Image(int camera, int t) {
  const auto key = std::make_pair(camera, t);
  auto it = cache_.find(key);
  if (it != cache_.end()) return it->second;
  // Keep two frames per camera: the pair being tracked.
  for (auto i = cache_.begin(); i != cache_.end();)
    i = i->first.first == camera && std::abs(i->first.second - t) > 1 ? cache_.erase(i) : ++i;
  return cache_.emplace(key, images_(camera, t)).first->second;
}

void LabelEngine::Note(int camera, int t, int knot, const std::string& why) {
  if (why.empty())
    reasons_.erase({camera, t, knot});
  else
    reasons_[{camera, t, knot}] = why;
}

void LabelEngine::ToReview(int camera, int t, int knot, const std::string& why,
                           std::vector<LabelEdit>* flags) {
  Label l = store_->labels().at(camera, t, knot);
  l.state = LabelState::kNeedsReview;
  flags->push_back({camera, t, knot, l});
  Note(camera, t, knot, why);
}

EngineCounts LabelEngine::Commit(const std::string& name, const std::vector<LabelEdit>& edits) {
  EngineCounts n;
  for (const auto& e : edits) {
    if (e.label.state == LabelState::kAccepted) {
      ++n.accepted;
      Note(e.camera, e.t, e.knot, "");
    } else if (e.label.state == LabelState::kNeedsReview) {
      ++n.review;
    }
  }
  store_->Apply(name, edits);
  return n;
}

NeighbourSlots LabelEngine::Slots(int camera, int t, int knot,
                                  const std::vector<std::optional<Eigen::Vector3d>>& point) const {
  const LabelSet& set = store_->labels();
  const std::array<int, 4> slot_knot = SlotKnots(knot);
  NeighbourSlots slots;
  for (int s = 0; s < 4; ++s) {
    const int n = slot_knot[s];
    if (n < 0) continue;
    slots.present[s] = true;
    const Label& l = set.at(camera, t, n);
    if (l.accepted()) {
      slots.px[s] = l.px;
    } else if (rig_ && n < static_cast<int>(point.size()) && point[n]) {
      const Eigen::Vector2d q = rig_->cameras[RigIndex(camera)].ProjectWorld(*point[n]);
      if (q.allFinite()) slots.px[s] = q;
    }
  }
  return slots;
}

std::array<int, 4> GridSlots(int rows, int cols, int knot) {
  const int r = knot / cols, c = knot % cols;
  return {c + 1 < cols ? knot + 1 : -1, r + 1 < rows ? knot + cols : -1, c > 0 ? knot - 1 : -1,
          r > 0 ? knot - cols : -1};
}

YarnDirections AcceptedNeighbourYarns(const LabelSet& set, int camera, int t, int knot) {
  YarnDirections yarns;
  const std::array<int, 4> slot_knot = GridSlots(set.rows, set.cols, knot);
  for (int s = 0; s < 4; ++s)
    if (slot_knot[s] >= 0 && set.at(camera, t, slot_knot[s]).accepted())
      yarns.neighbour_px[s] = set.at(camera, t, slot_knot[s]).px;
  return yarns;
}

std::array<int, 4> LabelEngine::SlotKnots(int knot) const {
  return GridSlots(store_->labels().rows, store_->labels().cols, knot);
}

std::vector<int> LabelEngine::Neighbours(int knot) const {
  std::vector<int> n;  // right, down, left, up
  for (int k : SlotKnots(knot))
    if (k >= 0) n.push_back(k);
  return n;
}

void LabelEngine::FindFarSides(int camera, int t, const cv::Mat& image,
                               const std::function<std::optional<Eigen::Vector2d>(int)>& px,
                               std::vector<LabelEdit>* edits,
                               std::map<int, Junction>* junction_of) {
  const LabelSet& set = store_->labels();
  const int rows = set.rows, cols = set.cols;
  // The unseeded corner's row and column.
  int far_row = 0, far_col = 0;
  for (int k : {0, cols - 1, (rows - 1) * cols, rows * cols - 1})
    if (!set.at(camera, t, k).present()) far_row = k / cols, far_col = k % cols;
  // The knots found along the other two sides: the grid's map into the image.
  std::vector<cv::Point2f> grid, image_px;
  for (int k = 0; k < rows * cols; ++k) {
    const int r = k / cols, c = k % cols;
    if (r == far_row || c == far_col) continue;
    if ((r != 0 && r != rows - 1) && (c != 0 && c != cols - 1)) continue;
    if (const auto p = px(k)) {
      grid.emplace_back(static_cast<float>(c), static_cast<float>(r));
      image_px.emplace_back(static_cast<float>(p->x()), static_cast<float>(p->y()));
    }
  }
  if (grid.size() < 6) return;
  const cv::Mat h = cv::findHomography(grid, image_px, 0);
  if (h.empty()) return;
  auto predict = [&](int r, int c) {
    std::vector<cv::Point2f> in{{static_cast<float>(c), static_cast<float>(r)}}, out;
    cv::perspectiveTransform(in, out, h);
    return Eigen::Vector2d(out[0].x, out[0].y);
  };
  for (int k = 0; k < rows * cols; ++k) {
    const int r = k / cols, c = k % cols;
    if ((r != far_row && c != far_col) || (r == far_row && c == far_col) || px(k) ||
        set.at(camera, t, k).hidden())
      continue;
    // A brush of a third of a link: the nearest other knot is two thirds away, or more.
    const Eigen::Vector2d p = predict(r, c);
    const double link_px = std::min((predict(r, c + 1) - p).norm(), (predict(r + 1, c) - p).norm());
    const FindNodeResult found = FindNode(image, p, link_px / 3.0, o_.detector);
    if (found.status != FindNodeStatus::kFound || found.knot.solid) continue;
    // Accepted only if its yarns then leave it towards its neighbours (checked with the rest).
    edits->push_back(
        {camera, t, k, Made(found.knot.px, LabelSource::kFindPath, found.knot.confidence, true)});
    (*junction_of)[k] = found.knot;
  }
}

EngineCounts LabelEngine::LabelFirstFrame(int t) {
  const LabelSet& set = store_->labels();
  const int rows = set.rows, cols = set.cols;
  const int corners[4] = {0, cols - 1, (rows - 1) * cols, rows * cols - 1};
  std::vector<LabelEdit> edits;
  for (int camera = 0; camera < static_cast<int>(set.cameras.size()); ++camera) {
    int seeded = 0;
    for (int k : corners) seeded += set.at(camera, t, k).present();
    if (seeded < 3) continue;
    const cv::Mat& image = Image(camera, t);
    if (image.empty()) continue;
    const size_t first_edit = edits.size();
    std::map<int, Junction> junction_of;  // the junction Find Path took for each knot
    auto px = [&](int k) -> std::optional<Eigen::Vector2d> {
      for (size_t i = first_edit; i < edits.size(); ++i)
        if (edits[i].knot == k) return edits[i].label.px;
      const Label& l = set.at(camera, t, k);
      if (l.present()) return l.px;
      return std::nullopt;
    };
    auto path = [&](int a, int b) {
      const auto pa = px(a), pb = px(b);
      if (!pa || !pb) return FindPathResult{};
      return FindPath(image, cols, a, *pa, b, *pb, o_.detector);
    };
    // The four sides: each knot from one path (its junction count checked against the grid).
    for (const auto& [a, b] :
         {std::pair(corners[0], corners[1]), std::pair(corners[2], corners[3]),
          std::pair(corners[0], corners[2]), std::pair(corners[1], corners[3])}) {
      const FindPathResult r = path(a, b);
      for (size_t i = 0; i < r.knots.size(); ++i)
        if (Free(set.at(camera, t, r.knots[i]))) {
          edits.push_back(
              {camera, t, r.knots[i],
               Made(r.junctions[i].px, LabelSource::kFindPath, r.junctions[i].confidence, true)});
          junction_of[r.knots[i]] = r.junctions[i];
        }
    }
    // A corner hidden (behind the target, say): the knots of its two sides where the grid of the
    // other two sides puts them, so that the rows and columns can still be followed.
    if (seeded == 3) FindFarSides(camera, t, image, px, &edits, &junction_of);
    // Inner knots: along their row and along their column; both must agree.
    std::map<int, Eigen::Vector2d> by_row, by_column;
    std::map<int, double> confidence;
    for (int row = 1; row + 1 < rows; ++row) {
      const FindPathResult r = path(row * cols, row * cols + cols - 1);
      for (size_t i = 0; i < r.knots.size(); ++i) {
        by_row[r.knots[i]] = r.junctions[i].px;
        junction_of[r.knots[i]] = r.junctions[i];
        confidence[r.knots[i]] = r.junctions[i].confidence;
      }
    }
    for (int col = 1; col + 1 < cols; ++col) {
      const FindPathResult r = path(col, (rows - 1) * cols + col);
      for (size_t i = 0; i < r.knots.size(); ++i) {
        by_column[r.knots[i]] = r.junctions[i].px;
        const auto c = confidence.find(r.knots[i]);
        confidence[r.knots[i]] =
            std::min(c == confidence.end() ? 1.0 : c->second, r.junctions[i].confidence);
      }
    }
    for (int row = 1; row + 1 < rows; ++row)
      for (int col = 1; col + 1 < cols; ++col) {
        const int k = row * cols + col;
        if (!Free(set.at(camera, t, k))) continue;
        const auto a = by_row.find(k), b = by_column.find(k);
        if (a == by_row.end() && b == by_column.end()) continue;
        const bool both = a != by_row.end() && b != by_column.end();
        const bool agree = both && (a->second - b->second).norm() < o_.row_column_agreement_px;
        const Eigen::Vector2d where = a != by_row.end() ? a->second : b->second;
        edits.push_back({camera, t, k, Made(where, LabelSource::kFindPath, confidence[k], agree)});
        if (!both) one_path_.insert({camera, t, k});
        if (!agree)
          Note(camera, t, k,
               both ? "Find Path: its row and its column put it " +
                          std::to_string((a->second - b->second).norm()) + " px apart"
                    : "Find Path: found along its row or its column only");
      }
    // Every accepted knot's yarns must leave it towards its neighbours found along the paths
    // (the count, spacing and row-column checks do not see a junction of a yarn and the target
    // box's edges taken for a knot missed beside it).
    for (size_t i = first_edit; i < edits.size(); ++i) {
      LabelEdit& e = edits[i];
      if (e.label.state != LabelState::kAccepted) continue;
      NeighbourSlots slots;
      const std::array<int, 4> slot_knot = SlotKnots(e.knot);
      for (int s = 0; s < 4; ++s) {
        slots.present[s] = slot_knot[s] >= 0;
        if (slots.present[s]) slots.px[s] = px(slot_knot[s]);
      }
      const auto j = junction_of.find(e.knot);
      if (j != junction_of.end() && BranchesMatchLinks(j->second, slots, o_.branch_tolerance_deg))
        continue;
      e.label.state = LabelState::kNeedsReview;
      Note(camera, t, e.knot,
           "Find Path: the junction's yarns do not leave it towards its neighbours");
    }
  }
  return Commit("Find Path (frame row " + std::to_string(t) + ")", edits);
}

EngineCounts LabelEngine::FillByPaths(int t) {
  const LabelSet& set = store_->labels();
  const int rows = set.rows, cols = set.cols;
  std::vector<LabelEdit> edits;
  for (int camera = 0; camera < static_cast<int>(set.cameras.size()); ++camera) {
    const cv::Mat& image = Image(camera, t);
    if (image.empty()) continue;
    // Each knot between two accepted ones of its row (by_row) or column (by_column): the
    // junction its path took.
    std::map<int, Junction> by_row, by_column;
    auto follow = [&](const std::vector<int>& line, std::map<int, Junction>* found) {
      int last = -1;  // index in `line` of the last accepted knot
      for (int i = 0; i < static_cast<int>(line.size()); ++i) {
        const Label& l = set.at(camera, t, line[i]);
        if (l.hidden()) {
          last = -1;
          continue;
        }
        if (!l.accepted()) continue;
        if (last >= 0 && i - last >= 2) {
          const FindPathResult r =
              FindPath(image, cols, line[last], set.at(camera, t, line[last]).px, line[i], l.px,
                       o_.detector);
          for (size_t n = 0; n < r.knots.size(); ++n) (*found)[r.knots[n]] = r.junctions[n];
        }
        last = i;
      }
    };
    for (int r = 0; r < rows; ++r) {
      std::vector<int> line;
      for (int c = 0; c < cols; ++c) line.push_back(r * cols + c);
      follow(line, &by_row);
    }
    for (int c = 0; c < cols; ++c) {
      std::vector<int> line;
      for (int r = 0; r < rows; ++r) line.push_back(r * cols + c);
      follow(line, &by_column);
    }
    // The knots found: accepted where row and column agree and the junction's yarns leave
    // towards its neighbours (the accepted ones and those found here).
    std::map<int, Eigen::Vector2d> found_px;
    for (const auto* m : {&by_row, &by_column})
      for (const auto& [k, j] : *m) found_px.emplace(k, j.px);
    for (const auto& [k, where] : found_px) {
      const Label& l = set.at(camera, t, k);
      if (l.accepted() || l.hidden()) continue;
      const auto a = by_row.find(k), b = by_column.find(k);
      const bool both = a != by_row.end() && b != by_column.end();
      const Junction& j = a != by_row.end() ? a->second : b->second;
      NeighbourSlots slots;
      const std::array<int, 4> slot_knot = SlotKnots(k);
      for (int s = 0; s < 4; ++s) {
        const int n = slot_knot[s];
        slots.present[s] = n >= 0;
        if (n < 0) continue;
        if (set.at(camera, t, n).accepted())
          slots.px[s] = set.at(camera, t, n).px;
        else if (found_px.count(n))
          slots.px[s] = found_px.at(n);
      }
      const bool agree = both &&
                         (a->second.px - b->second.px).norm() < o_.row_column_agreement_px &&
                         BranchesMatchLinks(j, slots, o_.branch_tolerance_deg) &&
                         ColourChangesAt(j, o_.edge_colour_step_px);
      if (agree) {
        edits.push_back({camera, t, k, Made(j.px, LabelSource::kFindPath, j.confidence, true)});
      } else if (!l.present() && !both) {
        edits.push_back({camera, t, k, Made(j.px, LabelSource::kFindPath, j.confidence, false)});
        one_path_.insert({camera, t, k});
        Note(camera, t, k, "Find Path: found along its row or its column only");
      }
    }
  }
  return Commit("Find Path between labeled knots (frame row " + std::to_string(t) + ")", edits);
}

EngineCounts LabelEngine::FillByPathsAndCheck(int t) {
  EngineCounts counts = FillByPaths(t);
  if (counts.accepted > 0) Add(&counts, CrossCheck(t));
  return counts;
}

namespace {

// Whether tracking from `from` may write `to`: where there is no label yet, and where the label
// there was tracked from one under review while `from` has since been accepted (a person checked
// the origin: its track is followed again, with tracking's own checks; nothing else is replaced).
bool Trackable(const Label& to, const Label& from) {
  if (Free(to)) return true;
  return from.accepted() && to.state == LabelState::kNeedsReview &&
         to.source == LabelSource::kTracked;
}

}  // namespace

EngineCounts LabelEngine::Track(int from, int to) {
  const LabelSet& set = store_->labels();
  // One camera's tracking: its knots to track, and what TrackKnots made of them.
  struct CameraTrack {
    std::vector<std::pair<int, Eigen::Vector2d>> knots;
    std::vector<bool> was_accepted;
    std::vector<bool> from_hand;     // placed by the person in `from`
    std::vector<KnownMotion> known;  // knots accepted in both frames, not tracked again
    const cv::Mat* a = nullptr;
    const cv::Mat* b = nullptr;
    std::vector<TrackedKnot> tracked;
  };
  const int n_cam = static_cast<int>(set.cameras.size());
  std::vector<CameraTrack> jobs(n_cam);
  for (int camera = 0; camera < n_cam; ++camera) {
    CameraTrack& job = jobs[camera];
    for (int k = 0; k < set.knots(); ++k) {
      const Label& l = set.at(camera, from, k);
      if (!l.present()) continue;
      if (!Trackable(set.at(camera, to, k), l)) {
        if (l.accepted() && set.at(camera, to, k).accepted())
          job.known.push_back({k, l.px, set.at(camera, to, k).px});
        continue;
      }
      job.knots.emplace_back(k, l.px);
      job.was_accepted.push_back(l.state == LabelState::kAccepted);
      job.from_hand.push_back(l.source == LabelSource::kManual);
    }
    if (job.knots.empty()) continue;
    // The frames are read here, one camera after the other (the cache is not shared across
    // threads); std::map keeps the references valid while other cameras' frames are added.
    const cv::Mat& a = Image(camera, from);
    const cv::Mat& b = Image(camera, to);
    if (a.empty() || b.empty()) continue;
    job.a = &a, job.b = &b;
  }
  // The cameras tracked side by side: each camera's knots depend on that camera's frames only.
#pragma omp parallel for schedule(dynamic) num_threads(std::max(1, o_.threads))
  for (int camera = 0; camera < n_cam; ++camera) {
    CameraTrack& job = jobs[camera];
    if (job.a)
      job.tracked = TrackKnots(*job.a, *job.b, job.knots, set.rows, set.cols, o_.track, job.known);
  }
  std::vector<LabelEdit> edits;
  for (int camera = 0; camera < n_cam; ++camera) {
    const CameraTrack& job = jobs[camera];
    for (size_t i = 0; i < job.tracked.size(); ++i) {
      const TrackedKnot& tk = job.tracked[i];
      // From a hand-placed label: the junction where the flow carried it, not one beside it
      // (in the wrapping, tracked labels after runs of the person's clicks took crossings
      // 2.1-3.2 px from the knot).
      const double snapped = (tk.px - tk.predicted).norm();
      const bool off_hand = tk.accepted && job.from_hand[i] && o_.from_hand_snap_px > 0.0 &&
                            !(snapped <= o_.from_hand_snap_px);
      const bool accepted = tk.accepted && job.was_accepted[i] && !off_hand;
      edits.push_back(
          {camera, to, tk.knot, Made(tk.px, LabelSource::kTracked, tk.confidence, accepted)});
      if (off_hand)
        Note(camera, to, tk.knot,
             "tracked from a label placed by hand onto a junction " + Px(snapped) +
                 " px from where the flow carried it");
      else if (!accepted)
        Note(camera, to, tk.knot, tk.accepted ? "tracked from a label under review" : tk.why);
    }
  }
  return Commit("track frame row " + std::to_string(from) + " to " + std::to_string(to), edits);
}

FindNodeResult LabelEngine::FindNodeAt(int camera, int t, int knot, const Eigen::Vector2d& centre,
                                       double radius_px) {
  const cv::Mat& image = Image(camera, t);
  if (image.empty()) {
    FindNodeResult r;
    r.why = "the frame cannot be read";
    return r;
  }
  FindNodeResult r = FindNode(image, centre, radius_px, o_.detector, Neighbours(knot).size() == 2);
  // Only a corner knot sits in a blob (its corner mass); elsewhere a blob is yarns bunched in a
  // fold (one once gave an inner knot 2.7 px off).
  if (r.status == FindNodeStatus::kFound && r.knot.solid && Neighbours(knot).size() != 2) {
    r.status = FindNodeStatus::kNone;
    r.why = "no yarn junction in the brush, only a blob (the knot has no corner mass)";
  }
  // Where the other cameras fix the knot, in the brush: it decides between several junctions,
  // and places the knot where the image shows none.
  bool by_motion = false;
  std::optional<Eigen::Vector2d> others = OthersPlace(camera, t, knot, &by_motion);
  if (others && (*others - centre).norm() > radius_px + o_.projection_tolerance_px) others.reset();
  const auto agrees = [&](const Junction& j) {
    return others && (j.px - *others).norm() <= o_.projection_tolerance_px;
  };
  if (r.status == FindNodeStatus::kSeveral && others) {
    const auto near = std::count_if(r.candidates.begin(), r.candidates.end(), agrees);
    if (near == 1) {
      r.knot = *std::find_if(r.candidates.begin(), r.candidates.end(), agrees);
      r.status = FindNodeStatus::kFound;
      r.why.clear();
    }
  }
  if (r.status == FindNodeStatus::kFound && !(others && !agrees(r.knot))) {
    // The junction, where the other cameras agree with it (their word outweighs the doubts of
    // its yarns), else judged by its yarns and the other cameras' labels.
    const std::string doubt = agrees(r.knot) ? "" : FoundNodeDoubt(camera, t, knot, r.knot);
    Commit("Find Node",
           {{camera, t, knot,
             Made(r.knot.px, LabelSource::kFindNode, r.knot.confidence, doubt.empty())}});
    if (!doubt.empty()) Note(camera, t, knot, "Find Node: " + doubt);
    return r;
  }
  // Several junctions, none where they put it: the person chooses.
  if (!others || r.status == FindNodeStatus::kSeveral) return r;
  const std::string where =
      by_motion ? "the other cameras' labels and its motion" : "the other cameras' labels";
  if (r.status == FindNodeStatus::kFound) {
    // A junction the other cameras put elsewhere: one of the two is wrong, and nothing tells
    // which. Kept for review. (Placed where they put it, Net B's 400 frames at both speeds had
    // 5 such: each placement 1.65-1.97 px off, about as far as the junction from it, one of
    // two views' labels 1.6-1.7 px off along the epipolar line, where no residual shows it.)
    Commit("Find Node",
           {{camera, t, knot, Made(r.knot.px, LabelSource::kFindNode, r.knot.confidence, false)}});
    Note(camera, t, knot,
         "Find Node: the junction is " + Px((r.knot.px - *others).norm()) + " px from where " +
             where + " put the knot");
    return r;
  }
  if (LabelNear(camera, t, knot, *others)) return r;
  // No junction: the knot where they put it.
  Junction placed;
  placed.px = *others;
  placed.confidence = 0.5;
  r.why = "no junction in the brush; placed where " + where + " put the knot";
  r.status = FindNodeStatus::kFound;
  r.knot = placed;
  r.projected = true;
  Commit("Find Node", {{camera, t, knot, Made(placed.px, LabelSource::kProjected, 0.5, true)}});
  return r;
}

int LabelEngine::CheckAgainstPerson(int t, int knot, const std::vector<int>& person) {
  if (!rig_) return 0;
  const LabelSet& set = store_->labels();
  const auto persons = [&](int c) {
    const LabelSource s = set.at(c, t, knot).source;
    return s == LabelSource::kManual || s == LabelSource::kImported ||
           std::find(person.begin(), person.end(), c) != person.end();
  };
  std::vector<Observation> obs;
  std::vector<int> from;
  for (int c = 0; c < static_cast<int>(set.cameras.size()); ++c)
    if (Observed(set.at(c, t, knot))) {
      obs.push_back({RigIndex(c), set.at(c, t, knot).px});
      from.push_back(c);
    }
  if (std::none_of(from.begin(), from.end(), persons)) return 0;
  TriangulationOptions topt;
  topt.outlier_threshold_px = o_.epipolar_tolerance_px;
  std::vector<LabelEdit> flags;
  const auto flag = [&](size_t i, const std::string& why) {
    ToReview(from[i], t, knot, why, &flags);
  };
  // Two of the person's views or more: they are the reference, each tool's label held against
  // where they put the knot (they must agree with each other; if not, it is the person's word).
  std::vector<Observation> persons_views;
  for (size_t i = 0; i < from.size(); ++i)
    if (persons(from[i])) persons_views.push_back(obs[i]);
  if (persons_views.size() >= 2) {
    for (size_t i = 0; i < from.size(); ++i)
      if (!persons(from[i]))
        if (const std::optional<double> off = OffTheViews(
                *rig_, obs[i], persons_views, topt, o_.projection_tolerance_px, o_.label_sigma_px))
          flag(i, "after the person's labels: " + Px(*off) +
                      " px from where the person's labels put the knot");
    obs.clear();
  }
  // The person's one view: the worst view each time, until the rest agree (a knot may have two
  // tools' labels off).
  while (obs.size() >= 3) {
    const auto off =
        ViewOffTheOthers(*rig_, obs, topt, o_.projection_tolerance_px, o_.label_sigma_px);
    if (!off) break;
    const size_t i = static_cast<size_t>(off->first);
    if (persons(from[i])) {
      for (size_t j = 0; j < from.size(); ++j)
        if (!persons(from[j]))
          flag(j, "after the person's label in " + set.cameras[from[i]] + ": the cameras " +
                      "disagree with it by " + Px(off->second) + " px");
      break;
    }
    flag(i, "after the person's labels: " + Px(off->second) +
                " px from where the other cameras put the knot");
    obs.erase(obs.begin() + static_cast<std::ptrdiff_t>(i));
    from.erase(from.begin() + static_cast<std::ptrdiff_t>(i));
  }
  if (flags.empty()) return 0;
  return Commit("check after the person's label (frame row " + std::to_string(t) + ")", flags)
      .review;
}

std::optional<Eigen::Vector2d> LabelEngine::OthersPlace(int camera, int t, int knot,
                                                        bool* by_motion) const {
  if (by_motion) *by_motion = false;
  if (!rig_ || !(o_.place_sigma_px > 0.0)) return std::nullopt;
  const std::vector<Observation> others = OtherViews(camera, t, knot);
  if (others.empty()) return std::nullopt;
  TriangulationOptions topt;
  topt.outlier_threshold_px = o_.epipolar_tolerance_px;
  if (others.size() >= 2) {
    // They must agree closely: two views, each a little off across their epipolar lines, show
    // it in their residuals only (a label 3.6 px off once left 1.8 px in each, within the
    // epipolar tolerance); three or more, each view against the others too.
    const PointEstimate e = TriangulatePoint(*rig_, others, topt);
    if (!e.valid || !e.outliers.empty()) return std::nullopt;
    for (double r : e.residual_px)
      if (!(r <= o_.place_residual_px)) return std::nullopt;
    if (ViewOffTheOthers(*rig_, others, topt, o_.projection_tolerance_px, o_.label_sigma_px))
      return std::nullopt;
    const std::optional<ProjectedPoint> q = ProjectEstimate(*rig_, RigIndex(camera), e);
    if (!q || !FineEnough(camera, others, e.position)) return std::nullopt;
    if (WorstSigma(*q, o_.label_sigma_px) <= o_.place_sigma_px) return q->px;
  }
  // The views do not fix it alone: with the knot's motion.
  const std::optional<PointEstimate> e = MotionPoint(camera, t, knot);
  if (!e) return std::nullopt;
  const std::optional<ProjectedPoint> q = ProjectEstimate(*rig_, RigIndex(camera), *e);
  if (!q || !(WorstSigma(*q, o_.label_sigma_px) <= o_.place_sigma_px)) return std::nullopt;
  // The path's views of frame row t and the frames beside it are the other cameras' (and this
  // camera's own, in other frames: as fine as it).
  if (!FineEnough(camera, others, e->position)) return std::nullopt;
  if (by_motion) *by_motion = true;
  return q->px;
}

bool LabelEngine::FineEnough(int camera, const std::vector<Observation>& views,
                             const Eigen::Vector3d& point) const {
  if (!(o_.place_max_magnification > 0.0)) return true;
  // px per metre at the point: the focal length over the depth.
  const auto scale = [&](int rig_index) {
    const calib::Camera& cam = rig_->cameras[rig_index];
    const double depth = (cam.cam_from_world * point).z();
    return depth > 0.0 ? cam.intrinsics.fx / depth : 0.0;
  };
  double finest = 0.0;
  for (const Observation& v : views) finest = std::max(finest, scale(v.camera));
  return finest * o_.place_max_magnification >= scale(RigIndex(camera));
}

std::vector<Observation> LabelEngine::OtherViews(int camera, int t, int knot) const {
  std::vector<Observation> views;
  if (!rig_) return views;
  const LabelSet& set = store_->labels();
  for (int o = 0; o < static_cast<int>(set.cameras.size()); ++o)
    if (o != camera && Observed(set.at(o, t, knot)))
      views.push_back({RigIndex(o), set.at(o, t, knot).px});
  return views;
}

std::optional<PointEstimate> LabelEngine::MotionPoint(int camera, int t, int knot) const {
  if (!rig_ || o_.motion_frames < 1) return std::nullopt;
  const LabelSet& set = store_->labels();
  // The knot's own labels (no placed ones) in frame row s of every camera but `but` (-1: all).
  const auto views_in = [&](int s, int but, std::vector<TimedObservation>* views) {
    const std::vector<Observation> in_s = OtherViews(but, s, knot);
    for (const Observation& v : in_s) views->push_back({static_cast<double>(s), v});
    return !in_s.empty();
  };
  std::vector<TimedObservation> now;
  if (!views_in(t, camera, &now)) return std::nullopt;
  const double sigma2 = o_.label_sigma_px * o_.label_sigma_px;
  // The frame rows before t (else after: tracking backwards), the adjacent one among them. This
  // camera's own labels join the path only where it has one in the adjacent row: its place two
  // rows past its last label is that label's error carried on by the path, grown each row (in
  // the wrapping, three such second places in a row were 2.1-2.3 px off, the first of each pair
  // 0.8-1.3 px), while its place one row on is what the path is for.
  for (const int step : {-1, 1}) {
    const int adjacent = t + step;
    if (adjacent < 0 || adjacent >= set.frames()) continue;
    const int but = Observed(set.at(camera, adjacent, knot)) ? -1 : camera;
    std::vector<TimedObservation> views = now;
    for (int i = 1; i <= o_.motion_frames; ++i) {
      const int s = t + step * i;
      if (s < 0 || s >= set.frames() || (!views_in(s, but, &views) && i == 1)) break;
    }
    if (views.size() == now.size()) continue;
    const PointEstimate e = FitConstantVelocity(*rig_, views, t);
    if (!e.valid) continue;
    // Every view on the path, all of them as the labels' noise explains, and no one view alone
    // moving it (one that alone fixes a direction bends the path to itself).
    const bool close = std::all_of(e.residual_px.begin(), e.residual_px.end(),
                                   [&](double r) { return r <= o_.place_residual_px; });
    const int dof = 2 * static_cast<int>(views.size()) - 6;
    if (close && dof > 0 && e.sum_squares_px2 / sigma2 <= Chi2Quantile999(dof) &&
        NoViewMovesIt(camera, views, t, e))
      return e;
  }
  return std::nullopt;
}

bool LabelEngine::NoViewMovesIt(int camera, const std::vector<TimedObservation>& views, int t,
                                const PointEstimate& e) const {
  const std::optional<ProjectedPoint> q = ProjectEstimate(*rig_, RigIndex(camera), e);
  if (!q) return false;
  std::vector<TimedObservation> rest(views.begin() + 1, views.end());
  for (size_t i = 0; i < views.size(); ++i) {
    if (i > 0) rest[i - 1] = views[i - 1];  // rest: every view but i
    const PointEstimate without = FitConstantVelocity(*rig_, rest, t);
    if (!without.valid) continue;
    const std::optional<ProjectedPoint> p = ProjectEstimate(*rig_, RigIndex(camera), without);
    if (!p || (p->px - q->px).norm() > o_.place_leave_one_out_px) return false;
  }
  return true;
}

std::optional<double> LabelEngine::MotionOff(int camera, int t, int knot,
                                             const Eigen::Vector2d& px) const {
  const LabelSet& set = store_->labels();
  for (const int s : {t - 1, t + 1}) {
    if (s < 0 || s >= set.frames() || !set.at(camera, s, knot).accepted()) continue;
    // The mean motion of its neighbours accepted in both rows.
    Eigen::Vector2d motion = Eigen::Vector2d::Zero();
    int n = 0;
    for (const int j : Neighbours(knot))
      if (set.at(camera, s, j).accepted() && set.at(camera, t, j).accepted()) {
        motion += set.at(camera, t, j).px - set.at(camera, s, j).px;
        ++n;
      }
    if (n < 2) continue;
    const Eigen::Vector2d expected = set.at(camera, s, knot).px + motion / n;
    return (px - expected).norm();
  }
  return std::nullopt;
}

std::optional<double> LabelEngine::VelocityOff(int camera, int t, int knot,
                                               const Eigen::Vector2d& px) const {
  const LabelSet& set = store_->labels();
  for (const int step : {-1, 1}) {
    // Its accepted labels in the frame rows t - step, t - 2 step (and t - 3 step).
    std::vector<Eigen::Vector2d> p;
    for (int i = 1; i <= 3; ++i) {
      const int s = t + step * i;
      if (s < 0 || s >= set.frames() || !set.at(camera, s, knot).accepted()) break;
      p.push_back(set.at(camera, s, knot).px);
    }
    // A straight line at constant velocity through them (least squares), at t.
    if (p.size() == 2) return (px - (2.0 * p[0] - p[1])).norm();
    if (p.size() == 3) return (px - (4.0 * p[0] + p[1] - 2.0 * p[2]) / 3.0).norm();
  }
  return std::nullopt;
}

std::optional<double> LabelEngine::OwnMotionOff(int camera, int t, int knot,
                                                const Eigen::Vector2d& px) const {
  const std::optional<double> moved = MotionOff(camera, t, knot, px);
  const std::optional<double> own = VelocityOff(camera, t, knot, px);
  return own && (!moved || *own < *moved) ? own : moved;
}

bool LabelEngine::LabelNear(int camera, int t, int knot, const Eigen::Vector2d& px) const {
  const LabelSet& set = store_->labels();
  for (int j = 0; j < set.knots(); ++j) {
    const Label& l = set.at(camera, t, j);
    if (j != knot && l.accepted() && (l.px - px).norm() < o_.exclusion_px) return true;
  }
  return false;
}

std::string LabelEngine::FoundNodeDoubt(int camera, int t, int knot, const Junction& j) const {
  // A knotless edge knot is where its straight links' colours change.
  if (!ColourChangesAt(j, o_.edge_colour_step_px)) {
    char why[120];
    std::snprintf(why, sizeof why,
                  "the colours of its straight yarns change %.1f px from the junction",
                  (j.colour_step - j.px).norm());
    return why;
  }
  // What confirms the junction is the knot: a crossing of two yarns of a folded net looks like
  // a knot to the rings and the fit, so a junction is accepted only where a check that could
  // have refused it ran and passed (its motion, its yarns towards two or more labeled
  // neighbours, the other cameras, its path), or it is the corner's own mass.
  // A corner mass confirms its corner where only the corner's two yarns leave it: bunched in a
  // fold, with more yarns around it, its outline's centre was 2.0-2.3 px from the knot.
  const int degree = static_cast<int>(Neighbours(knot).size());
  bool confirmed = j.solid && degree == 2 && j.branches <= 2 && !j.solid_cut;
  // Its motion since the adjacent frame against its neighbours' (a junction of another layer
  // of a folded net, 3.6 px from the knot, had yarns along the knot's own).
  const std::optional<double> moved = MotionOff(camera, t, knot, j.px);
  if (moved && *moved > o_.place_motion_px) {
    char why[96];
    std::snprintf(why, sizeof why,
                  "it moved %.1f px otherwise than its neighbours since the "
                  "frame before",
                  *moved);
    return why;
  }
  confirmed = confirmed || moved.has_value();
  // Its yarns against its accepted neighbours in this view.
  const NeighbourSlots slots = Slots(camera, t, knot, {});
  // They confirm it only where every link's direction is known (each yarn seen then runs along
  // one, three at least): with a link unknown, its yarn may be another knot's (a folded net seen
  // edge-on put a row's three links on one line in the image, and a column's yarn crossing it
  // 5.5 px from the knot passed for the unknown link).
  const std::vector<double> link_angles = KnownLinkAngles(j.px, slots);
  if (link_angles.size() >= 2) {
    if (!BranchesMatchLinks(j, slots, o_.branch_tolerance_deg, true))
      return "the junction's yarns do not run towards its labeled neighbours";
    confirmed = confirmed || (static_cast<int>(link_angles.size()) == degree &&
                              j.branches >= std::min(degree, 3));
  }
  // Its place against the point two or more other cameras agree on.
  const std::vector<Observation> others = OtherViews(camera, t, knot);
  // A junction a yarn short of the knot's degree, with neither its motion nor the other
  // cameras to check its place: in folds, a yarn beside the knot's own or another layer's
  // crossing made such junctions 2-2.7 px off, their yarns along the knot's links. The other
  // cameras check it only where they fix the knot (OthersPlace; the caller found they do not):
  // the far pair alone, whose point projects into a near camera to a pixel or more, once let a
  // junction 2.7 px off pass within the 1.5 px of their check below.
  // Where nothing checks its place, a junction of the knot's degree must have each yarn along
  // one of its links (another layer's yarn crossing a row 2 px from a knot made one).
  if (!j.solid && !moved) {
    char why[160];
    if (j.branches < degree) {
      std::snprintf(why, sizeof why,
                    "the junction has %d yarns, the knot %d, and nothing checks "
                    "its place (no motion, no other cameras that fix it)",
                    j.branches, degree);
      return why;
    }
    if (link_angles.size() >= 2 && !BranchesMatchLinks(j, slots, o_.track.max_yarn_angle_deg))
      return "a yarn of the junction leads to no labeled neighbour, and nothing checks its "
             "place (no motion, no other cameras that fix it)";
  }
  TriangulationOptions topt;
  topt.outlier_threshold_px = o_.epipolar_tolerance_px;
  const std::string unconfirmed =
      "nothing confirms the junction is the knot and not a crossing of yarns (no labeled "
      "neighbours, motion or other cameras to check it against)";
  // One other camera or none: its path over the adjacent frames with that view (MotionPoint),
  // where it fixes the knot to a pixel (a check needs less than a placement): in a fold a
  // junction of another layer 2.1 px from the knot moved 1.4 px otherwise than the knot's
  // neighbours, within place_motion_px, and 1.6 px from where its path put it.
  if (others.size() < 2) {
    // One other camera's label: the junction must lie on its epipolar line (a crossing on the
    // knot's own yarn passes only where the yarn runs along that line).
    if (others.size() == 1) {
      std::vector<Observation> pair = others;
      pair.push_back({RigIndex(camera), j.px});
      const PointEstimate e = TriangulatePoint(*rig_, pair, topt);
      // Two views leave the same residual in each (half the distance from the epipolar line,
      // where their scales are alike); an outlier between two is either of them.
      const bool fitted = e.residual_px.size() == 2 && std::isfinite(e.residual_px[0]) &&
                          std::isfinite(e.residual_px[1]);
      if (fitted && (!e.outliers.empty() ||
                     !(e.residual_px[0] + e.residual_px[1] <= o_.epipolar_tolerance_px))) {
        char why[112];
        std::snprintf(why, sizeof why, "%.1f px from the epipolar line of the other camera's label",
                      e.residual_px[0] + e.residual_px[1]);
        return why;
      }
    }
    const std::optional<PointEstimate> path = MotionPoint(camera, t, knot);
    const std::optional<ProjectedPoint> p =
        path ? ProjectEstimate(*rig_, RigIndex(camera), *path) : std::nullopt;
    if (!p || !(WorstSigma(*p, o_.label_sigma_px) <= kPathCheckSigmaPx))
      return confirmed ? "" : unconfirmed;
    const double off = (p->px - j.px).norm();
    if (off <= o_.projection_tolerance_px) return "";
    char why[120];
    std::snprintf(why, sizeof why,
                  "%.1f px from where its motion and the other cameras' labels "
                  "put the knot",
                  off);
    return why;
  }
  // Where the others do not agree there is nothing to go by.
  const std::optional<ProjectedPoint> q =
      ProjectAgreeingViews(*rig_, RigIndex(camera), others, topt);
  if (!q) return confirmed ? "" : unconfirmed;
  const double off = (q->px - j.px).norm();
  if (off <= o_.projection_tolerance_px) {
    // Their place confirms the junction only where it is sure to a pixel: the near pair's two
    // views, 15 degrees apart, put a knot in a far camera to 1.7-2.6 px (for the labels' noise),
    // and junctions 2.5 px from the knot passed within the tolerance of such places.
    const double sure = WorstSigma(*q, o_.label_sigma_px);
    if (confirmed || sure <= kPathCheckSigmaPx) return "";
    char why[160];
    std::snprintf(why, sizeof why,
                  "%.1f px from where the other cameras' labels put the knot, but they fix it "
                  "only to %.1f px here, and nothing else confirms the junction",
                  off, sure);
    return why;
  }
  char why[112];
  std::snprintf(why, sizeof why, "%.1f px from where the other cameras' labels put the knot", off);
  return why;
}

void LabelEngine::EstimateLinkLength(const std::vector<std::optional<Eigen::Vector3d>>& p) {
  if (link_length_m_ > 0.0) return;
  const LabelSet& set = store_->labels();
  std::vector<double> d;
  for (int k = 0; k < set.knots(); ++k)
    for (int n : Neighbours(k))
      if (n > k && p[k] && p[n]) d.push_back((*p[k] - *p[n]).norm());
  if (d.size() >= 4) link_length_m_ = Median(d);
}

namespace {

// The image-grid prediction of a knot in one camera from its accepted neighbours there.
struct GridPrediction {
  Eigen::Vector2d px;
  double spacing;  // the longest link among the neighbours used (px)
};

// The midpoint of each two opposite accepted neighbours of knot k in (camera c, frame row t),
// and the fourth corner of each parallelogram with a diagonal one, averaged; none when there is
// no such guess or the guesses disagree (by a quarter of the spacing or more).
std::optional<GridPrediction> PredictFromImageGrid(const LabelSet& set, int c, int t, int k) {
  const int cols = set.cols, knots = set.knots();
  auto at = [&](int j) -> std::optional<Eigen::Vector2d> {
    if (j < 0 || j >= knots || !set.at(c, t, j).accepted()) return std::nullopt;
    return set.at(c, t, j).px;
  };
  const int r = k / cols, col = k % cols;
  std::vector<Eigen::Vector2d> guesses;
  double spacing = 0.0;
  auto pair = [&](int a, int b) {
    const auto pa = at(a), pb = at(b);
    if (!pa || !pb) return;
    guesses.push_back(0.5 * (*pa + *pb));
    spacing = std::max(spacing, 0.5 * (*pa - *pb).norm());
  };
  if (col > 0 && col + 1 < cols) pair(k - 1, k + 1);
  if (r > 0 && r + 1 < set.rows) pair(k - cols, k + cols);
  for (int dr : {-1, 1})
    for (int dc : {-1, 1}) {
      if (r + dr < 0 || r + dr >= set.rows || col + dc < 0 || col + dc >= cols) continue;
      const auto a = at(k + dc), b = at(k + dr * cols), d = at(k + dr * cols + dc);
      if (!a || !b || !d) continue;
      guesses.push_back(*a + *b - *d);
      spacing = std::max(spacing, std::max((*a - *d).norm(), (*b - *d).norm()));
    }
  if (guesses.empty() || spacing <= 0.0) return std::nullopt;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& g : guesses) mean += g;
  mean /= static_cast<double>(guesses.size());
  bool agree = true;
  for (const auto& g : guesses) agree = agree && (g - mean).norm() < 0.25 * spacing;
  if (!agree) return std::nullopt;
  return GridPrediction{mean, spacing};
}

// The samples thinned to about 3 px apart (the first of each cluster kept, in order).
std::vector<Eigen::Vector2d> ThinSamples(const std::vector<Eigen::Vector2d>& region) {
  std::vector<Eigen::Vector2d> thin = {region.front()};
  for (const auto& q : region) {
    bool close = false;
    for (const auto& p : thin) close = close || (p - q).norm() < 3.0;
    if (!close) thin.push_back(q);
  }
  return thin;
}

// The largest gap from a sample to its nearest one (px), from 4 to 30 (a lone sample: 30).
double LargestSampleGap(const std::vector<Eigen::Vector2d>& region) {
  double step = 4.0;
  for (size_t i = 0; i < region.size(); ++i) {
    double nearest = 30.0;
    for (size_t j = 0; j < region.size(); ++j)
      if (j != i) nearest = std::min(nearest, (region[i] - region[j]).norm());
    step = std::max(step, nearest);
  }
  return step;
}

// A distance for a message: "2.3".
// The median colour of a region of `image` (per channel, 0..1 of the image's range).
std::vector<double> MedianColour(const cv::Mat& image, const cv::Rect& box) {
  const int channels = image.channels();
  std::vector<double> m(channels, 0.0);
  const cv::Rect r = box & cv::Rect(0, 0, image.cols, image.rows);
  if (r.area() == 0) return m;
  const double range = image.depth() == CV_16U ? 65535.0 : image.depth() == CV_8U ? 255.0 : 1.0;
  cv::Mat values;
  image(r).clone().convertTo(values, CV_64F, 1.0 / range);
  values = values.reshape(1, r.area());  // a row per pixel, a column per channel
  std::vector<double> v(values.rows);
  for (int ch = 0; ch < channels; ++ch) {
    for (int i = 0; i < values.rows; ++i) v[i] = values.at<double>(i, ch);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    m[ch] = v[v.size() / 2];
  }
  return m;
}

// The scene's background colour: the median of a sparse grid of the frame's pixels (yarns
// cover little of a frame).
std::vector<double> SceneBackground(const cv::Mat& image) {
  if (image.empty()) return {};
  cv::Mat sparse;
  cv::resize(image, sparse, cv::Size(std::max(1, image.cols / 16), std::max(1, image.rows / 16)), 0,
             0, cv::INTER_NEAREST);
  return MedianColour(sparse, cv::Rect(0, 0, sparse.cols, sparse.rows));
}

// Whether `px` lies on the scene's background `scene`: the median colour within `reach` of it,
// and of the places `reach` to each side, is within `tolerance` (0..1 of the image's range) of
// it. Over the target or another body it is not, and a knot there may be behind it.
bool OnSceneBackground(const cv::Mat& image, const std::vector<double>& scene,
                       const Eigen::Vector2d& px, double reach, double tolerance) {
  if (image.empty() || static_cast<int>(scene.size()) != image.channels()) return false;
  const int r = static_cast<int>(std::ceil(reach));
  for (const Eigen::Vector2d& d :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(reach, 0), Eigen::Vector2d(-reach, 0),
        Eigen::Vector2d(0, reach), Eigen::Vector2d(0, -reach)}) {
    const Eigen::Vector2d at = px + d;
    const std::vector<double> m = MedianColour(
        image,
        cv::Rect(static_cast<int>(at.x()) - r, static_cast<int>(at.y()) - r, 2 * r + 1, 2 * r + 1));
    for (size_t ch = 0; ch < m.size(); ++ch)
      if (std::abs(m[ch] - scene[ch]) > tolerance) return false;
  }
  return true;
}

// The one view of three or more that the others place the knot more than `tolerance` px from,
// beyond what the labels' noise (`sigma` px in each view) explains there: its index into `obs`
// and that distance. The check of all the views together cannot see it: a label 2-3 px off
// pulls the joint point, and its residual stays within the outlier threshold. The others must
// agree with each other (no outlier among them); where they fix the point poorly (a stereo
// pair's depth, seen from across), its projection is uncertain and nothing is flagged.
std::optional<std::pair<int, double>> ViewOffTheOthers(const calib::Rig& rig,
                                                       const std::vector<Observation>& obs,
                                                       const TriangulationOptions& topt,
                                                       double tolerance, double sigma) {
  if (obs.size() < 3) return std::nullopt;
  std::optional<std::pair<int, double>> worst;
  for (size_t i = 0; i < obs.size(); ++i) {
    std::vector<Observation> others;
    for (size_t o = 0; o < obs.size(); ++o)
      if (o != i) others.push_back(obs[o]);
    const std::optional<double> off = OffTheViews(rig, obs[i], others, topt, tolerance, sigma);
    if (off && (!worst || *off > worst->second)) worst = std::make_pair(static_cast<int>(i), *off);
  }
  return worst;
}

// How far `others`, agreeing with each other, place the knot from `view` (px), where that is more
// than `tolerance` beyond what the labels' noise (`sigma` px in each view) explains there;
// nullopt otherwise, or where they do not fix it (ProjectAgreeingViews).
std::optional<double> OffTheViews(const calib::Rig& rig, const Observation& view,
                                  const std::vector<Observation>& others,
                                  const TriangulationOptions& topt, double tolerance,
                                  double sigma) {
  if (others.size() < 2 || !(tolerance > 0.0) || !(sigma > 0.0)) return std::nullopt;
  const std::optional<ProjectedPoint> q = ProjectAgreeingViews(rig, view.camera, others, topt);
  if (!q) return std::nullopt;
  const Eigen::Vector2d off = q->px - view.px;
  if (off.norm() <= tolerance) return std::nullopt;
  // The projection's covariance plus this label's own noise; beyond the 99.9 % ellipse of two
  // degrees of freedom.
  const Eigen::Matrix2d covariance =
      sigma * sigma * (Eigen::Matrix2d::Identity() + q->unit_covariance);
  if (off.dot(covariance.ldlt().solve(off)) > 13.8) return off.norm();
  return std::nullopt;
}

// `n` added to `sum`.
void Add(EngineCounts* sum, const EngineCounts& n) {
  sum->accepted += n.accepted;
  sum->review += n.review;
}

}  // namespace

// CrossCheck's state in one frame row, shared by its steps.
struct LabelEngine::FrameCheck {
  int t = 0;
  int cameras = 0, knots = 0;
  bool geometry = false;  // a rig and two cameras or more: the checks in 3D run
  TriangulationOptions topt;
  // Per knot, the point its accepted labels triangulate to; `clean`: where every view is an
  // inlier.
  std::vector<std::optional<Eigen::Vector3d>> point, clean;
  // The triangulated points as each camera sees them (NaN where there is none), this pass.
  std::vector<std::vector<Eigen::Vector2d>> projected;
  // Each camera's scene background (SceneBackground), where it was needed.
  std::map<int, std::vector<double>> background;
  // What each search looked at, so a later pass does not repeat a search that found nothing.
  std::map<std::pair<int, int>, Eigen::Vector2d> searched;

  // Whether (camera c, knot k) was last searched at `centre` (within 0.5 px); if not, `centre`
  // is noted as its last search.
  bool Repeat(int c, int k, const Eigen::Vector2d& centre) {
    const auto key = std::make_pair(c, k);
    const auto it = searched.find(key);
    if (it != searched.end() && (it->second - centre).norm() < 0.5) return true;
    searched[key] = centre;
    return false;
  }
};

// One camera's frame in a Fill Grid pass.
struct LabelEngine::FillView {
  int camera;
  const cv::Mat& image;
  cv::Size size;
  double margin;  // the detector needs its inner ring (and its filter's support) inside the frame

  bool Inside(const Eigen::Vector2d& q) const {
    return q.allFinite() && q.x() >= margin && q.y() >= margin &&
           q.x() <= size.width - 1 - margin && q.y() <= size.height - 1 - margin;
  }
};

// A junction a Fill Grid search found for a knot, and how it was searched for.
struct LabelEngine::FillCandidate {
  int camera;
  Eigen::Vector2d px;
  double confidence;
  std::string how;
};

EngineCounts LabelEngine::CrossCheck(int t) {
  const LabelSet& set = store_->labels();
  FrameCheck f;
  f.t = t;
  f.cameras = static_cast<int>(set.cameras.size());
  f.knots = set.knots();
  f.geometry = rig_ && f.cameras >= 2;
  f.topt.outlier_threshold_px = o_.epipolar_tolerance_px;
  f.point.resize(f.knots);
  f.clean.resize(f.knots);
  EngineCounts total;
  // 0. Labels at the picture's edge, whose knot may be outside it: no reference for the rest.
  total.review += CheckPictureEdge(t);
  // 1. Epipolar consistency of the accepted labels.
  if (f.geometry) total.review += CheckEpipolar(&f);
  // 2. Fill Grid, pass after pass while a pass accepts labels (their points help the next).
  int filled = 0;
  for (int pass = 0; pass < o_.fill_passes; ++pass) {
    const EngineCounts n = FillGridPass(&f, pass);
    Add(&total, n);
    filled += n.accepted;
    if (n.accepted == 0) break;
    if (f.geometry) TriangulateAccepted(&f, nullptr);
  }
  // The labels Fill Grid accepted, checked like the rest (a candidate is accepted where the
  // cameras agree within the outlier threshold; each one's place is known better only now).
  if (f.geometry && filled > 0) total.review += CheckEpipolar(&f);
  if (filled > 0) total.review += CheckPictureEdge(t);
  // 3. Where the target hides the knot.
  total.review += CheckHidden(t);
  // 4. The yarn colours.
  if (codebook_) total.review += CheckColours(t);
  return total;
}

int LabelEngine::CheckHidden(int t) {
  if (!rig_ || target_.empty()) return 0;
  const LabelSet& set = store_->labels();
  const double time_s = set.frame_index[t] / target_.fps;
  TriangulationOptions topt;
  topt.outlier_threshold_px = o_.epipolar_tolerance_px;
  std::vector<LabelEdit> flags;
  for (int c = 0; c < static_cast<int>(set.cameras.size()); ++c)
    for (int k = 0; k < set.knots(); ++k) {
      const Label& l = set.at(c, t, k);
      if (!l.accepted() || l.source == LabelSource::kManual || l.source == LabelSource::kImported)
        continue;
      const std::vector<Observation> others = OtherViews(c, t, k);
      if (others.size() < 2) continue;
      const PointEstimate e = TriangulatePoint(*rig_, others, topt);
      if (!e.valid || !e.outliers.empty() || !UsableGeometry(e)) continue;
      const calib::Camera& camera = rig_->cameras[RigIndex(c)];
      if (!TargetHides(target_, camera.Center(), e.position, time_s, -o_.target_margin_m)) continue;
      std::string from;  // the cameras of `others` (OtherViews: every other one with the knot)
      for (int o = 0; o < static_cast<int>(set.cameras.size()); ++o)
        if (o != c && Observed(set.at(o, t, k)))
          from += (from.empty() ? "" : ", ") + set.cameras[o];
      ToReview(c, t, k, "the target hides the knot here (where " + from + " put it)", &flags);
    }
  if (flags.empty()) return 0;
  return Commit("the target's check (frame row " + std::to_string(t) + ")", flags).review;
}

int LabelEngine::CheckPictureEdge(int t) {
  if (o_.picture_edge_px <= 0.0) return 0;
  const LabelSet& set = store_->labels();
  std::vector<LabelEdit> flags;
  for (int c = 0; c < static_cast<int>(set.cameras.size()); ++c) {
    cv::Size size;
    for (int k = 0; k < set.knots(); ++k) {
      const Label& l = set.at(c, t, k);
      if (!l.accepted() || l.source == LabelSource::kManual || l.source == LabelSource::kImported)
        continue;
      if (size.empty()) size = Image(c, t).size();
      if (size.empty()) break;
      const double inside = InsideOuterEdgePx(l.px, size.width, size.height);
      if (inside >= o_.picture_edge_px) continue;
      char why[128];
      std::snprintf(why, sizeof why,
                    "at the picture's edge (%.1f px inside it): the knot may lie outside it",
                    std::max(inside, 0.0));
      ToReview(c, t, k, why, &flags);
    }
  }
  if (flags.empty()) return 0;
  return Commit("the picture's edge (frame row " + std::to_string(t) + ")", flags).review;
}

LabelingSummary LabelEngine::LabelFrames(int first, int last, const FrameDone& after_frame) {
  LabelingSummary summary;
  if (first > last) return summary;
  // The first frame row from its seeds, then the cameras cross-checked and the gaps filled.
  Add(&summary.first_frame, LabelFirstFrame(first));
  Add(&summary.cross_checked, CrossCheck(first));
  Add(&summary.first_frame, FillByPathsAndCheck(first));
  summary.frames = 1;
  if (after_frame) after_frame(first);
  // Each later row tracked from the one before.
  const LabelingSummary rest = TrackFrames(first, last, [&](int t) {
    if (after_frame) after_frame(t);
    return true;
  });
  Add(&summary.tracked, rest.tracked);
  Add(&summary.cross_checked, rest.cross_checked);
  summary.frames += rest.frames;
  return summary;
}

LabelingSummary LabelEngine::TrackFrames(int from, int to, const Checkpoint& checkpoint) {
  LabelingSummary summary;
  const int step = to >= from ? 1 : -1;
  for (int t = from + step; t != to + step; t += step) {
    Add(&summary.tracked, Track(t - step, t));
    Add(&summary.cross_checked, CrossCheck(t));
    ++summary.frames;
    if (checkpoint && !checkpoint(t)) break;
  }
  return summary;
}

void LabelEngine::TriangulateAccepted(FrameCheck* f, std::vector<LabelEdit>* flags) {
  const LabelSet& set = store_->labels();
  const int t = f->t;
  for (int k = 0; k < f->knots; ++k) {
    f->point[k].reset();
    f->clean[k].reset();
    // The knot's accepted labels, and the cameras they are from.
    std::vector<Observation> obs;
    std::vector<int> from;
    for (int c = 0; c < f->cameras; ++c)
      if (Observed(set.at(c, t, k))) {
        obs.push_back({RigIndex(c), set.at(c, t, k).px});
        from.push_back(c);
      }
    if (obs.size() < 2) continue;
    const PointEstimate e = TriangulatePoint(*rig_, obs, f->topt);
    if (e.valid) f->point[k] = e.position;
    if (e.valid && e.outliers.empty()) f->clean[k] = e.position;
    if (!flags) continue;
    // Every view of a point it cannot resolve, or the views it leaves out, to review.
    auto flag = [&](int i, const std::string& why) { ToReview(from[i], t, k, why, flags); };
    if (!e.valid) {
      for (size_t i = 0; i < from.size(); ++i)
        flag(static_cast<int>(i), "epipolar check: the cameras disagree (" + e.why + ")");
    } else if (!e.outliers.empty()) {
      for (int i : e.outliers)
        flag(i, "epipolar check: " + Px(e.residual_px[i]) + " px off the point of all the cameras");
    } else if (const auto off = ViewOffTheOthers(*rig_, obs, f->topt, o_.projection_tolerance_px,
                                                 o_.label_sigma_px)) {
      flag(off->first,
           "epipolar check: " + Px(off->second) + " px from where the other cameras put the knot");
    }
  }
}

int LabelEngine::CheckEpipolar(FrameCheck* f) {
  std::vector<LabelEdit> flags;
  TriangulateAccepted(f, &flags);
  int review = 0;
  // The flags committed, the points triangulated again without them.
  if (!flags.empty()) {
    review = Commit("epipolar check (frame row " + std::to_string(f->t) + ")", flags).review;
    TriangulateAccepted(f, nullptr);
  }
  EstimateLinkLength(f->clean);
  return review;
}

EngineCounts LabelEngine::FillGridPass(FrameCheck* f, int pass) {
  // Positions already taken in each camera (accepted labels and the knots' projections), so a
  // junction is never given to a second knot: the projections of this pass's points.
  f->projected.assign(f->cameras,
                      std::vector<Eigen::Vector2d>(f->knots, Eigen::Vector2d::Constant(NAN)));
  if (f->geometry)
    for (int c = 0; c < f->cameras; ++c)
      for (int j = 0; j < f->knots; ++j)
        if (f->point[j]) f->projected[c][j] = rig_->cameras[RigIndex(c)].ProjectWorld(*f->point[j]);
  // Each camera searched for its missing knots.
  std::vector<LabelEdit> edits;
  FillCandidates candidates;
  for (int c = 0; c < f->cameras; ++c) SearchCamera(f, c, &edits, &candidates);
  // Candidates become labels only when the cameras agree in 3D.
  AcceptCandidates(*f, candidates, &edits);
  const std::vector<LabelEdit> unique = OneLabelPerPlace(f->t, edits);
  return Commit(
      "Fill Grid (frame row " + std::to_string(f->t) + ", pass " + std::to_string(pass + 1) + ")",
      unique);
}

void LabelEngine::SearchCamera(FrameCheck* f, int c, std::vector<LabelEdit>* edits,
                               FillCandidates* candidates) {
  const LabelSet& set = store_->labels();
  const cv::Mat& image = Image(c, f->t);
  if (image.empty()) return;
  const FillView view{c, image, image.size(), o_.detector.ring_radius_px + 2.0};
  for (int k = 0; k < f->knots; ++k) {
    const Label& l = set.at(c, f->t, k);
    if (l.accepted() || l.hidden()) continue;
    // A junction Find Path took along the knot's row or column alone (the other path crossed
    // knots the target hides): a candidate, accepted where other cameras confirm it.
    if (l.source == LabelSource::kFindPath && f->geometry && one_path_.count({c, f->t, k}))
      if (const std::optional<FillCandidate> found = PathCandidate(f, view, k)) {
        (*candidates)[k].push_back(*found);
        continue;
      }
    // (a) The knot's own triangulated point, where it has one; else, seen by one other camera,
    // placed where that view and its motion put it.
    if (f->geometry && f->point[k]) {
      if (const std::optional<LabelEdit> e = SearchAtProjection(f, view, k)) edits->push_back(*e);
      continue;
    }
    if (f->geometry)
      if (const std::optional<LabelEdit> e = PlaceAtProjection(f, view, k)) {
        edits->push_back(*e);
        continue;
      }
    // (b) Spheres of link length around triangulated neighbours; (c) else the image-space grid
    // in this camera.
    std::string how;
    std::vector<Eigen::Vector2d> region = LinkSphereRegion(*f, view, k, &how);
    const std::optional<FillCandidate> found =
        region.empty() ? SearchImageGrid(f, view, k)
                       : SearchRegion(f, view, k, std::move(region), how);
    if (found) (*candidates)[k].push_back(*found);
  }
}

std::optional<LabelEngine::FillCandidate> LabelEngine::PathCandidate(FrameCheck* f,
                                                                     const FillView& view, int k) {
  const int c = view.camera;
  const Eigen::Vector2d at = store_->labels().at(c, f->t, k).px;
  if (!view.Inside(at) || f->Repeat(c, k, at)) return std::nullopt;
  // Its junction again, judged by its yarns as Fill Grid's own candidates are; its neighbours'
  // directions from their labels of the paths too (those along the same row are also found
  // along one path only).
  NeighbourSlots slots = Slots(c, f->t, k, f->point);
  const std::array<int, 4> slot_knot = SlotKnots(k);
  for (int s = 0; s < 4; ++s) {
    if (slot_knot[s] < 0 || slots.px[s]) continue;
    const Label& n = store_->labels().at(c, f->t, slot_knot[s]);
    if (n.present() && n.source == LabelSource::kFindPath) slots.px[s] = n.px;
  }
  const FindNodeResult r = FindNode(view.image, at, 1.0, o_.detector);
  if (r.status == FindNodeStatus::kFound && (r.knot.px - at).norm() <= 0.5 &&
      !TakenNear(*f, c, k, r.knot.px) && ColourChangesAt(r.knot, o_.edge_colour_step_px) &&
      BranchesMatchLinks(r.knot, slots, o_.branch_tolerance_deg))
    return FillCandidate{c, r.knot.px, r.knot.confidence, "Find Path along its row or column"};
  return std::nullopt;
}

std::optional<LabelEdit> LabelEngine::SearchAtProjection(FrameCheck* f, const FillView& view,
                                                         int k) {
  const int c = view.camera;
  const Eigen::Vector2d q = f->projected[c][k];
  if (!view.Inside(q) || f->Repeat(c, k, q)) return std::nullopt;
  // The point checks a junction here only as finely as its views see it (a point only the far
  // pair fixed let a junction 2.05 px off in a near camera pass within the tolerance).
  if (!FineEnough(c, OtherViews(c, f->t, k), *f->point[k])) return std::nullopt;
  // The brush a little wider than the tolerance: the detector's seeds are 1.5 px apart.
  const FindNodeResult r = FindNode(view.image, q, o_.projection_tolerance_px + 1.5, o_.detector,
                                    Neighbours(k).size() == 2);
  if (r.status == FindNodeStatus::kFound && (r.knot.px - q).norm() <= o_.projection_tolerance_px &&
      !TakenNear(*f, c, k, r.knot.px) && ColourChangesAt(r.knot, o_.edge_colour_step_px) &&
      BranchesMatchLinks(r.knot, Slots(c, f->t, k, f->point), o_.branch_tolerance_deg))
    return LabelEdit{c, f->t, k, Made(r.knot.px, LabelSource::kFillGrid, r.knot.confidence, true)};
  return PlaceAtProjection(f, view, k);
}

std::optional<LabelEdit> LabelEngine::PlaceAtProjection(FrameCheck* f, const FillView& view,
                                                        int k) {
  const int c = view.camera, t = f->t;
  const NeighbourSlots slots = Slots(c, t, k, f->point);
  if (std::count(slots.present.begin(), slots.present.end(), true) < 3) return std::nullopt;
  // Where the other cameras' own labels fix the knot.
  const std::optional<Eigen::Vector2d> q = OthersPlace(c, t, k);
  if (!q || !view.Inside(*q) || TakenNear(*f, c, k, *q)) return std::nullopt;
  // Its yarns there, along at least two of its links.
  const std::vector<double> links = KnownLinkAngles(*q, slots);
  if (links.size() < 2) return std::nullopt;
  const double reach = std::ceil(DetectorReach(o_.detector)) + 2.0;
  const cv::Rect roi(static_cast<int>(q->x() - reach), static_cast<int>(q->y() - reach),
                     static_cast<int>(2 * reach) + 1, static_cast<int>(2 * reach) + 1);
  const KnotDetector detector(view.image, roi, o_.detector);
  std::vector<bool> seen;
  const int yarns = detector.YarnsAlong(*q, links, o_.branch_tolerance_deg * M_PI / 180.0, &seen);
  if (yarns < 2) return std::nullopt;
  // Whether it lies over the target or another body (not on the scene's background).
  auto scene = f->background.find(c);
  if (scene == f->background.end())
    scene = f->background.emplace(c, SceneBackground(view.image)).first;
  const bool over_body = !OnSceneBackground(view.image, scene->second, *q, o_.background_reach_px,
                                            o_.background_tolerance);
  // Over the target or another body, a knot may be behind it: there every one of its links
  // must be seen leaving it (at least three); or, where this camera saw the knot in an adjacent
  // frame row (its label there accepted), a yarn must pass through the place (two opposite
  // links seen). A knot just behind the body's outline shows the yarns of the links that cross
  // it, two adjacent ones at most; a knot in front of it, draped over the target's edges, often
  // shows only the yarn across the edge, the one along it lost in the body's own edge. (The first
  // 60 frames of Net A 0.5 m/s and Net B at both speeds: 77 hidden knots seen the frame before,
  // each with two adjacent yarns; Net B at 0.8 m/s, frames 140-179: 85 visible ones with only
  // an opposite pair.)
  const LabelSet& set = store_->labels();
  const bool seen_before = (t > 0 && set.at(c, t - 1, k).accepted()) ||
                           (t + 1 < set.frames() && set.at(c, t + 1, k).accepted());
  const auto yarn_through = [&] {
    for (size_t a = 0; a < links.size(); ++a)
      for (size_t b = a + 1; b < links.size(); ++b)
        if (seen[a] && seen[b] &&
            std::abs(std::remainder(links[a] - links[b], 2.0 * M_PI)) >
                o_.detector.straight_angle_deg * M_PI / 180.0)
          return true;
    return false;
  };
  const bool every_link = yarns >= 3 && yarns >= static_cast<int>(links.size());
  if (over_body && !every_link && !(seen_before && yarn_through())) return std::nullopt;
  // And this camera's own labels agree, a check no other camera's label enters: the knot moved
  // from its label in an adjacent frame row as its neighbours did, or as it was moving (its
  // labels in the frame rows before, at constant velocity); where neither is known, it lies
  // where this camera's tracking took it (the flow's end, or the junction it found there).
  std::optional<double> moved = OwnMotionOff(c, t, k, *q);
  const Label& tracked = set.at(c, t, k);
  if (!moved && tracked.present() && tracked.source == LabelSource::kTracked)
    moved = (tracked.px - *q).norm();
  if (!moved || *moved > o_.place_motion_px) return std::nullopt;
  // And where its yarns, fitted along its links, meet (where they fit): the other cameras'
  // labels may be a pixel or two off themselves in a fold, and the far pair sees their error
  // magnified; a place off the yarns' meeting point by more than a junction may be is not placed.
  std::vector<Eigen::Vector2d> link_vectors;
  for (const std::optional<Eigen::Vector2d>& n : slots.px)
    if (n) link_vectors.push_back(*n - *q);
  const std::optional<Junction> fit =
      FitAlongLinks(view.image, *q, link_vectors, o_.track.fit_along_gap_px, o_.detector);
  if (fit && (fit->px - *q).norm() > o_.projection_tolerance_px) return std::nullopt;
  return LabelEdit{c, t, k, Made(*q, LabelSource::kProjected, 0.5, true)};
}

std::vector<Eigen::Vector2d> LabelEngine::LinkSphereRegion(const FrameCheck& f,
                                                           const FillView& view, int k,
                                                           std::string* how) const {
  const double link = link_length_m_;
  // The knot's triangulated neighbours; two of them opposite fix it on a circle.
  std::vector<Eigen::Vector3d> around;
  std::vector<int> around_knots;
  for (int n : Neighbours(k))
    if (f.geometry && f.point[n]) {
      around.push_back(*f.point[n]);
      around_knots.push_back(n);
    }
  const int cols = store_->labels().cols;
  bool opposite = false;
  for (size_t i = 0; i < around_knots.size(); ++i)
    for (size_t j = i + 1; j < around_knots.size(); ++j)
      opposite = opposite || std::abs(around_knots[i] - around_knots[j]) == 2 ||
                 std::abs(around_knots[i] - around_knots[j]) == 2 * cols;
  std::vector<Eigen::Vector2d> region;  // projected candidate points
  if (link > 0.0 && around.size() >= 2 && (opposite || around.size() >= 3)) {
    // The pair farthest apart spans the circle; the rest filter it.
    size_t ia = 0, ib = 1;
    for (size_t i = 0; i < around.size(); ++i)
      for (size_t j = i + 1; j < around.size(); ++j)
        if ((around[i] - around[j]).norm() > (around[ia] - around[ib]).norm()) ia = i, ib = j;
    const Eigen::Vector3d mid = 0.5 * (around[ia] + around[ib]);
    const Eigen::Vector3d axis = (around[ib] - around[ia]).normalized();
    const double half = 0.5 * (around[ib] - around[ia]).norm();
    const double reach = link * (1.0 + o_.link_tolerance);
    if (half <= reach) {
      const double rho = std::sqrt(std::max(0.0, reach * reach - half * half));
      const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
      // The lens where the balls of link length meet (links may be slack), sampled.
      for (double fr : {1.0, 0.8, 0.6, 0.4, 0.2, 0.0})
        for (int s = 0; s < (fr > 0 ? 48 : 1); ++s) {
          const double a = 2 * M_PI * s / 48;
          const Eigen::Vector3d p = mid + fr * rho * (std::cos(a) * u + std::sin(a) * v);
          bool ok = true;
          for (const auto& n : around) ok = ok && (p - n).norm() <= reach;
          if (!ok) continue;
          const Eigen::Vector2d q = rig_->cameras[RigIndex(view.camera)].ProjectWorld(p);
          if (view.Inside(q)) region.push_back(q);
        }
      *how = "spheres of link length around " + std::to_string(around.size()) +
             " triangulated neighbours";
    }
  }
  return region;
}

std::optional<LabelEngine::FillCandidate> LabelEngine::SearchRegion(
    FrameCheck* f, const FillView& view, int k, std::vector<Eigen::Vector2d> region,
    const std::string& how) {
  const int c = view.camera;
  // The region's bounding circle: too vague to search, or searched in an earlier pass.
  Eigen::AlignedBox2d box;
  for (const auto& q : region) box.extend(q);
  const Eigen::Vector2d centre = box.center();
  const double radius = 0.5 * box.diagonal().norm() + 4.0;
  if (radius > 150.0 || f->Repeat(c, k, centre)) return std::nullopt;
  if (region.size() > 1) region = ThinSamples(region);
  // The detector over the circle, with room for its rings.
  const double roi_margin = std::ceil(DetectorReach(o_.detector)) + 1.0;
  const int x0 = std::max(0, static_cast<int>(centre.x() - radius - roi_margin));
  const int y0 = std::max(0, static_cast<int>(centre.y() - radius - roi_margin));
  const int x1 = std::min(view.size.width, static_cast<int>(centre.x() + radius + roi_margin + 1));
  const int y1 = std::min(view.size.height, static_cast<int>(centre.y() + radius + roi_margin + 1));
  const KnotDetector detector(view.image, cv::Rect(x0, y0, x1 - x0, y1 - y0), o_.detector);
  // Searched only near the projected samples, and only from pixels on a yarn (a knot is
  // where yarns meet): far fewer than the pixels of the region.
  std::vector<Junction> near;
  const double reach = 0.5 * LargestSampleGap(region) + 2.0;
  const cv::Mat& ridge = detector.ridge();
  const double on_yarn = 0.5 * detector.peak_threshold();
  std::vector<Eigen::Vector2d> examined;
  for (int y = 0; y < ridge.rows; ++y)
    for (int x = 0; x < ridge.cols; ++x) {
      if (ridge.at<float>(y, x) < on_yarn) continue;
      const Eigen::Vector2d p(x0 + x, y0 + y);
      bool in_region = false;
      for (const auto& q : region) in_region = in_region || (q - p).norm() <= reach;
      if (!in_region) continue;
      bool done = false;
      for (const auto& e : examined) done = done || (e - p).norm() < 1.5;
      for (const Junction& n : near) done = done || (n.px - p).norm() < 3.0;
      if (done) continue;
      examined.push_back(p);
      const std::optional<Junction> j = detector.Examine(p);
      if (!j) continue;
      bool merged = false;
      for (const Junction& n : near)
        merged = merged || (n.px - j->px).norm() < o_.detector.merge_px;
      if (!merged && !TakenNear(*f, c, k, j->px) && ColourChangesAt(*j, o_.edge_colour_step_px) &&
          BranchesMatchLinks(*j, Slots(c, f->t, k, f->point), o_.branch_tolerance_deg))
        near.push_back(*j);
    }
  // The one unlabeled junction near the projected lens.
  if (near.size() == 1) return FillCandidate{c, near[0].px, near[0].confidence, how};
  return std::nullopt;
}

std::optional<LabelEngine::FillCandidate> LabelEngine::SearchImageGrid(FrameCheck* f,
                                                                       const FillView& view,
                                                                       int k) {
  const int c = view.camera;
  const std::optional<GridPrediction> g = PredictFromImageGrid(store_->labels(), c, f->t, k);
  if (!g || !view.Inside(g->px) || f->Repeat(c, k, g->px)) return std::nullopt;
  const FindNodeResult r =
      FindNode(view.image, g->px, 0.3 * g->spacing, o_.detector, Neighbours(k).size() == 2);
  if (r.status == FindNodeStatus::kFound && !TakenNear(*f, c, k, r.knot.px) &&
      ColourChangesAt(r.knot, o_.edge_colour_step_px) &&
      BranchesMatchLinks(r.knot, Slots(c, f->t, k, f->point), o_.branch_tolerance_deg))
    return FillCandidate{c, r.knot.px, r.knot.confidence,
                         "the image grid of its labeled neighbours"};
  return std::nullopt;
}

bool LabelEngine::TakenNear(const FrameCheck& f, int c, int k, const Eigen::Vector2d& px) const {
  const LabelSet& set = store_->labels();
  for (int j = 0; j < f.knots; ++j) {
    if (j == k) continue;
    const Label& l = set.at(c, f.t, j);
    if (l.accepted() && (l.px - px).norm() < o_.exclusion_px) return true;
    const Eigen::Vector2d& q = f.projected[c][j];
    if (q.allFinite() && (q - px).norm() < o_.exclusion_px) return true;
  }
  return false;
}

void LabelEngine::AcceptCandidates(const FrameCheck& f, const FillCandidates& candidates,
                                   std::vector<LabelEdit>* edits) {
  const LabelSet& set = store_->labels();
  for (const auto& [k, list] : candidates) {
    std::string why = "Fill Grid: seen by one camera only (" + list.front().how + ")";
    if (f.geometry && ConfirmCandidates(f, k, list, edits, &why)) continue;
    // Not confirmed: for review, where the camera has no label of the knot.
    for (const auto& cand : list)
      if (!set.at(cand.camera, f.t, k).present()) {
        edits->push_back(
            {cand.camera, f.t, k, Made(cand.px, LabelSource::kFillGrid, cand.confidence, false)});
        Note(cand.camera, f.t, k, why);
      }
  }
}

bool LabelEngine::ConfirmCandidates(const FrameCheck& f, int k,
                                    const std::vector<FillCandidate>& list,
                                    std::vector<LabelEdit>* edits, std::string* why) const {
  const LabelSet& set = store_->labels();
  const double link = link_length_m_;
  // The knot's accepted labels, then its candidates, triangulated together.
  std::vector<Observation> obs;
  for (int c = 0; c < f.cameras; ++c)
    if (Observed(set.at(c, f.t, k))) obs.push_back({RigIndex(c), set.at(c, f.t, k).px});
  const size_t first = obs.size();
  for (const auto& cand : list) obs.push_back({RigIndex(cand.camera), cand.px});
  if (obs.size() < 2) return false;
  const PointEstimate e = TriangulatePoint(*rig_, obs, f.topt);
  // The point within a link (and the tolerance) of each triangulated neighbour.
  bool near_links = e.valid;
  for (int n : Neighbours(k))
    if (e.valid && f.point[n] && link > 0.0)
      near_links =
          near_links && (e.position - *f.point[n]).norm() <= link * (1.0 + o_.link_tolerance);
  if (!e.valid) {
    *why = "Fill Grid: the cameras' candidates disagree (" + e.why + ")";
    return false;
  }
  if (!near_links) {
    *why = "Fill Grid: the cameras agree on a point farther than a link from its neighbours";
    return false;
  }
  // The candidates the triangulation keeps as inliers are accepted, each where the rest do not
  // contradict it. A candidate's residual in the joint point is smaller than its distance from
  // where the other views put the knot, and with one other view it only has to lie near that
  // view's epipolar line: in the wrapping such candidates were accepted 2.2-6.5 px from the
  // knot. So the other views, where they fix the knot to a pixel, must put it within
  // projection_tolerance_px of the candidate, and this camera's own labels, where it has one in
  // an adjacent frame row, must have it move as its neighbours did or as it was moving (within
  // place_motion_px, as for a placement).
  bool confirmed = false;
  std::string doubt;
  for (size_t i = first; i < obs.size(); ++i) {
    const bool inlier =
        std::find(e.inliers.begin(), e.inliers.end(), static_cast<int>(i)) != e.inliers.end();
    const FillCandidate& cand = list[i - first];
    if (!inlier) continue;
    std::vector<Observation> rest = obs;
    rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(i));
    const std::optional<ProjectedPoint> q =
        rest.size() >= 2 ? ProjectAgreeingViews(*rig_, RigIndex(cand.camera), rest, f.topt)
                         : std::nullopt;
    if (q && WorstSigma(*q, o_.label_sigma_px) <= kPathCheckSigmaPx &&
        (q->px - cand.px).norm() > o_.projection_tolerance_px) {
      doubt = "Fill Grid: the junction is " + Px((q->px - cand.px).norm()) +
              " px from where the other cameras' labels put the knot";
      continue;
    }
    const std::optional<double> moved = OwnMotionOff(cand.camera, f.t, k, cand.px);
    if (moved && *moved > o_.place_motion_px) {
      doubt = "Fill Grid: the junction moved " + Px(*moved) +
              " px otherwise than the knot's neighbours and its own path since the adjacent "
              "frame";
      continue;
    }
    confirmed = true;
    edits->push_back(
        {cand.camera, f.t, k, Made(cand.px, LabelSource::kFillGrid, cand.confidence, true)});
  }
  if (!confirmed)
    *why = doubt.empty() ? "Fill Grid: off the epipolar geometry of the other cameras" : doubt;
  return confirmed;
}

std::vector<LabelEdit> LabelEngine::OneLabelPerPlace(int t, const std::vector<LabelEdit>& edits) {
  // One label per (camera, knot): the first edit wins (accepted ones come first per knot).
  std::vector<LabelEdit> unique;
  for (const auto& e : edits) {
    bool seen = false;
    for (const auto& u : unique) seen = seen || (u.camera == e.camera && u.knot == e.knot);
    if (!seen) unique.push_back(e);
  }
  // Two knots given junctions this close in one camera: neither is trusted.
  for (auto& a : unique)
    for (auto& b : unique)
      if (&a != &b && a.camera == b.camera && a.label.state == LabelState::kAccepted &&
          (a.label.px - b.label.px).norm() < o_.exclusion_px) {
        a.label.state = LabelState::kNeedsReview;
        Note(a.camera, t, a.knot, "Fill Grid: another knot was found at the same place");
      }
  return unique;
}

void LabelEngine::SetCodebook(KnotCodebook codebook, IdentityCheckOptions options) {
  std::string why;
  if (!codebook.IsValid(&why)) throw std::invalid_argument("colour codebook: " + why);
  if (static_cast<int>(codebook.knots.size()) != store_->labels().knots())
    throw std::invalid_argument("colour codebook: " + std::to_string(codebook.knots.size()) +
                                " knots, the labels have " +
                                std::to_string(store_->labels().knots()));
  if (!options.IsValid(&why)) throw std::invalid_argument("colour check: " + why);
  codebook_ = std::move(codebook);
  identity_ = std::move(options);
}

int LabelEngine::CheckColours(int t) {
  if (!codebook_) return 0;
  const LabelSet& set = store_->labels();
  std::vector<LabelEdit> flags;
  for (int c = 0; c < static_cast<int>(set.cameras.size()); ++c) {
    const cv::Mat& image = Image(c, t);
    if (image.empty() || image.type() != CV_8UC3) continue;
    for (int k = 0; k < set.knots(); ++k) {
      const Label& l = set.at(c, t, k);
      // Not the person's clicks, imported seeds, or placed labels: a placed label takes its
      // identity from the other cameras' labels (each checked in its own view), and where it is
      // placed, in folds, another layer's yarns cross its own (200 right labels were flagged on
      // Net B at 0.8 m/s in frames 141-179).
      if (!l.accepted() || l.source == LabelSource::kManual || l.source == LabelSource::kImported ||
          l.source == LabelSource::kProjected)
        continue;
      const IdentityCheck check = CheckIdentity(image, *codebook_, k, l.px,
                                                AcceptedNeighbourYarns(set, c, t, k), identity_);
      if (check.verdict != IdentityVerdict::kMismatch) continue;
      ToReview(c, t, k, "colour check: " + check.why, &flags);
    }
  }
  if (flags.empty()) return 0;
  return Commit("colour check (frame row " + std::to_string(t) + ")", flags).review;
}

}  // namespace netlab::recon
