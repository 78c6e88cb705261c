#include "libreconstruct/labeling/knot_detect.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "libreconstruct/recording/bayer.h"

namespace netlab::recon {
namespace {

constexpr int kRingSamples = 180;
// masked_: on a solid (no ridge, no yarn samples), on an edge of the background (no samples).
constexpr uchar kSolid = 255, kEdge = 128;

// cos a, sin a, cos 2a, sin 2a of the ring's sample angles a = 2 pi i / kRingSamples.
struct RingTable {
  std::array<double, kRingSamples> c, s, c2, s2;
  RingTable() {
    for (int i = 0; i < kRingSamples; ++i) {
      const double a = 2 * M_PI * i / kRingSamples;
      c[i] = std::cos(a), s[i] = std::sin(a), c2[i] = std::cos(2 * a), s2[i] = std::sin(2 * a);
    }
  }
};
const RingTable& Table() {
  static const RingTable table;
  return table;
}

// Pixels around a point that Examine reads: the outer ring and the ridge filter's support.

double AngleBetween(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 2 * M_PI);
  return std::min(d, 2 * M_PI - d);
}

// A quantile of the values of a CV_32F image (q in [0, 1]), from every `stride`-th value.
double Quantile(const cv::Mat& m, double q, int stride = 1) {
  std::vector<float> v;
  v.reserve(m.total() / stride + m.rows);
  for (int y = 0; y < m.rows; ++y) {
    const float* row = m.ptr<float>(y);
    for (int x = y % stride; x < m.cols; x += stride) v.push_back(row[x]);
  }
  if (v.empty()) return 0.0;
  auto it = v.begin() + static_cast<long>(std::min<double>(v.size() - 1, q * v.size()));
  std::nth_element(v.begin(), it, v.end());
  return *it;
}

// Which Bayer pattern (at the image's top-left pixel) an 8-bit BGR image was demosaiced from by
// OpenCV's bilinear demosaicing (Demosaic, bayer.h), if any: re-mosaicing it with that pattern
// and demosaicing again gives the image back, away from the border. kNone when no pattern does
// (a rendered or already processed image), or when the image is too flat to tell.
BayerPattern DemosaicedFrom(const cv::Mat& image) {
  if (image.type() != CV_8UC3 || image.rows < 8 || image.cols < 8) return BayerPattern::kNone;
  // A central window is enough (and four demosaicings of a whole region are not free); its
  // origin at even offsets keeps the pattern's phase.
  const int w = std::min(image.cols, 40), h = std::min(image.rows, 40);
  const cv::Mat eight_bgr =
      image(cv::Rect((image.cols - w) / 4 * 2, (image.rows - h) / 4 * 2, w, h));
  const cv::Rect inner(2, 2, eight_bgr.cols - 4, eight_bgr.rows - 4);
  const int allowed = inner.area() * 3 / 1000;
  int matches = 0;
  BayerPattern found = BayerPattern::kNone;
  for (BayerPattern p :
       {BayerPattern::kRGGB, BayerPattern::kBGGR, BayerPattern::kGRBG, BayerPattern::kGBRG}) {
    cv::Mat again, diff;
    cv::cvtColor(Mosaic(eight_bgr, p), again, OpenCvBayerCode(p));
    cv::absdiff(again(inner), eight_bgr(inner), diff);
    if (cv::countNonZero(diff.reshape(1) > 1) <= allowed) {
      found = p;
      ++matches;
    }
  }
  return matches == 1 ? found : BayerPattern::kNone;
}

// One sample of the image near a branch: its position along (u) and across (v) the branch line,
// px, its colour channel and its value (image minus background, 0..1).
struct YarnSample {
  double u, v;
  int channel;
  double value;
};

// erf(x) given e = exp(-x^2): 1 - poly(t) e, t = 1 / (1 + 0.3275911 |x|), to 1.5e-7
// (Abramowitz and Stegun 7.1.26); the exponential is the one the derivatives need anyway.
double Erf(double x, double e) {
  const double t = 1.0 / (1.0 + 0.3275911 * std::abs(x));
  const double poly =
      t *
      (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
  const double v = 1.0 - poly * e;
  return x < 0 ? -v : v;
}

// The model of a straight yarn seen across: a strip of half width h (px) blurred by a Gaussian
// of `blur` px, value = offset_c + area_c * Strip(v - (rho + kappa u)) in each colour channel c.
// Strip is the blurred strip of unit area, so that a yarn thinner than the blur keeps a finite
// area as h goes to 0:
//   Strip(d) = (erf((d + h) / (sqrt 2 blur)) - erf((d - h) / (sqrt 2 blur))) / (4 h).
double StripValue(double d, double h, double blur) {
  const double k = 1.0 / (std::sqrt(2.0) * blur);
  const double a = (d + h) * k, b = (d - h) * k;
  return 0.25 * (Erf(a, std::exp(-a * a)) - Erf(b, std::exp(-b * b))) / h;
}

// Strip and its derivatives by the distance d and by h.
double Strip(double d, double h, double blur, double* d_d, double* d_h) {
  const double k = 1.0 / (std::sqrt(2.0) * blur);
  const double a = (d + h) * k, b = (d - h) * k;
  const double ea = std::exp(-a * a), eb = std::exp(-b * b);
  const double box = 0.5 * (Erf(a, ea) - Erf(b, eb));
  const double box_d = k / std::sqrt(M_PI) * (ea - eb), box_h = k / std::sqrt(M_PI) * (ea + eb);
  *d_d = box_d / (2 * h);
  *d_h = (box_h * h - box) / (2 * h * h);
  return box / (2 * h);
}

struct YarnFit {
  bool ok = false;
  // The yarn's centre line, v = rho + kappa (u - u_knot): its offset at the knot, px, and its
  // slope against the branch line.
  double rho = 0.0, kappa = 0.0;
  double half_width = 0.0;  // px
  double snr = 0.0;         // |area| / residual RMS
  double sigma_rho = 0.0;   // standard error of rho, px (from the residuals)
  Eigen::VectorXd params;   // rho, kappa (at the strip's middle), h, area_c, offset_c
};

// The least-squares areas and offsets of each channel for a fixed line and width (the model is
// linear in them), into p; returns the sum of squared residuals.
// The yarn model's parameters (3 + 2 channels, at most three channels): on the stack, as the fit
// runs for every yarn of every knot in every frame.
constexpr int kMaxYarnChannels = 3;
constexpr int kMaxYarnParams = 3 + 2 * kMaxYarnChannels;
using YarnParams = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxYarnParams, 1>;
using YarnNormal =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxYarnParams, kMaxYarnParams>;

double SolveLinear(const std::vector<YarnSample>& samples, int channels, double blur,
                   YarnParams* p) {
  struct Sums {
    double n = 0, g = 0, gg = 0, v = 0, gv = 0, vv = 0;
  };
  std::array<Sums, kMaxYarnChannels> sums{};
  for (const YarnSample& s : samples) {
    const double g = StripValue(s.v - (*p)(0) - (*p)(1) * s.u, (*p)(2), blur);
    Sums& m = sums[s.channel];
    m.n += 1, m.g += g, m.gg += g * g, m.v += s.value, m.gv += g * s.value;
    m.vv += s.value * s.value;
  }
  double ss = 0.0;
  for (int c = 0; c < channels; ++c) {
    const Sums& m = sums[c];
    const double det = m.gg * m.n - m.g * m.g;
    double area = 0.0, offset = m.n > 0 ? m.v / m.n : 0.0;
    if (det > 1e-12 * std::max(1.0, m.gg * m.n)) {
      area = (m.gv * m.n - m.g * m.v) / det;
      offset = (m.gg * m.v - m.g * m.gv) / det;
    }
    (*p)(3 + c) = area;
    (*p)(3 + channels + c) = offset;
    // The sum of (value - area g - offset)^2.
    ss += m.vv + area * area * m.gg + offset * offset * m.n - 2 * area * m.gv - 2 * offset * m.v +
          2 * area * offset * m.g;
  }
  return ss;
}

// The yarn model fitted to the samples (channels 0..channels-1; u measured from the middle of
// the strip, where the line's offset and slope are uncorrelated; the knot at u_knot).
// Parameters rho, kappa (the line v = rho + kappa u), h (from half_width), area_c, offset_c.
// The offset has several local minima (a thin yarn of one dye is seen by every second row or
// column of its colour), so with `search` the fit starts from the best line of a grid across
// the strip and over small turns; then Levenberg-Marquardt.
YarnFit FitYarn(const std::vector<YarnSample>& samples, int channels, double blur, bool search,
                double half_width, double u_knot) {
  constexpr double kMinHalfWidth = 0.05;
  YarnFit fit;
  const int np = 3 + 2 * channels;
  if (channels < 1 || channels > kMaxYarnChannels || static_cast<int>(samples.size()) < 4 * np)
    return fit;
  YarnParams p = YarnParams::Zero(np), trial = p;
  p(2) = half_width;
  if (search) {
    // A search in offset alone, then in turn, once put a line 1.8 px off at the knot: the turn
    // of a thin one-dye yarn along a pixel axis is left to its weak channels.
    double best = std::numeric_limits<double>::infinity();
    for (double kappa : {-0.08, -0.04, 0.0, 0.04, 0.08})
      for (double rho = -1.4; rho <= 1.4 + 1e-9; rho += 0.2) {
        trial(0) = rho;
        trial(1) = kappa;
        trial(2) = half_width;
        const double ss = SolveLinear(samples, channels, blur, &trial);
        if (ss < best) best = ss, p = trial;
      }
  } else {
    SolveLinear(samples, channels, blur, &p);
  }
  auto cost = [&](const YarnParams& q) {
    double sum = 0.0;
    for (const YarnSample& s : samples) {
      const double r = q(3 + channels + s.channel) +
                       q(3 + s.channel) * StripValue(s.v - q(0) - q(1) * s.u, q(2), blur) - s.value;
      sum += r * r;
    }
    return sum;
  };
  // Gauss-Newton normal equations J^T J, J^T r at q. A yarn thinner than the blur: h at its
  // bound, held there from then on (its width is not seen; letting it go and come back
  // zig-zags).
  bool held = false;
  // A sample's Jacobian row has five nonzero entries: the line (0, 1), the width (2), and its
  // channel's area and offset; only those products are summed.
  auto normal_equations = [&](const YarnParams& q, YarnNormal* jtj, YarnParams* jtr) {
    jtj->setZero(np, np);
    jtr->setZero(np);
    for (const YarnSample& s : samples) {
      double dd, dh;
      const double a = q(3 + s.channel);
      const double g = Strip(s.v - q(0) - q(1) * s.u, q(2), blur, &dd, &dh);
      const std::array<int, 5> at = {0, 1, 2, 3 + s.channel, 3 + channels + s.channel};
      const std::array<double, 5> j = {-a * dd, -a * dd * s.u, a * dh, g, 1.0};
      const double r = q(3 + channels + s.channel) + a * g - s.value;
      for (int m = 0; m < 5; ++m) {
        for (int n = 0; n <= m; ++n) (*jtj)(at[m], at[n]) += j[m] * j[n];
        (*jtr)(at[m]) += j[m] * r;
      }
    }
    *jtj = jtj->selfadjointView<Eigen::Lower>();
    held = held || q(2) <= kMinHalfWidth;
    if (held) {
      jtj->row(2).setZero();
      jtj->col(2).setZero();
      (*jtj)(2, 2) = 1.0;
      (*jtr)(2) = 0.0;
    }
  };
  double current = cost(p), lambda = 1e-3, last_step = std::numeric_limits<double>::infinity();
  bool converged = false;
  YarnNormal jtj;
  YarnParams jtr;
  for (int iteration = 0; iteration < 30 && !converged; ++iteration) {
    normal_equations(p, &jtj, &jtr);
    for (int tries = 0; tries < 8; ++tries) {
      YarnNormal a = jtj;
      a.diagonal() += lambda * jtj.diagonal() + YarnParams::Constant(np, 1e-12);
      YarnParams next = p + a.ldlt().solve(-jtr);
      next(2) = std::clamp(next(2), kMinHalfWidth, 4.0);
      const double c = next.allFinite() ? cost(next) : std::numeric_limits<double>::infinity();
      if (c < current) {
        last_step = std::abs(next(0) - p(0)) + 10 * std::abs(next(1) - p(1));
        converged = last_step < 1e-5 || c > current * (1 - 1e-9);
        p = next;
        current = c;
        lambda = std::max(1e-7, lambda * 0.3);
        break;
      }
      lambda *= 10;
      if (tries == 7) converged = true;  // no step lowers the cost: at the minimum
    }
  }
  // The standard error of rho at the knot (rho + kappa u_knot) from the normal equations at
  // the solution and the residuals.
  normal_equations(p, &jtj, &jtr);
  const double dof = std::max(1.0, static_cast<double>(samples.size()) - np);
  const YarnNormal cov = jtj.ldlt().solve(YarnNormal::Identity(np, np));
  const double var = cov(0, 0) + 2 * u_knot * cov(0, 1) + u_knot * u_knot * cov(1, 1);
  fit.sigma_rho = std::sqrt(std::max(0.0, var) * current / dof);
  fit.rho = p(0) + p(1) * u_knot;
  fit.params = p;
  fit.kappa = p(1);
  fit.half_width = p(2);
  double area2 = 0.0;
  for (int c = 0; c < channels; ++c) area2 += p(3 + c) * p(3 + c);
  fit.snr = std::sqrt(area2) / std::max(std::sqrt(current / samples.size()), 1e-9);
  // The line settled to a hundredth of a pixel (the width of a yarn thinner than the blur
  // need not).
  fit.ok = (converged || last_step < 1e-2) && p.allFinite() && std::isfinite(fit.sigma_rho);
  return fit;
}

// Whether a second yarn runs beside a fitted one: parallel to it, at least `gap` px off its
// centre line and within `across` px of the branch line, where the strongest such yarn (by how
// much it lowers the residuals) lowers them by more than `significance` times their variance
// per sample, has at least `fraction` of the fitted yarn's area (the norm over the channels)
// and does a fifth of that in each half of the strip. Two yarns that close (a fold of the net seen
// edge-on, another part of the net behind) are one ridge to the rings, and the fit takes one of
// them: the junction is not known across them (the bunched Net B at 0.8 m/s had three placed
// 2-2.5 px off this way; on a normal frame about one branch in 2000 has such a yarn).
bool YarnBeside(const std::vector<YarnSample>& samples, int channels, double blur,
                const YarnFit& fit, double gap, double across, double significance,
                double fraction) {
  if (!fit.ok || fit.params.size() != 3 + 2 * channels) return false;
  const Eigen::VectorXd& p = fit.params;
  std::vector<double> residual(samples.size());
  double ss = 0.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const YarnSample& s = samples[i];
    residual[i] = s.value - p(3 + channels + s.channel) -
                  p(3 + s.channel) * StripValue(s.v - p(0) - p(1) * s.u, p(2), blur);
    ss += residual[i] * residual[i];
  }
  const double variance = ss / std::max<double>(1.0, samples.size() - p.size());
  const double area = p.segment(3, channels).norm();
  if (!(area > 0.0) || !(variance > 0.0)) return false;
  // A yarn lighter than what is behind it (or darker, on a light target): the second one too.
  const double bright = p.segment(3, channels).sum() >= 0.0 ? 1.0 : -1.0;
  // The strip's two halves (near the junction, far from it): a yarn beside runs along both and
  // lowers the residuals of each; the rim of a knot ball lies in the near half only.
  double u_min = samples[0].u, u_max = samples[0].u;
  for (const YarnSample& s : samples) u_min = std::min(u_min, s.u), u_max = std::max(u_max, s.u);
  const double u_mid = 0.5 * (u_min + u_max);
  double strongest_drop = 0.0, its_area = 0.0, its_weaker_half = 0.0;
  std::vector<double> gr(2 * channels), gg(2 * channels);
  for (double rho = -across; rho <= across + 1e-9; rho += 0.25) {
    if (std::abs(rho - p(0)) < gap) continue;
    std::fill(gr.begin(), gr.end(), 0.0);
    std::fill(gg.begin(), gg.end(), 0.0);
    for (size_t i = 0; i < samples.size(); ++i) {
      const YarnSample& s = samples[i];
      const double g = StripValue(s.v - rho - p(1) * s.u, p(2), blur);
      const int at = (s.u < u_mid ? 0 : channels) + s.channel;
      gr[at] += g * residual[i];
      gg[at] += g * g;
    }
    // Each channel's area of the second yarn by least squares on the residuals, and how much
    // it lowers them, in all and in each half.
    double drop = 0.0, half_drop[2] = {0.0, 0.0}, second = 0.0;
    for (int c = 0; c < channels; ++c) {
      const double r = gr[c] + gr[channels + c], q = gg[c] + gg[channels + c];
      if (!(q > 0.0) || r * bright <= 0.0) continue;
      const double a = r / q;
      drop += r * a;
      for (int h = 0; h < 2; ++h)
        half_drop[h] += 2.0 * a * gr[h * channels + c] - a * a * gg[h * channels + c];
      second += a * a;
    }
    if (drop > strongest_drop)
      strongest_drop = drop, its_area = std::sqrt(second),
      its_weaker_half = std::min(half_drop[0], half_drop[1]);
  }
  return strongest_drop > significance * variance && its_area >= fraction * area &&
         its_weaker_half >= 0.2 * strongest_drop;
}

}  // namespace

bool ColourChangesAt(const Junction& j, double max_px) {
  return !(max_px > 0.0) || !j.colour_step.allFinite() || (j.colour_step - j.px).norm() <= max_px;
}

double DetectorReach(const KnotDetectorOptions& o) {
  return 2.0 * o.ring_radius_px + 4 * o.ridge_sigma_px + 4;
}

namespace {

// The region in 8 bits per channel (scaled so that its largest value is 255 when it is not).
cv::Mat EightBit(const cv::Mat& region) {
  cv::Mat eight;
  if (region.depth() == CV_8U) {
    eight = region;
  } else {
    double max = 0.0;
    cv::minMaxLoc(region.reshape(1), nullptr, &max);
    region.convertTo(eight, CV_8U, max > 0 ? 255.0 / max : 1.0);
  }
  return eight;
}

// Where the background has edges: the direction of its gradient from the structure tensor
// (doubled angles: cos 2 phi, sin 2 phi, times w = |gradient| / background_edge, at most 1), and
// the tensor's trace (|gradient|^2). All CV_32F.
struct BackgroundEdges {
  cv::Mat c2, s2, trace;
};

BackgroundEdges FindBackgroundEdges(const cv::Mat& bg, double background_edge) {
  cv::Mat gx, gy;
  cv::Sobel(bg, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(bg, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  cv::Mat jxx(bg.size(), CV_32F), jyy(bg.size(), CV_32F), jxy(bg.size(), CV_32F);
  const int nc = gx.channels();
  for (int y = 0; y < bg.rows; ++y) {
    const float* ax = gx.ptr<float>(y);
    const float* ay = gy.ptr<float>(y);
    for (int x = 0; x < bg.cols; ++x) {
      float xx = 0, yy = 0, xy = 0;
      for (int c = 0; c < nc; ++c) {
        const float u = ax[nc * x + c], v = ay[nc * x + c];
        xx += u * u, yy += v * v, xy += u * v;
      }
      jxx.at<float>(y, x) = xx, jyy.at<float>(y, x) = yy, jxy.at<float>(y, x) = xy;
    }
  }
  for (cv::Mat* m : {&jxx, &jyy, &jxy}) cv::GaussianBlur(*m, *m, cv::Size(), 1.5);
  BackgroundEdges edges;
  edges.c2.create(bg.size(), CV_32F);
  edges.s2.create(bg.size(), CV_32F);
  const float level2 = static_cast<float>(background_edge * background_edge);
  for (int y = 0; y < bg.rows; ++y)
    for (int x = 0; x < bg.cols; ++x) {
      const float a = jxx.at<float>(y, x) - jyy.at<float>(y, x), b = 2 * jxy.at<float>(y, x);
      const float norm = std::sqrt(a * a + b * b);
      const float trace = jxx.at<float>(y, x) + jyy.at<float>(y, x);
      const float w = std::min(1.0f, std::sqrt(trace / level2));
      edges.c2.at<float>(y, x) = norm > 0 ? w * a / norm : 0.0f;
      edges.s2.at<float>(y, x) = norm > 0 ? w * b / norm : 0.0f;
    }
  edges.trace = jxx + jyy;
  return edges;
}

}  // namespace

KnotDetector::KnotDetector(const cv::Mat& image, cv::Rect roi, KnotDetectorOptions options)
    : o_(options) {
  const cv::Rect full(0, 0, image.cols, image.rows);
  roi_ = roi.empty() ? full : (roi & full);
  if (roi_.empty()) return;
  // Foreground: the distance from the local background, a median over a window much wider than
  // a yarn (the target mock-up or the aircraft behind the net are not one colour).
  const cv::Mat eight = EightBit(image(roi_));
  pattern_ = static_cast<int>(DemosaicedFrom(eight));
  cv::Mat background, f, bg;
  cv::medianBlur(eight, background, o_.background_window_px | 1);
  eight.convertTo(f, CV_32F, 1.0 / 255);
  background.convertTo(bg, CV_32F, 1.0 / 255);
  diff_ = f - bg;
  std::vector<cv::Mat> differences;
  cv::split(diff_, differences);
  cv::Mat fg = cv::Mat::zeros(f.size(), CV_32F);
  for (const cv::Mat& c : differences) fg += c.mul(c);
  cv::sqrt(fg, fg);
  // Small solids (corner masses) are not yarns: masked.
  MaskSolids(f);
  // Edges of the background (of the target behind the net): the median follows a straight
  // edge, but not to the pixel, nor round a corner, and what it misses is a thin line of
  // foreground along the edge, a ridge like a yarn's. Such ridges run along the background's
  // edge, a yarn crossing the edge does not: a ridge is weakened by w sin^2 of its angle to the
  // background's gradient (FindBackgroundEdges).
  BackgroundEdges edges;
  if (o_.background_edge > 0) {
    edges = FindBackgroundEdges(bg, o_.background_edge);
    // Nor are the yarn model's samples taken on such an edge (the model has no step).
    const float level2 = static_cast<float>(o_.background_edge * o_.background_edge);
    masked_.setTo(kEdge, (edges.trace > 0.25f * level2) & (masked_ == 0));
  }
  // Ridges of the foreground at the thread's scale, and the branch peaks' threshold.
  ComputeRidges(fg, edges.c2, edges.s2);
  threshold_ = PeakThreshold();
}

void KnotDetector::MaskSolids(const cv::Mat& f) {
  // Small solids (corner masses) are not yarns: their rims look like ridges and meet the yarns
  // like junctions. A solid is what survives an opening with a disc several yarn widths across
  // (yarns and their crossings, however many, are thinner) of the region that stands out from
  // the region's median colour; only compact blobs count (a target face behind the net is
  // background, handled by the local median).
  std::vector<cv::Mat> channels;
  cv::split(f, channels);
  cv::Mat global = cv::Mat::zeros(f.size(), CV_32F);
  for (const cv::Mat& c : channels) {
    cv::Mat d = c - Quantile(c, 0.5, 3);
    global += d.mul(d);
  }
  cv::sqrt(global, global);
  cv::Mat bright = global > o_.solid_fraction * Quantile(global, 0.995), opened;
  const int disc = 2 * static_cast<int>(std::ceil(2.5 * o_.ridge_sigma_px)) + 1;
  cv::morphologyEx(bright, opened, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(disc, disc)));
  FindSolids(opened, global);
}

void KnotDetector::ComputeRidges(const cv::Mat& fg, const cv::Mat& edge_c2,
                                 const cv::Mat& edge_s2) {
  // Along a ridge the Hessian's larger eigenvalue (about 0) has its eigenvector, at angle theta;
  // stored as R (cos 2 theta, sin 2 theta), which interpolates bilinearly (doubled angles).
  cv::Mat smooth, dxx, dyy, dxy;
  cv::GaussianBlur(fg, smooth, cv::Size(), o_.ridge_sigma_px);
  cv::Sobel(smooth, dxx, CV_32F, 2, 0, 3);
  cv::Sobel(smooth, dyy, CV_32F, 0, 2, 3);
  cv::Sobel(smooth, dxy, CV_32F, 1, 1, 3);
  ridge_.create(fg.size(), CV_32F);
  field_.create(fg.size(), CV_32FC3);
  for (int y = 0; y < fg.rows; ++y)
    for (int x = 0; x < fg.cols; ++x) {
      const float a = dxx.at<float>(y, x), b = dyy.at<float>(y, x), c = dxy.at<float>(y, x);
      const float root = std::sqrt(0.25f * (a - b) * (a - b) + c * c);
      const float lambda_min = 0.5f * (a + b) - root;
      float r = masked_.at<uchar>(y, x) == kSolid ? 0.0f : std::max(0.0f, -lambda_min);
      // The ridge's direction (doubled angle): cos 2 theta, sin 2 theta.
      const float c2 = root > 0 ? (a - b) / (2 * root) : 0.0f, s2 = root > 0 ? c / root : 0.0f;
      if (!edge_c2.empty()) {
        // sin^2(theta - phi) = (1 - cos 2 theta cos 2 phi - sin 2 theta sin 2 phi) / 2.
        const float ec = edge_c2.at<float>(y, x), es = edge_s2.at<float>(y, x);
        const float w = std::sqrt(ec * ec + es * es);
        r *= 1.0f - (0.5f * w - 0.5f * (c2 * ec + s2 * es));
      }
      ridge_.at<float>(y, x) = r;
      field_.at<cv::Vec3f>(y, x) = cv::Vec3f(r, r * c2, r * s2);
    }
}

double KnotDetector::PeakThreshold() const {
  // A branch peak must stand out from the background's noise (the median ridge strength is the
  // background's: yarns cover a small part of the region; a corner mass's masked pixels are
  // not counted). Not from the strong yarns: on a rendered shot of Net A the weakest yarn at a
  // knot was under 1/13 of the strongest at one knot in ten, under 1/26 at one in a hundred
  // (royal blue and brown beside white), and a quarter of the strong ridges missed a knot in
  // four.
  std::vector<float> open;
  open.reserve(ridge_.total());
  for (int y = 0; y < ridge_.rows; ++y)
    for (int x = 0; x < ridge_.cols; ++x)
      if (masked_.at<uchar>(y, x) != kSolid) open.push_back(ridge_.at<float>(y, x));
  const cv::Mat unmasked(open, false);
  return open.empty() ? o_.min_peak
                      : std::max({o_.noise_factor * Quantile(unmasked, 0.5),
                                  o_.peak_fraction * Quantile(unmasked, 0.99), o_.min_peak});
}

void KnotDetector::FindSolids(const cv::Mat& blobs, const cv::Mat& level) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(blobs, labels, stats, centroids, 8, CV_32S);
  masked_ = cv::Mat::zeros(blobs.size(), CV_8U);
  // A blob cut by the region's border may be a piece of something large (a face of the
  // target): a solid only when small against the region; one wholly inside is a solid up to
  // max_solid_area_px.
  const double largest_cut = std::min(o_.max_solid_area_px, 0.25 * blobs.rows * blobs.cols);
  auto at = [&](const Eigen::Vector2d& q) {  // bilinear, 0 outside
    if (!(q.x() >= 0 && q.y() >= 0 && q.x() < level.cols - 1 && q.y() < level.rows - 1)) return 0.0;
    const int x = static_cast<int>(q.x()), y = static_cast<int>(q.y());
    const double fx = q.x() - x, fy = q.y() - y;
    const float* r0 = level.ptr<float>(y);
    const float* r1 = level.ptr<float>(y + 1);
    return (1 - fy) * ((1 - fx) * r0[x] + fx * r0[x + 1]) +
           fy * ((1 - fx) * r1[x] + fx * r1[x + 1]);
  };
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const int x0 = stats.at<int>(i, cv::CC_STAT_LEFT), y0 = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    const bool inside = x0 > 2 && y0 > 2 && x0 + w < blobs.cols - 2 && y0 + h < blobs.rows - 2;
    if (area > (inside ? o_.max_solid_area_px : largest_cut)) continue;
    masked_.setTo(kSolid, labels == i);
    // The centre of a solid wholly inside the region: a circle through its outline. On rays
    // from the blob's centroid the outline is where the level falls steepest (where it falls
    // to half the level 2 px inside put small balls' centres 0.14 px towards their lit side, the
    // steepest drop 0.10 px: a shaded ball is brightest at its lit limb). Rays along an attached
    // yarn find its end or nothing: outliers of the circle.
    if (!inside) continue;
    const Eigen::Vector2d c0(centroids.at<double>(i, 0), centroids.at<double>(i, 1));
    const double r0 = std::sqrt(area / M_PI);
    std::vector<Eigen::Vector2d> edge;
    constexpr int kRays = 72;
    constexpr double kStep = 0.25;
    for (int k = 0; k < kRays; ++k) {
      const double a = 2 * M_PI * k / kRays;
      const Eigen::Vector2d d(std::cos(a), std::sin(a));
      std::vector<double> drops;
      double steepest = 0.0;
      int best = -1;
      for (double r = 0.3 * r0; r <= 1.5 * r0 + 4; r += kStep) {
        drops.push_back(at(c0 + (r - 0.5) * d) - at(c0 + (r + 0.5) * d));
        if (drops.back() > steepest)
          steepest = drops.back(), best = static_cast<int>(drops.size()) - 1;
      }
      if (best <= 0 || best + 1 >= static_cast<int>(drops.size())) continue;
      // Sub-sample: the vertex of the parabola through the steepest drop and its neighbours.
      const double before = drops[best - 1], after = drops[best + 1];
      const double curvature = before - 2 * drops[best] + after;
      const double delta = curvature < 0 ? 0.5 * (before - after) / curvature : 0.0;
      const double found = 0.3 * r0 + kStep * (best + std::clamp(delta, -1.0, 1.0));
      if (found > 0) edge.push_back(c0 + found * d);
    }
    // Circle fit (Kasa, algebraic), outliers out, then refined geometrically (Gauss-Newton).
    Eigen::Vector2d centre = c0;
    double radius = r0, rms = 0.0;
    std::vector<Eigen::Vector2d> used = edge;
    for (int round = 0; round < 3 && used.size() >= kRays / 3; ++round) {
      Eigen::MatrixXd a(used.size(), 3);
      Eigen::VectorXd b(used.size());
      for (size_t m = 0; m < used.size(); ++m) {
        a.row(m) << used[m].x(), used[m].y(), 1.0;
        b(m) = -(used[m].squaredNorm());
      }
      const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);
      centre = Eigen::Vector2d(-0.5 * s(0), -0.5 * s(1));
      radius = std::sqrt(std::max(0.0, centre.squaredNorm() - s(2)));
      for (int it = 0; it < 5; ++it) {
        Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
        Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
        for (const auto& q : used) {
          const Eigen::Vector2d d = q - centre;
          const double dist = d.norm();
          if (dist < 1e-9) continue;
          const Eigen::Vector3d j(-d.x() / dist, -d.y() / dist, -1.0);
          jtj += j * j.transpose();
          jtr += j * (dist - radius);
        }
        const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
        if (!step.allFinite()) break;
        centre += step.head<2>();
        radius += step(2);
      }
      std::vector<double> residual;
      for (const auto& q : edge) residual.push_back(std::abs((q - centre).norm() - radius));
      std::vector<double> sorted = residual;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      const double limit = std::max(0.5, 4.0 * 1.4826 * sorted[sorted.size() / 2]);
      used.clear();
      double ss = 0.0;
      for (size_t m = 0; m < edge.size(); ++m)
        if (residual[m] <= limit) used.push_back(edge[m]), ss += residual[m] * residual[m];
      rms = used.empty() ? 0.0 : std::sqrt(ss / used.size());
    }
    if (used.size() < kRays / 2 || !(radius > 1.0) || (centre - c0).norm() > 0.5 * r0) continue;
    solids_.push_back({centre + Eigen::Vector2d(roi_.x, roi_.y), radius, rms});
  }
  cv::dilate(masked_, masked_, cv::Mat(), cv::Point(-1, -1),
             static_cast<int>(std::ceil(2 * o_.ridge_sigma_px)));
}

std::vector<double> KnotDetector::SampleRing(const Eigen::Vector2d& centre, double radius) const {
  const int n = kRingSamples;
  const RingTable& t = Table();
  std::vector<double> ring(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const double u = centre.x() + radius * t.c[i] - roi_.x;
    const double v = centre.y() + radius * t.s[i] - roi_.y;
    if (!(u >= 0 && v >= 0 && u <= field_.cols - 1 && v <= field_.rows - 1)) continue;
    const int x0 = std::min(static_cast<int>(u), field_.cols - 2);
    const int y0 = std::min(static_cast<int>(v), field_.rows - 2);
    const float fx = static_cast<float>(u - x0), fy = static_cast<float>(v - y0);
    const cv::Vec3f* r0 = field_.ptr<cv::Vec3f>(y0) + x0;
    const cv::Vec3f* r1 = field_.ptr<cv::Vec3f>(y0 + 1) + x0;
    const cv::Vec3f q =
        (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
    // R cos^2(theta - a) = R (1 + cos 2 theta cos 2a + sin 2 theta sin 2a) / 2.
    ring[i] = 0.5 * (q[0] + q[1] * t.c2[i] + q[2] * t.s2[i]);
  }
  return ring;
}

std::vector<double> KnotDetector::Peaks(const std::vector<double>& profile, double* weakest) const {
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
  std::sort(peaks.begin(), peaks.end(),
            [](const Peak& x, const Peak& y) { return x.value > y.value; });
  std::vector<Peak> kept;
  for (const Peak& pk : peaks) {
    bool near = false;
    for (const Peak& k : kept) near = near || AngleBetween(pk.angle, k.angle) < separation;
    if (!near) kept.push_back(pk);
  }
  std::sort(kept.begin(), kept.end(),
            [](const Peak& x, const Peak& y) { return x.angle < y.angle; });
  std::vector<double> angles;
  double weak = std::numeric_limits<double>::infinity();
  for (const Peak& k : kept) {
    angles.push_back(k.angle);
    weak = std::min(weak, k.value / threshold_);
  }
  if (weakest) *weakest = angles.empty() ? 0.0 : weak;
  return angles;
}

namespace {

// The least-squares intersection of lines (point, unit direction), each weighted (all 1 when
// `weights` is empty): false when they are about parallel. *rms: the RMS distance of the
// point from the lines; *sigma (when given): the point's largest standard deviation, the
// weights being 1 / the variance of each line's offset.
bool Intersect(const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& lines,
               const std::vector<double>& weights, Eigen::Vector2d* point, double* rms,
               double* sigma = nullptr) {
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero(), geometry = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& [q, d] = lines[i];
    const double w = weights.empty() ? 1.0 : weights[i];
    const Eigen::Matrix2d m = Eigen::Matrix2d::Identity() - d * d.transpose();
    geometry += m;
    a += w * m;
    b += w * m * q;
  }
  // Lines at small angles meet far from where they are known (the geometry decides this, not
  // the weights).
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(geometry);
  if (!(svd.singularValues()[1] > 0.05 * svd.singularValues()[0])) return false;
  *point = a.ldlt().solve(b);
  if (sigma) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(a);
    *sigma = 1.0 / std::sqrt(std::max(eig.eigenvalues()[0], 1e-12));
  }
  double ss = 0.0;
  for (const auto& [q, d] : lines) {
    const Eigen::Vector2d off = *point - q;
    ss += (off - off.dot(d) * d).squaredNorm();
  }
  *rms = std::sqrt(ss / lines.size());
  return point->allFinite();
}

}  // namespace

bool KnotDetector::NearBackgroundEdge(const Eigen::Vector2d& px, double radius) const {
  if (masked_.empty()) return false;
  const int r = static_cast<int>(std::ceil(radius));
  const int cx = static_cast<int>(std::lround(px.x())) - roi_.x;
  const int cy = static_cast<int>(std::lround(px.y())) - roi_.y;
  for (int y = std::max(0, cy - r); y <= std::min(masked_.rows - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(masked_.cols - 1, cx + r); ++x)
      if (masked_.at<uchar>(y, x) == kEdge && (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r)
        return true;
  return false;
}

int KnotDetector::YarnsAlong(const Eigen::Vector2d& px, const std::vector<double>& angles,
                             double tolerance_rad, std::vector<bool>* seen_along) const {
  if (seen_along) seen_along->assign(angles.size(), false);
  if (ridge_.empty() || angles.empty()) return 0;
  const int n_rings = std::max(2, o_.rings_count);
  const int quorum = std::max(2, n_rings - 1);
  std::vector<int> seen(angles.size(), 0);
  for (int i = 0; i < n_rings; ++i) {
    const double radius = o_.ring_radius_px * (1.0 + static_cast<double>(i) / (n_rings - 1));
    const std::vector<double> peaks = Peaks(SampleRing(px, radius), nullptr);
    for (size_t a = 0; a < angles.size(); ++a)
      for (double p : peaks)
        if (AngleBetween(p, angles[a]) <= tolerance_rad) {
          ++seen[a];
          break;
        }
  }
  if (seen_along)
    for (size_t a = 0; a < angles.size(); ++a) (*seen_along)[a] = seen[a] >= quorum;
  return static_cast<int>(
      std::count_if(seen.begin(), seen.end(), [&](int s) { return s >= quorum; }));
}

std::optional<Junction> KnotDetector::ExamineRings(const Eigen::Vector2d& px) const {
  return ExamineRings(px, o_.ring_radius_px);
}

std::optional<Junction> KnotDetector::ExamineRings(const Eigen::Vector2d& px,
                                                   double ring_radius_px) const {
  if (ridge_.empty()) return std::nullopt;
  auto is_junction = [&](const std::vector<double>& angles) {
    const size_t b = angles.size();
    if (b == 2) return AngleBetween(angles[0], angles[1]) < o_.straight_angle_deg * M_PI / 180;
    return b == 3 || b == 4;
  };
  // Branches are followed on rings_count circles from r0 to 2 r0; each branch line is fitted
  // through its peaks. All rings but one must agree on the branches: one may cross something
  // else (the edge of the target, another yarn's end) or miss a yarn where it crosses such an
  // edge; it is left out.
  const int n_rings = std::max(2, o_.rings_count);
  const int quorum = std::max(2, n_rings - 1);
  std::vector<double> radii(n_rings);
  for (int i = 0; i < n_rings; ++i)
    radii[i] = ring_radius_px * (1.0 + static_cast<double>(i) / (n_rings - 1));
  std::vector<std::vector<double>> rings(n_rings);
  std::vector<double> weak(n_rings, 0.0);
  // The rings' majority: the branch count shared by a quorum of rings, whose innermost ring
  // is a junction; -1 when there is none. Rings are sampled as needed: most seeds are decided
  // by the first two.
  auto majority = [&](const Eigen::Vector2d& centre, bool lazy) {
    int sampled = 0;
    for (; sampled < n_rings; ++sampled) {
      rings[sampled] = Peaks(SampleRing(centre, radii[sampled]), &weak[sampled]);
      if (lazy && sampled + 1 >= n_rings - quorum + 1) {
        // Any quorum needs one of the rings sampled so far to be a junction.
        bool any = false;
        for (int i = 0; i <= sampled; ++i) any = any || is_junction(rings[i]);
        if (!any) return -1;
      }
    }
    for (int i = 0; i < n_rings; ++i) {
      if (!is_junction(rings[i])) continue;
      int agree = 0;
      for (int k = 0; k < n_rings; ++k) agree += rings[k].size() == rings[i].size();
      if (agree >= quorum) return static_cast<int>(rings[i].size());
    }
    return -1;
  };
  const int count = majority(px, true);
  if (count < 0) return std::nullopt;
  Eigen::Vector2d p = px;
  Junction j;
  for (int iteration = 0; iteration < 5; ++iteration) {
    if (iteration > 0 && majority(p, false) != count) return std::nullopt;
    std::vector<int> used;
    double weakest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n_rings; ++i)
      if (static_cast<int>(rings[i].size()) == count) {
        used.push_back(i);
        weakest = std::min(weakest, weak[i]);
      }
    const std::vector<double>& inner = rings[used.front()];
    if (!is_junction(inner)) return std::nullopt;
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> lines;
    std::vector<Eigen::Vector2d> pts;
    for (double t0 : inner) {
      // The branch's points on the agreeing circles (nearest peak in angle to the previous
      // circle's).
      double t_prev = t0;
      pts.clear();
      for (int i : used) {
        double best = 1e9, t = t_prev;
        for (double c : rings[i])
          if (AngleBetween(c, t_prev) < best) best = AngleBetween(c, t_prev), t = c;
        if (best > 20 * M_PI / 180) return std::nullopt;
        pts.push_back(p + radii[i] * Eigen::Vector2d(std::cos(t), std::sin(t)));
        t_prev = t;
      }
      // Least-squares line through the points: centroid and principal direction, outwards.
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const auto& q : pts) mean += q;
      mean /= static_cast<double>(pts.size());
      Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
      for (const auto& q : pts) cov += (q - mean) * (q - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
      Eigen::Vector2d d = eig.eigenvectors().col(1);
      if (d.dot(pts.back() - pts.front()) < 0) d = -d;
      lines.emplace_back(mean, d);
    }
    Eigen::Vector2d next;
    double rms = 0.0;
    if (!Intersect(lines, {}, &next, &rms) || (next - px).norm() > radii[0]) return std::nullopt;
    j.px = next;
    j.branches = count;
    j.branch_angles_rad.clear();
    for (const auto& [q, d] : lines) j.branch_angles_rad.push_back(std::atan2(d.y(), d.x()));
    j.fit_rms_px = rms;
    j.contrast = weakest;
    const bool settled = (next - p).norm() < (o_.fit_yarns ? 0.05 : 1e-3);
    p = next;
    if (settled) break;
  }
  j.confidence = std::clamp((j.contrast - 1.0) / 2.0, 0.0, 1.0) *
                 std::exp(-0.5 * (j.fit_rms_px / 0.5) * (j.fit_rms_px / 0.5));
  return j;
}

namespace {

// Whether one of the junction's yarns alone places it along the others: two yarns, or three of
// which two are one straight yarn (an edge knot).
bool HasLoneYarn(const Junction& j, double straight_angle_deg) {
  const std::vector<double>& a = j.branch_angles_rad;
  if (a.size() == 2) return true;
  if (a.size() != 3) return false;
  for (size_t i = 0; i < 3; ++i)
    for (size_t k = i + 1; k < 3; ++k)
      if (AngleBetween(a[i], a[k]) > straight_angle_deg * M_PI / 180) return true;
  return false;
}

}  // namespace

std::optional<Junction> KnotDetector::Refine(const Junction& j) const {
  if (!o_.fit_yarns) return j;
  const std::optional<Junction> out = RefineOver(j, o_.fit_from_px, 2.0 * o_.ring_radius_px);
  if (!(o_.near_fit_to_px > 0.0)) return out;
  // Fitted again on the yarns' first few pixels, where the default strip settled (or, where it
  // fitted no line through the junction, a yarn turned within it, where the rings put it).
  const std::optional<Junction> rings = ExamineRings(out ? out->px : j.px, 0.5 * o_.near_fit_to_px);
  // Without the default's junction, the near fit alone, on the same yarns.
  if (!rings || (!out && rings->branches != j.branches)) return out;
  bool near_bends = false;
  std::optional<Junction> near =
      RefineOver(*rings, o_.near_fit_from_px, o_.near_fit_to_px, &near_bends);
  if (!out) {
    if (near) near->contrast = j.contrast;
    return near;
  }
  // A slack link buckles, and where it turns within the strip (the knotless Net B's links, ~12 px
  // from the knot in the far pair) the line fitted over the whole strip misses the knot by up to
  // 3.5 px along its normal, with a good fit. Near the knot the yarns are straight: where the
  // near fit settles elsewhere, it is the junction.
  //
  // A lone yarn that bends even within the near strip (it leaves the knot turned, then runs
  // aside): the strip's fit, which took it for straight, placed the junction along the others
  // by about its offset.
  if (near_bends && rings->branches == out->branches) return std::nullopt;
  // Nor may the two fits of such a junction disagree by much: the lone yarn is all that places
  // it along the others, and the fits see it bend.
  if (near && near->branches == out->branches && HasLoneYarn(*out, o_.straight_angle_deg) &&
      o_.lone_agree_px > 0.0 && (near->px - out->px).norm() > o_.lone_agree_px &&
      (near->px - out->px).norm() <= o_.bend_px)
    return std::nullopt;
  // The same yarns (a knot ball's rim, near enough for the small rings, adds branches).
  // Only a near fit of every yarn, which places the junction well, overrules the default: on
  // its few pixels a dim yarn of one dye (seen by every second pixel of a mosaic) can take a
  // wrong turn and still fit.
  if (near && near->branches == out->branches && (near->px - out->px).norm() > o_.bend_px &&
      near->fitted_branches == near->branches && near->sigma_px <= o_.near_sigma_px) {
    Junction bent = *near;
    bent.contrast = out->contrast;
    bent.confidence = std::min(out->confidence, near->confidence);
    return bent;
  }
  return out;
}

namespace {

// Whether a yarn that alone fixes a junction's place along the others (the inner yarn of an edge
// knot, whose other two are one straight line; either yarn of a two-yarn junction) bends within
// its strip: fitted on the strip's near half and on its far half, its line's offset at the
// junction differs by more than max_px. Such a yarn's line, fitted over the strip, misses the
// junction along the straight yarn by about that much, and nothing else checks it (a knotless
// edge knot whose slack inner link turns within the strip was placed 2-5 px along the edge, with
// the fitted lines meeting well). `lines`: the fitted lines, of branches `fitted`; `samples`:
// each branch's samples (u from the strip's middle; the junction at u = -middle).
bool LoneYarnBends(const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>>& lines,
                   const std::vector<int>& fitted,
                   const std::vector<std::vector<YarnSample>>& samples, double middle,
                   const std::vector<double>& half_widths, int channels, double blur,
                   double max_px) {
  if (!(max_px > 0.0)) return false;
  for (size_t i = 0; i < lines.size(); ++i) {
    // Lone: the other lines do not fix a point.
    Eigen::Matrix2d geometry = Eigen::Matrix2d::Zero();
    for (size_t o = 0; o < lines.size(); ++o)
      if (o != i)
        geometry += Eigen::Matrix2d::Identity() - lines[o].second * lines[o].second.transpose();
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(geometry);
    if (svd.singularValues()[1] > 0.05 * svd.singularValues()[0]) continue;
    const int b = fitted[i];
    std::vector<YarnSample> near, far;
    for (const YarnSample& s : samples[b]) (s.u < 0.0 ? near : far).push_back(s);
    const YarnFit a = FitYarn(near, channels, blur, true, half_widths[b], -middle);
    const YarnFit z = FitYarn(far, channels, blur, true, half_widths[b], -middle);
    if (a.ok && z.ok && a.snr >= 3.0 && z.snr >= 3.0 && std::abs(a.rho - z.rho) > max_px)
      return true;
  }
  return false;
}

}  // namespace

std::optional<Junction> KnotDetector::RefineOver(const Junction& j, double from, double to,
                                                 bool* lone_bends) const {
  if (lone_bends) *lone_bends = false;
  const int channels = diff_.channels();
  const BayerPattern pattern = static_cast<BayerPattern>(pattern_);
  const double middle = 0.5 * (from + to);
  const double across = o_.fit_half_width_px;
  std::vector<double> angles = j.branch_angles_rad;
  std::vector<double> half_widths(angles.size(), 0.5);
  Eigen::Vector2d centre = j.px;
  Junction out = j;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> lines;
  std::vector<int> fitted;
  std::vector<std::vector<YarnSample>> branch_samples(angles.size());
  std::vector<YarnFit> branch_fits(angles.size());
  double last_move = 0.0;
  // Fitted from the rings' lines (searching across them), then again from the fitted lines
  // through the new centre, until it settles (most do in two passes; five, so that one started
  // a few pixels off still settles: with three, settle_px refused 11 more Net A knots in 60
  // frames, with five 4).
  for (int pass = 0; pass < 5; ++pass) {
    lines.clear();
    fitted.clear();
    std::vector<double> weights;
    for (size_t b = 0; b < angles.size(); ++b) {
      const Eigen::Vector2d d(std::cos(angles[b]), std::sin(angles[b])), n(-d.y(), d.x());
      // The samples of this branch: in its strip, nearer (in angle) to it than to any other
      // branch, off solids; of a demosaiced image only each pixel's own colour.
      std::vector<YarnSample> samples;
      const Eigen::Vector2d a = centre + from * d, z = centre + to * d;
      const int x0 =
          std::max(0, static_cast<int>(std::floor(std::min(a.x(), z.x()) - across)) - roi_.x);
      const int x1 = std::min(
          diff_.cols - 1, static_cast<int>(std::ceil(std::max(a.x(), z.x()) + across)) - roi_.x);
      const int y0 =
          std::max(0, static_cast<int>(std::floor(std::min(a.y(), z.y()) - across)) - roi_.y);
      const int y1 = std::min(
          diff_.rows - 1, static_cast<int>(std::ceil(std::max(a.y(), z.y()) + across)) - roi_.y);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector2d q = Eigen::Vector2d(x + roi_.x, y + roi_.y) - centre;
          const double u = q.dot(d), v = q.dot(n);
          if (u < from || u > to || std::abs(v) > across || masked_.at<uchar>(y, x)) continue;
          const double polar = std::atan2(q.y(), q.x());
          bool nearest = true;
          for (size_t o = 0; o < angles.size(); ++o)
            nearest = nearest &&
                      (o == b || AngleBetween(polar, angles[o]) > AngleBetween(polar, angles[b]));
          if (!nearest) continue;
          if (pattern != BayerPattern::kNone) {
            const int c = BayerColor(pattern, y, x);
            samples.push_back({u - middle, v, c, diff_.ptr<float>(y)[3 * x + c]});
          } else {
            for (int c = 0; c < channels; ++c)
              samples.push_back({u - middle, v, c, diff_.ptr<float>(y)[channels * x + c]});
          }
        }
      const YarnFit fit =
          FitYarn(samples, channels, o_.yarn_blur_px, pass == 0, half_widths[b], -middle);
      branch_samples[b] = std::move(samples);
      branch_fits[b] = fit;
      // A branch counts when its yarn fits well (a clear signal, a line known to a fraction of
      // a pixel) and stays near the rings' line along the strip.
      if (!fit.ok || fit.snr < 3.0 || fit.sigma_rho > 0.3 ||
          std::abs(fit.rho + fit.kappa * middle) > 1.5)
        continue;
      const Eigen::Vector2d dir = (d + fit.kappa * n).normalized();
      lines.emplace_back(centre + fit.rho * n, dir);
      weights.push_back(1.0 / std::max(fit.sigma_rho * fit.sigma_rho, 0.03 * 0.03));
      fitted.push_back(static_cast<int>(b));
      half_widths[b] = std::max(0.1, fit.half_width);
    }
    // At most one branch of four left out (too dim to fit, a yarn crossing it, the edge of the
    // target), and the lines left must cross: three at least, which then check each other (two
    // lines always meet: an edge knot whose dim yarn was left out was once put 2 px off).
    Eigen::Vector2d next;
    double rms = 0.0, sigma = 0.0;
    if (lines.size() < std::min<size_t>(angles.size(), 3) || lines.size() + 1 < angles.size() ||
        !Intersect(lines, weights, &next, &rms, &sigma) ||
        (next - j.px).norm() > 0.5 * o_.ring_radius_px)
      return std::nullopt;
    last_move = (next - centre).norm();
    const bool settled = last_move < 0.01;
    centre = next;
    out.px = next;
    out.fit_rms_px = rms;
    out.sigma_px = sigma;
    out.fitted_branches = static_cast<int>(lines.size());
    for (size_t i = 0; i < lines.size(); ++i)
      angles[fitted[i]] = std::atan2(lines[i].second.y(), lines[i].second.x());
    out.branch_angles_rad = angles;
    if (settled) break;
  }
  // A fit that still moved on its last pass has not found the junction (Net B's crossings,
  // whose links each turn at the knot, can walk it from line to line).
  if (last_move > o_.settle_px) return std::nullopt;
  // The fitted yarns must meet in one point.
  if (out.fit_rms_px > 0.5) return std::nullopt;
  if (LoneYarnBends(lines, fitted, branch_samples, middle, half_widths, channels, o_.yarn_blur_px,
                    o_.lone_bend_px)) {
    if (lone_bends) *lone_bends = true;
    return std::nullopt;
  }
  // And none may have another yarn beside it.
  if (o_.beside_significance > 0.0)
    for (int b : fitted)
      if (YarnBeside(branch_samples[b], channels, o_.yarn_blur_px, branch_fits[b], o_.beside_gap_px,
                     across, o_.beside_significance, o_.beside_fraction))
        return std::nullopt;
  // An edge junction: where its straight pair's colour changes.
  if (o_.colour_step && angles.size() == 3 && lines.size() == 3)
    for (int i = 0; i < 3; ++i)
      for (int k = i + 1; k < 3; ++k)
        if (AngleBetween(angles[fitted[i]], angles[fitted[k]]) >
            o_.straight_angle_deg * M_PI / 180) {
          const int l = 3 - i - k;
          const double step =
              ColourStep(out.px, lines[i], lines[k], lines[l], branch_fits[fitted[i]].params,
                         branch_fits[fitted[k]].params, branch_fits[fitted[l]].params);
          out.colour_step = out.px + step * (lines[k].second - lines[i].second).normalized();
        }
  out.confidence = std::clamp((out.contrast - 1.0) / 2.0, 0.0, 1.0) *
                   std::exp(-0.5 * (out.fit_rms_px / 0.5) * (out.fit_rms_px / 0.5));
  return out;
}

double KnotDetector::ColourStep(const Eigen::Vector2d& px, const Line& a, const Line& b,
                                const Line& l, const Eigen::VectorXd& pa, const Eigen::VectorXd& pb,
                                const Eigen::VectorXd& pl) const {
  const int channels = diff_.channels();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd ca = pa.segment(3, channels), cb = pb.segment(3, channels);
  if (!(ca.norm() > 0.0) || !(cb.norm() > 0.0) || (ca.normalized() - cb.normalized()).norm() < 0.5)
    return nan;
  // The background left in the foreground: the three fits' offsets, averaged.
  const Eigen::VectorXd offset =
      (pa.segment(3 + channels, channels) + pb.segment(3 + channels, channels) +
       pl.segment(3 + channels, channels)) /
      3.0;
  const Eigen::VectorXd cl = pl.segment(3, channels);
  const double blur = o_.yarn_blur_px;
  const Eigen::Vector2d e = (b.second - a.second).normalized();  // along the pair, towards b
  auto normal = [](const Line& line) { return Eigen::Vector2d(-line.second.y(), line.second.x()); };
  const Eigen::Vector2d na = normal(a), nb = normal(b), nl = normal(l);
  const BayerPattern pattern = static_cast<BayerPattern>(pattern_);
  // The samples within 8 px of the junction: each one's place along the pair, each yarn's
  // strip value there (the lone yarn's ending at the junction), channel and value.
  struct Sample {
    double t, sa, sb, sl;
    int channel;
    double value;
  };
  std::vector<Sample> samples;
  constexpr double kReach = 8.0;
  const auto cdf = [&](double x) { return 0.5 * std::erfc(-x / (std::sqrt(2.0) * blur)); };
  for (int y = static_cast<int>(std::floor(px.y() - kReach)) - roi_.y;
       y <= static_cast<int>(std::ceil(px.y() + kReach)) - roi_.y; ++y)
    for (int x = static_cast<int>(std::floor(px.x() - kReach)) - roi_.x;
         x <= static_cast<int>(std::ceil(px.x() + kReach)) - roi_.x; ++x) {
      if (x < 0 || y < 0 || x >= diff_.cols || y >= diff_.rows || masked_.at<uchar>(y, x)) continue;
      const Eigen::Vector2d q(x + roi_.x, y + roi_.y);
      if ((q - px).norm() > kReach) continue;
      const double va = (q - a.first).dot(na), vb = (q - b.first).dot(nb),
                   vl = (q - l.first).dot(nl);
      const double sa = StripValue(va, pa(2), blur), sb = StripValue(vb, pb(2), blur),
                   sl = StripValue(vl, pl(2), blur) * cdf((q - px).dot(l.second));
      const double t = (q - px).dot(e);
      if (pattern != BayerPattern::kNone) {
        const int c = BayerColor(pattern, y, x);
        samples.push_back({t, sa, sb, sl, c, diff_.ptr<float>(y)[3 * x + c]});
      } else {
        for (int c = 0; c < channels; ++c)
          samples.push_back({t, sa, sb, sl, c, diff_.ptr<float>(y)[channels * x + c]});
      }
    }
  double best = std::numeric_limits<double>::infinity(), best_s = nan;
  for (double s = -6.0; s <= 6.0 + 1e-9; s += 0.1) {
    double sse = 0.0;
    for (const Sample& m : samples) {
      const double w = cdf(m.t - s);
      const double model = offset(m.channel) + (1.0 - w) * ca(m.channel) * m.sa +
                           w * cb(m.channel) * m.sb + cl(m.channel) * m.sl;
      sse += (m.value - model) * (m.value - model);
    }
    if (sse < best) best = sse, best_s = s;
  }
  return best_s;
}

std::optional<Junction> KnotDetector::FitAlong(const Eigen::Vector2d& px,
                                               const std::vector<double>& angles,
                                               double from_px) const {
  if (angles.size() < 2 || diff_.empty()) return std::nullopt;
  Junction seed;
  seed.px = px;
  seed.branches = static_cast<int>(angles.size());
  seed.branch_angles_rad = angles;
  seed.contrast = 2.0;  // no rings' peaks to measure it by: confidence from the fit alone
  std::optional<Junction> j = RefineOver(seed, from_px, from_px + o_.near_fit_to_px);
  if (j) j->branches = j->fitted_branches;
  return j;
}

std::optional<Junction> KnotDetector::Examine(const Eigen::Vector2d& px) const {
  const std::optional<Junction> j = ExamineRings(px);
  return j ? Refine(*j) : std::nullopt;
}

std::vector<Junction> KnotDetector::FindInCircle(const Eigen::Vector2d& centre,
                                                 double radius) const {
  // Junctions from the rings, merged; then each refined once. Seeds on a grid, nearest the
  // centre first: a seed within 3/4 of a ring radius of a junction already found is not needed
  // (two junctions that close are none: each ring would see the other's yarns too).
  std::vector<Eigen::Vector2d> seeds;
  const double step = 1.5;
  for (double dy = -radius; dy <= radius; dy += step)
    for (double dx = -radius; dx <= radius; dx += step)
      if (dx * dx + dy * dy <= radius * radius) seeds.emplace_back(dx, dy);
  std::stable_sort(seeds.begin(), seeds.end(),
                   [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
                     return a.squaredNorm() < b.squaredNorm();
                   });
  std::vector<Junction> coarse;
  for (const Eigen::Vector2d& offset : seeds) {
    const Eigen::Vector2d seed = centre + offset;
    bool near = false;
    for (const Junction& j : coarse) near = near || (j.px - seed).norm() < 0.75 * o_.ring_radius_px;
    if (near) continue;
    const std::optional<Junction> j = ExamineRings(seed);
    if (!j || (j->px - centre).norm() > radius + o_.merge_px) continue;
    bool merged = false;
    for (Junction& k : coarse)
      if ((k.px - j->px).norm() < o_.merge_px) {
        if (j->confidence > k.confidence) k = *j;
        merged = true;
      }
    if (!merged) coarse.push_back(*j);
  }
  std::vector<Junction> found;
  for (const Junction& c : coarse) {
    const std::optional<Junction> j = Refine(c);
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

std::vector<Junction> KnotDetector::SolidsInCircle(const Eigen::Vector2d& centre,
                                                   double radius) const {
  std::vector<Junction> found;
  for (const Solid& s : solids_)
    if ((s.centre - centre).norm() <= radius) found.push_back(SolidJunction(s));
  return found;
}

Junction KnotDetector::SolidJunction(const Solid& s) const {
  Junction j;
  j.px = s.centre;
  j.solid = true;
  // The yarns leaving it: ridge peaks on a ring just outside its masked rim.
  double weakest = 0.0;
  j.branch_angles_rad =
      Peaks(SampleRing(s.centre, s.radius + 2 * std::ceil(2 * o_.ridge_sigma_px) + 2), &weakest);
  j.branches = static_cast<int>(j.branch_angles_rad.size());
  j.contrast = weakest;
  j.fit_rms_px = s.rms_px;
  j.confidence = std::exp(-0.5 * (s.rms_px / 0.5) * (s.rms_px / 0.5));
  j.solid_cut = !(s.rms_px <= o_.solid_round_px);
  return j;
}

std::vector<Junction> KnotDetector::SolidsFor(const std::vector<Junction>& junctions) const {
  std::vector<Junction> out;
  std::vector<const Solid*> taken;
  for (const Junction& j : junctions) {
    const Solid* on = nullptr;
    for (const Solid& s : solids_)
      if (s.rms_px <= o_.solid_round_px && (s.centre - j.px).norm() <= s.radius) on = &s;
    if (!on) {
      out.push_back(j);
    } else if (std::find(taken.begin(), taken.end(), on) == taken.end()) {
      taken.push_back(on);
      out.push_back(SolidJunction(*on));
    }
  }
  return out;
}

cv::Rect FindNodeRegion(const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options) {
  const int margin = static_cast<int>(std::ceil(DetectorReach(options)));
  return cv::Rect(static_cast<int>(std::floor(centre.x() - radius)) - margin,
                  static_cast<int>(std::floor(centre.y() - radius)) - margin,
                  static_cast<int>(2 * radius) + 2 * margin + 2,
                  static_cast<int>(2 * radius) + 2 * margin + 2);
}

std::optional<Junction> FitAlongLinks(const cv::Mat& image, const Eigen::Vector2d& px,
                                      const std::vector<Eigen::Vector2d>& links, double gap_px,
                                      const KnotDetectorOptions& options) {
  if (!(gap_px > 0.0) || links.size() < 2) return std::nullopt;
  std::vector<double> angles;
  double closest = M_PI;
  for (const Eigen::Vector2d& d : links) {
    const double a = std::atan2(d.y(), d.x());
    for (const double b : angles) closest = std::min(closest, AngleBetween(a, b));
    angles.push_back(a);
  }
  if (closest < 5.0 * M_PI / 180.0) return std::nullopt;
  // Nearer the knot two yarns that close are one ridge, and each strip would take the other's
  // pixels. The strips may reach past a short link's neighbour: a link seen edge-on in a fold
  // leaves one strip without a fit, and three lines of four place the knot (on Net B at
  // 0.8 m/s, frames 140-179, keeping the strips within 3/4 of the shortest link cut the actions
  // this saves from 564 to 67, with no wrong label either way).
  const double from = std::max(options.fit_from_px, gap_px / (2.0 * std::sin(0.5 * closest)));
  // The detector's ROI: the strips' far ends, across, and the fit's moves (up to half a ring
  // radius).
  const double reach = from + options.near_fit_to_px + options.fit_half_width_px +
                       0.5 * options.ring_radius_px + 2.0;
  const cv::Rect roi(static_cast<int>(px.x() - reach), static_cast<int>(px.y() - reach),
                     static_cast<int>(2 * reach) + 1, static_cast<int>(2 * reach) + 1);
  return KnotDetector(image, roi, options).FitAlong(px, angles, from);
}

FindNodeResult FindNode(const cv::Mat& image, const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options, bool corner_mass) {
  return FindNode(KnotDetector(image, FindNodeRegion(centre, radius, options), options), centre,
                  radius, corner_mass);
}

FindNodeResult FindNode(const KnotDetector& detector, const Eigen::Vector2d& centre, double radius,
                        bool corner_mass) {
  FindNodeResult result;
  result.candidates = detector.FindInCircle(centre, radius);
  if (corner_mass) result.candidates = detector.SolidsFor(result.candidates);
  if (result.candidates.empty()) result.candidates = detector.SolidsInCircle(centre, radius);
  if (result.candidates.empty()) {
    result.status = FindNodeStatus::kNone;
    result.why = "no junction of 2-4 yarns and no solid inside the brush";
  } else if (result.candidates.size() > 1) {
    result.status = FindNodeStatus::kSeveral;
    result.why = std::to_string(result.candidates.size()) +
                 (result.candidates[0].solid ? " solids" : " junctions") + " inside the brush";
  } else {
    result.status = FindNodeStatus::kFound;
    result.knot = result.candidates[0];
  }
  return result;
}

namespace {

// The cheapest path from a to b on the detector's ridges (image px, pixel by pixel; the ROI
// `box` of the detector within the image): Dijkstra, 8-connected, step cost length / (ridge +
// small): the yarn is the cheap way. The ridge counts up to a few times the branch threshold:
// beyond, a yarn is a yarn, and the shortest one is the row (through 1 / ridge itself a path took
// a bright neighbouring column and two links across rather than its own dim column). nullopt
// when b cannot be reached.
std::optional<std::vector<Eigen::Vector2d>> FollowYarn(const KnotDetector& detector,
                                                       const cv::Rect& box,
                                                       const Eigen::Vector2d& px_a,
                                                       const Eigen::Vector2d& px_b) {
  const cv::Mat& ridge = detector.ridge();
  const float eps = static_cast<float>(0.05 * detector.peak_threshold());
  const float enough = static_cast<float>(3.0 * detector.peak_threshold());
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
        const float nd = d + step / (std::min(ridge.at<float>(y + dy, x + dx), enough) + eps);
        if (nd < dist[j]) {
          dist[j] = nd;
          prev[j] = i;
          queue.push({nd, j});
        }
      }
  }
  if (prev[to] < 0 && to != from) return std::nullopt;
  std::vector<Eigen::Vector2d> path;
  for (int i = to; i >= 0; i = prev[i]) path.emplace_back(box.x + i % w, box.y + i / w);
  std::reverse(path.begin(), path.end());
  return path;
}

// A junction on the followed yarn, at arc length `arc` (px) from a.
struct PathJunction {
  double arc;
  Junction j;
};

// The junctions along the path, away from the two end knots, in order of arc length; *length:
// the path's arc length (px).
std::vector<PathJunction> JunctionsAlong(const KnotDetector& detector,
                                         const std::vector<Eigen::Vector2d>& path,
                                         const Eigen::Vector2d& px_a, const Eigen::Vector2d& px_b,
                                         const KnotDetectorOptions& options, double* length) {
  std::vector<PathJunction> found;
  double arc = 0.0;
  for (size_t i = 0; i < path.size(); ++i) {
    if (i > 0) arc += (path[i] - path[i - 1]).norm();
    const Eigen::Vector2d& p = path[i];
    if ((p - px_a).norm() < 1.5 * options.ring_radius_px ||
        (p - px_b).norm() < 1.5 * options.ring_radius_px)
      continue;
    bool near = false;
    for (const PathJunction& f : found) near = near || (f.j.px - p).norm() < options.ring_radius_px;
    if (near) continue;
    const std::optional<Junction> j = detector.Examine(p);
    if (!j || (j->px - px_a).norm() < options.ring_radius_px ||
        (j->px - px_b).norm() < options.ring_radius_px)
      continue;
    bool merged = false;
    for (const PathJunction& f : found)
      merged = merged || (f.j.px - j->px).norm() < options.merge_px;
    if (!merged) found.push_back({arc, *j});
  }
  std::sort(found.begin(), found.end(),
            [](const PathJunction& x, const PathJunction& y) { return x.arc < y.arc; });
  *length = arc;
  return found;
}

// Why the `between` junctions along a yarn of arc length `total` are unevenly spaced (a gap
// under half or over 1.6 times the mean); empty when they are not. The links between are of one
// length: along the yarn the junctions are spread about evenly (perspective and sag change that
// slowly). A gap far from the mean means a junction missed and a spurious one taken instead (the
// edge of a corner mass looks like one), which a count alone does not see.
std::string UnevenSpacing(const std::vector<PathJunction>& found, int between, double total) {
  if (between <= 0) return "";
  const double mean = total / (between + 1);
  double previous = 0.0;
  for (int i = 0; i <= between; ++i) {
    const double next = i < between ? found[i].arc : total;
    const double gap = next - previous;
    if (gap < 0.5 * mean || gap > 1.6 * mean)
      return "the junctions along the yarn are unevenly spaced (a gap of " +
             std::to_string(static_cast<int>(gap)) + " px where " +
             std::to_string(static_cast<int>(mean)) +
             " px is the mean): a knot missed or a false junction";
    previous = next;
  }
  return "";
}

// Why the path left the row (or column); empty when it did not. The row runs through each
// junction: it has a yarn towards the knot before it and one towards the knot after (within
// kRowTurnDeg of the straight line to it; sag bends a link by a few degrees). A path that left
// the row for a brighter parallel one and came back found that row's knots, evenly spaced: 2
// wrong labels in a rendered shot before this check.
std::string LeftTheRow(const std::vector<PathJunction>& found, int between,
                       const Eigen::Vector2d& px_a, const Eigen::Vector2d& px_b) {
  constexpr double kRowTurnDeg = 20.0;
  for (int i = 0; i < between; ++i) {
    const Junction& j = found[i].j;
    const Eigen::Vector2d before = i > 0 ? found[i - 1].j.px : px_a;
    const Eigen::Vector2d after = i + 1 < between ? found[i + 1].j.px : px_b;
    for (const Eigen::Vector2d& q : {before, after}) {
      const double towards = std::atan2(q.y() - j.px.y(), q.x() - j.px.x());
      double best = M_PI;
      for (double a : j.branch_angles_rad) best = std::min(best, AngleBetween(a, towards));
      if (best > kRowTurnDeg * M_PI / 180)
        return "junction " + std::to_string(i + 1) + " along the yarn has no yarn towards " +
               "the next knot of the row or column (" +
               std::to_string(static_cast<int>(best * 180 / M_PI)) +
               " degrees off): the path left the row";
    }
  }
  return "";
}

}  // namespace

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
  const int margin = static_cast<int>(std::ceil(0.15 * length + DetectorReach(options)));
  const cv::Rect roi(static_cast<int>(std::floor(std::min(px_a.x(), px_b.x()))) - margin,
                     static_cast<int>(std::floor(std::min(px_a.y(), px_b.y()))) - margin,
                     static_cast<int>(std::abs(px_b.x() - px_a.x())) + 2 * margin + 2,
                     static_cast<int>(std::abs(px_b.y() - px_a.y())) + 2 * margin + 2);
  const KnotDetector detector(image, roi, options);
  const cv::Rect box = roi & cv::Rect(0, 0, image.cols, image.rows);
  // The yarn from a to b.
  std::optional<std::vector<Eigen::Vector2d>> path = FollowYarn(detector, box, px_a, px_b);
  if (!path) {
    result.why = "no path between the two knots";
    return result;
  }
  result.path = std::move(*path);
  // Its junctions: as many as the knots between, evenly spaced, with the row running through.
  double arc = 0.0;
  const std::vector<PathJunction> found =
      JunctionsAlong(detector, result.path, px_a, px_b, options, &arc);
  if (static_cast<int>(found.size()) != between) {
    result.why = "found " + std::to_string(found.size()) + " junctions along the yarn, but " +
                 std::to_string(between) + " knots lie between";
    return result;
  }
  result.why = UnevenSpacing(found, between, arc);
  if (result.why.empty()) result.why = LeftTheRow(found, between, px_a, px_b);
  if (!result.why.empty()) return result;
  // The knots between, in order from a.
  const int dr = (rb > ra) - (rb < ra), dc = (cb > ca) - (cb < ca);
  for (int i = 0; i < between; ++i) {
    result.knots.push_back((ra + (i + 1) * dr) * cols + ca + (i + 1) * dc);
    result.junctions.push_back(found[i].j);
  }
  result.ok = true;
  return result;
}

}  // namespace netlab::recon
