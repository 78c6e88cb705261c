#include "libreconstruct/knot_detect.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

namespace netlab::recon {
namespace {

constexpr int kRingSamples = 180;

// Pixels around a point that Examine reads: the outer ring and the ridge filter's support.
double Reach(const KnotDetectorOptions& o) {
  return 2.0 * o.ring_radius_px + 4 * o.ridge_sigma_px + 4;
}

double AngleBetween(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 2 * M_PI);
  return std::min(d, 2 * M_PI - d);
}

// A quantile of the values of a CV_32F image (q in [0, 1]).
double Quantile(const cv::Mat& m, double q) {
  std::vector<float> v(m.begin<float>(), m.end<float>());
  if (v.empty()) return 0.0;
  auto it = v.begin() + static_cast<long>(std::min<double>(v.size() - 1, q * v.size()));
  std::nth_element(v.begin(), it, v.end());
  return *it;
}

}  // namespace

KnotDetector::KnotDetector(const cv::Mat& image, cv::Rect roi, KnotDetectorOptions options)
    : o_(options) {
  const cv::Rect full(0, 0, image.cols, image.rows);
  roi_ = roi.empty() ? full : (roi & full);
  if (roi_.empty()) return;
  // Foreground: the distance from the local background, a median over a window much wider than
  // a yarn (the target mock-up or the aircraft behind the net are not one colour).
  cv::Mat region = image(roi_), eight;
  if (region.depth() == CV_8U) {
    eight = region;
  } else {
    double max = 0.0;
    cv::minMaxLoc(region.reshape(1), nullptr, &max);
    region.convertTo(eight, CV_8U, max > 0 ? 255.0 / max : 1.0);
  }
  cv::Mat background;
  cv::medianBlur(eight, background, o_.background_window_px | 1);
  cv::Mat f, bg;
  eight.convertTo(f, CV_32F, 1.0 / 255);
  background.convertTo(bg, CV_32F, 1.0 / 255);
  std::vector<cv::Mat> channels, bg_channels;
  cv::split(f, channels);
  cv::split(bg, bg_channels);
  cv::Mat fg = cv::Mat::zeros(f.size(), CV_32F);
  for (size_t i = 0; i < channels.size(); ++i) {
    cv::Mat d = channels[i] - bg_channels[i];
    fg += d.mul(d);
  }
  cv::sqrt(fg, fg);
  // Small solids (corner masses) are not yarns: their rims look like ridges and meet the yarns
  // like junctions. A solid is what survives an opening with a disc several yarn widths across
  // (yarns and their crossings, however many, are thinner) of the region that stands out from
  // the region's median colour; only compact blobs count (a target face behind the net is
  // background, handled by the local median).
  cv::Mat global = cv::Mat::zeros(f.size(), CV_32F);
  for (size_t i = 0; i < channels.size(); ++i) {
    cv::Mat d = channels[i] - Quantile(channels[i], 0.5);
    global += d.mul(d);
  }
  cv::sqrt(global, global);
  cv::Mat bright = global > o_.solid_fraction * Quantile(global, 0.995), opened, labels, stats,
          centroids;
  const int disc = 2 * static_cast<int>(std::ceil(2.5 * o_.ridge_sigma_px)) + 1;
  cv::morphologyEx(bright, opened, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(disc, disc)));
  const int n = cv::connectedComponentsWithStats(opened, labels, stats, centroids, 8, CV_32S);
  cv::Mat solid = cv::Mat::zeros(f.size(), CV_8U);
  const double largest = std::min(o_.max_solid_area_px, 0.25 * f.rows * f.cols);
  for (int i = 1; i < n; ++i)
    if (stats.at<int>(i, cv::CC_STAT_AREA) <= largest) solid.setTo(255, labels == i);
  cv::dilate(solid, solid, cv::Mat(), cv::Point(-1, -1),
             static_cast<int>(std::ceil(2 * o_.ridge_sigma_px)));
  // Ridges of the foreground at the thread's scale.
  cv::Mat smooth, dxx, dyy, dxy;
  cv::GaussianBlur(fg, smooth, cv::Size(), o_.ridge_sigma_px);
  cv::Sobel(smooth, dxx, CV_32F, 2, 0, 3);
  cv::Sobel(smooth, dyy, CV_32F, 0, 2, 3);
  cv::Sobel(smooth, dxy, CV_32F, 1, 1, 3);
  ridge_.create(f.size(), CV_32F);
  for (int y = 0; y < f.rows; ++y)
    for (int x = 0; x < f.cols; ++x) {
      const float a = dxx.at<float>(y, x), b = dyy.at<float>(y, x), c = dxy.at<float>(y, x);
      const float lambda_min = 0.5f * (a + b) - std::sqrt(0.25f * (a - b) * (a - b) + c * c);
      ridge_.at<float>(y, x) = solid.at<uchar>(y, x) ? 0.0f : std::max(0.0f, -lambda_min);
    }
  // A branch peak must stand out from the strong ridges (threads) and from the background's
  // noise alike.
  threshold_ = std::max(o_.peak_fraction * Quantile(ridge_, 0.99),
                        8.0 * Quantile(ridge_, 0.5) + 1e-6);
}

double KnotDetector::Sample(double x, double y) const {
  const double u = x - roi_.x, v = y - roi_.y;
  if (!(u >= 0 && v >= 0 && u <= ridge_.cols - 1 && v <= ridge_.rows - 1)) return 0.0;
  const int x0 = std::min(static_cast<int>(u), ridge_.cols - 2);
  const int y0 = std::min(static_cast<int>(v), ridge_.rows - 2);
  const double fx = u - x0, fy = v - y0;
  const float* r0 = ridge_.ptr<float>(y0);
  const float* r1 = ridge_.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

std::vector<double> KnotDetector::Ring(const Eigen::Vector2d& centre, double radius, int n) const {
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    out[i] = Sample(centre.x() + radius * std::cos(a), centre.y() + radius * std::sin(a));
  }
  return out;
}

std::vector<double> KnotDetector::Peaks(const std::vector<double>& profile,
                                        double* weakest) const {
  const int n = static_cast<int>(profile.size());
  std::vector<double> p(n);
  for (int i = 0; i < n; ++i)
    p[i] = 0.25 * profile[(i + n - 1) % n] + 0.5 * profile[i] + 0.25 * profile[(i + 1) % n];
  struct Peak {
    double angle, value;
  };
  std::vector<Peak> peaks;
  for (int i = 0; i < n; ++i) {
    const double a = p[(i + n - 1) % n], b = p[i], c = p[(i + 1) % n];
    if (!(b > threshold_ && b >= a && b > c)) continue;
    // Sub-sample position: the centroid of the raw profile above half the peak's height (a
    // parabola through the smoothed samples was biased by up to 0.4 px at the knot).
    double sw = 0.0, swx = 0.0;
    const double half = 0.5 * profile[i];
    for (int d = -6; d <= 6; ++d) {
      const double v = profile[(i + d + n) % n] - half;
      if (v <= 0) continue;
      sw += v;
      swx += v * d;
    }
    const double delta = sw > 0 ? swx / sw : 0.0;
    peaks.push_back({2 * M_PI * (i + delta) / n, b});
  }
  // Peaks closer than the least branch separation are one (the stronger).
  const double separation = o_.min_branch_separation_deg * M_PI / 180;
  std::sort(peaks.begin(), peaks.end(), [](const Peak& x, const Peak& y) { return x.value > y.value; });
  std::vector<Peak> kept;
  for (const Peak& pk : peaks) {
    bool near = false;
    for (const Peak& k : kept) near = near || AngleBetween(pk.angle, k.angle) < separation;
    if (!near) kept.push_back(pk);
  }
  std::sort(kept.begin(), kept.end(), [](const Peak& x, const Peak& y) { return x.angle < y.angle; });
  std::vector<double> angles;
  double weak = std::numeric_limits<double>::infinity();
  for (const Peak& k : kept) {
    angles.push_back(k.angle);
    weak = std::min(weak, k.value / threshold_);
  }
  if (weakest) *weakest = angles.empty() ? 0.0 : weak;
  return angles;
}

std::optional<Junction> KnotDetector::Examine(const Eigen::Vector2d& px) const {
  if (ridge_.empty()) return std::nullopt;
  auto is_junction = [&](const std::vector<double>& angles) {
    const size_t b = angles.size();
    if (b == 2) return AngleBetween(angles[0], angles[1]) < o_.straight_angle_deg * M_PI / 180;
    return b == 3 || b == 4;
  };
  // Branches are followed on three circles; each branch line is fitted through its peaks.
  const double radii[3] = {o_.ring_radius_px, 1.5 * o_.ring_radius_px, 2.0 * o_.ring_radius_px};
  double weakest = 0.0;
  const std::vector<double> first = Peaks(Ring(px, radii[0], kRingSamples), &weakest);
  if (!is_junction(first)) return std::nullopt;
  Eigen::Vector2d p = px;
  Junction j;
  for (int iteration = 0; iteration < 4; ++iteration) {
    std::vector<double> rings[3];
    double weak = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      double w = 0.0;
      rings[i] = Peaks(Ring(p, radii[i], kRingSamples), &w);
      if (rings[i].size() != first.size()) return std::nullopt;
      weak = std::min(weak, w);
    }
    if (!is_junction(rings[0])) return std::nullopt;
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> lines;
    for (double t0 : rings[0]) {
      // The branch's points on the three circles (nearest peak in angle on the outer ones).
      Eigen::Vector2d pts[3];
      double t_prev = t0;
      for (int i = 0; i < 3; ++i) {
        double best = 1e9, t = t_prev;
        for (double c : rings[i])
          if (AngleBetween(c, t_prev) < best) best = AngleBetween(c, t_prev), t = c;
        if (best > 20 * M_PI / 180) return std::nullopt;
        pts[i] = p + radii[i] * Eigen::Vector2d(std::cos(t), std::sin(t));
        t_prev = t;
      }
      // Least-squares line through the three points: centroid and principal direction.
      const Eigen::Vector2d mean = (pts[0] + pts[1] + pts[2]) / 3.0;
      Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
      for (const auto& q : pts) cov += (q - mean) * (q - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
      const Eigen::Vector2d d = eig.eigenvectors().col(1);
      const Eigen::Matrix2d m = Eigen::Matrix2d::Identity() - d * d.transpose();
      a += m;
      b += m * mean;
      lines.emplace_back(mean, d);
    }
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(a);
    if (!(svd.singularValues()[1] > 0.05 * svd.singularValues()[0])) return std::nullopt;
    const Eigen::Vector2d next = a.ldlt().solve(b);
    if (!next.allFinite() || (next - px).norm() > radii[0]) return std::nullopt;
    double ss = 0.0;
    for (const auto& [q, d] : lines) {
      const Eigen::Vector2d off = next - q;
      ss += (off - off.dot(d) * d).squaredNorm();
    }
    j.px = next;
    j.branches = static_cast<int>(rings[0].size());
    j.branch_angles_rad = rings[0];
    j.fit_rms_px = std::sqrt(ss / lines.size());
    j.contrast = weak;
    const bool settled = (next - p).norm() < 1e-3;
    p = next;
    if (settled) break;
  }
  j.confidence = std::clamp((j.contrast - 1.0) / 2.0, 0.0, 1.0) *
                 std::exp(-0.5 * (j.fit_rms_px / 0.5) * (j.fit_rms_px / 0.5));
  return j;
}

std::vector<Junction> KnotDetector::FindInCircle(const Eigen::Vector2d& centre,
                                                 double radius) const {
  std::vector<Junction> found;
  const double step = 1.5;
  for (double dy = -radius; dy <= radius; dy += step)
    for (double dx = -radius; dx <= radius; dx += step) {
      if (dx * dx + dy * dy > radius * radius) continue;
      const Eigen::Vector2d seed = centre + Eigen::Vector2d(dx, dy);
      bool near = false;
      for (const Junction& j : found) near = near || (j.px - seed).norm() < 0.5 * o_.ring_radius_px;
      if (near) continue;
      const std::optional<Junction> j = Examine(seed);
      if (!j || (j->px - centre).norm() > radius) continue;
      bool merged = false;
      for (Junction& k : found)
        if ((k.px - j->px).norm() < o_.merge_px) {
          if (j->confidence > k.confidence) k = *j;
          merged = true;
        }
      if (!merged) found.push_back(*j);
    }
  return found;
}

FindNodeResult FindNode(const cv::Mat& image, const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options) {
  const int margin = static_cast<int>(std::ceil(Reach(options)));
  const cv::Rect roi(static_cast<int>(std::floor(centre.x() - radius)) - margin,
                     static_cast<int>(std::floor(centre.y() - radius)) - margin,
                     static_cast<int>(2 * radius) + 2 * margin + 2,
                     static_cast<int>(2 * radius) + 2 * margin + 2);
  const KnotDetector detector(image, roi, options);
  FindNodeResult result;
  result.candidates = detector.FindInCircle(centre, radius);
  if (result.candidates.empty()) {
    result.status = FindNodeStatus::kNone;
    result.why = "no junction of 2-4 yarns inside the brush";
  } else if (result.candidates.size() > 1) {
    result.status = FindNodeStatus::kSeveral;
    result.why = std::to_string(result.candidates.size()) + " junctions inside the brush";
  } else {
    result.status = FindNodeStatus::kFound;
    result.knot = result.candidates[0];
  }
  return result;
}

FindPathResult FindPath(const cv::Mat& image, int cols, int knot_a, const Eigen::Vector2d& px_a,
                        int knot_b, const Eigen::Vector2d& px_b,
                        const KnotDetectorOptions& options) {
  FindPathResult result;
  const int ra = knot_a / cols, ca = knot_a % cols, rb = knot_b / cols, cb = knot_b % cols;
  if (ra != rb && ca != cb) {
    result.why = "the two knots are not in one row or column";
    return result;
  }
  const int between = std::max(std::abs(ra - rb), std::abs(ca - cb)) - 1;
  if (between < 0) {
    result.why = "the two knots are the same";
    return result;
  }
  // The region: the segment's bounding box with room for a sagging yarn and the rings.
  const double length = (px_b - px_a).norm();
  const int margin = static_cast<int>(std::ceil(0.15 * length + Reach(options)));
  const cv::Rect roi(static_cast<int>(std::floor(std::min(px_a.x(), px_b.x()))) - margin,
                     static_cast<int>(std::floor(std::min(px_a.y(), px_b.y()))) - margin,
                     static_cast<int>(std::abs(px_b.x() - px_a.x())) + 2 * margin + 2,
                     static_cast<int>(std::abs(px_b.y() - px_a.y())) + 2 * margin + 2);
  const KnotDetector detector(image, roi, options);
  const cv::Rect box = roi & cv::Rect(0, 0, image.cols, image.rows);
  const cv::Mat& ridge = detector.ridge();
  // Dijkstra, 8-connected, step cost length / (ridge + small): the yarn is the cheap way.
  const float eps = static_cast<float>(0.05 * detector.peak_threshold());
  const int w = ridge.cols, h = ridge.rows;
  auto index = [&](const Eigen::Vector2d& p) {
    const int x = std::clamp(static_cast<int>(std::lround(p.x())) - box.x, 0, w - 1);
    const int y = std::clamp(static_cast<int>(std::lround(p.y())) - box.y, 0, h - 1);
    return y * w + x;
  };
  const int from = index(px_a), to = index(px_b);
  std::vector<float> dist(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  std::vector<int> prev(dist.size(), -1);
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  dist[from] = 0.0f;
  queue.push({0.0f, from});
  while (!queue.empty()) {
    const auto [d, i] = queue.top();
    queue.pop();
    if (d > dist[i]) continue;
    if (i == to) break;
    const int x = i % w, y = i / w;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || x + dx < 0 || x + dx >= w || y + dy < 0 || y + dy >= h)
          continue;
        const int j = (y + dy) * w + x + dx;
        const float step = (dx && dy) ? 1.41421356f : 1.0f;
        const float nd = d + step / (ridge.at<float>(y + dy, x + dx) + eps);
        if (nd < dist[j]) {
          dist[j] = nd;
          prev[j] = i;
          queue.push({nd, j});
        }
      }
  }
  if (prev[to] < 0 && to != from) {
    result.why = "no path between the two knots";
    return result;
  }
  for (int i = to; i >= 0; i = prev[i]) result.path.emplace_back(box.x + i % w, box.y + i / w);
  std::reverse(result.path.begin(), result.path.end());
  // Junctions along the path, away from the two end knots, in order of arc length.
  struct Found {
    double arc;
    Junction j;
  };
  std::vector<Found> found;
  double arc = 0.0;
  for (size_t i = 0; i < result.path.size(); ++i) {
    if (i > 0) arc += (result.path[i] - result.path[i - 1]).norm();
    const Eigen::Vector2d& p = result.path[i];
    if ((p - px_a).norm() < 1.5 * options.ring_radius_px ||
        (p - px_b).norm() < 1.5 * options.ring_radius_px)
      continue;
    bool near = false;
    for (const Found& f : found) near = near || (f.j.px - p).norm() < options.ring_radius_px;
    if (near) continue;
    const std::optional<Junction> j = detector.Examine(p);
    if (!j || (j->px - px_a).norm() < options.ring_radius_px ||
        (j->px - px_b).norm() < options.ring_radius_px)
      continue;
    bool merged = false;
    for (const Found& f : found) merged = merged || (f.j.px - j->px).norm() < options.merge_px;
    if (!merged) found.push_back({arc, *j});
  }
  std::sort(found.begin(), found.end(), [](const Found& x, const Found& y) { return x.arc < y.arc; });
  if (static_cast<int>(found.size()) != between) {
    result.why = "found " + std::to_string(found.size()) + " junctions along the yarn, but " +
                 std::to_string(between) + " knots lie between";
    return result;
  }
  // The links between are of one length: along the yarn the junctions are spread about evenly
  // (perspective and sag change that slowly). A gap far from the mean means a junction missed
  // and a spurious one taken instead (the edge of a corner mass looks like one), which a count
  // alone does not see.
  if (between > 0) {
    const double total = arc, mean = total / (between + 1);
    double previous = 0.0;
    for (int i = 0; i <= between; ++i) {
      const double next = i < between ? found[i].arc : total;
      const double gap = next - previous;
      if (gap < 0.5 * mean || gap > 1.6 * mean) {
        result.why = "the junctions along the yarn are unevenly spaced (a gap of " +
                     std::to_string(static_cast<int>(gap)) + " px where " +
                     std::to_string(static_cast<int>(mean)) +
                     " px is the mean): a knot missed or a false junction";
        return result;
      }
      previous = next;
    }
  }
  const int dr = (rb > ra) - (rb < ra), dc = (cb > ca) - (cb < ca);
  for (int i = 0; i < between; ++i) {
    result.knots.push_back((ra + (i + 1) * dr) * cols + ca + (i + 1) * dc);
    result.junctions.push_back(found[i].j);
  }
  result.ok = true;
  return result;
}

}  // namespace netlab::recon
