#pragma once
// Knots in an image of thin coloured threads on a uniform background, and Find Node.
//
// Foreground: F = |I - background| (Euclidean over the colour channels; the background is a
// local median, background_window_px wide, so a target or cabin behind the net does not hide
// the yarns in front of it; solids are masked out, see solid_fraction). Ridges: the Hessian of F
// smoothed at the thread's scale; ridge strength R = max(0, -smallest eigenvalue) (bright lines
// in F, whatever their colour) and the ridge's direction. Where the background itself has an
// edge (the target's), a ridge along that edge is weakened: the median leaves a thin line of
// foreground there.
//
// A knot is where yarns meet: sampled on a circle around a point, the ridge strength along the
// radius (R cos^2 of the angle between ridge and radius: a yarn leaving the point counts fully,
// the rim of the knot's own bump not at all) peaks once per yarn leaving it. 3 or 4 peaks (edge,
// inner knot), or 2 peaks less than straight_angle_deg apart (a corner), make a junction; 2
// opposite peaks are a yarn passing by. Branches are followed on rings_count circles, all of
// which but one must agree. A peak must stand out from the background's noise, not from the
// strongest yarn: a knot's yarns differ up to 25-fold in contrast (dyes).
//
// Sub-pixel position: each branch is fitted with a model of a straight yarn (a blurred strip of
// constant colour) to the image's samples along it, fit_from_px to 2 ring_radius_px from the
// knot, and the knot is the least-squares intersection of the fitted lines (each weighted by its
// standard error; three or more lines, which must meet). When the image is a bilinearly
// demosaiced Bayer frame (detected: re-mosaiced and demosaiced it gives itself back), the
// samples are the mosaic's: each pixel's own colour only. A thin yarn of one dye is seen every
// second row and column in its red or blue channel, and any peak or centroid of the demosaiced
// image is pulled towards those rows by up to half a pixel (measured on a rendered shot: median
// 0.3-0.45 px off); the model, fitted where each sample was taken, is not (0.06-0.08 px).
//
// Slack links (the knotless Net B): a link may turn a few pixels from its junction, and a line
// fitted past the turn misses the junction. Each junction is fitted again on the yarns' first
// pixels (near_fit_*): where that settles elsewhere, or where the default strip fits no line,
// the near fit is the junction. A yarn that alone places the junction along the others (an edge
// knot's inner yarn: the other two are one straight yarn) is checked besides, since nothing else
// is: its strip's two halves must give the same line, and the default and near fits the same
// place; otherwise the junction is refused rather than placed along the edge (lone_bend_px,
// lone_agree_px). The near fit overrules the default only where it fitted every yarn and places
// the junction well (near_sigma_px), and no fit counts that has not settled (settle_px).
//
// Yarns beside yarns: where the net bunches, a fold seen edge-on or another part of the net
// behind runs within 2-3 px of a junction's yarn; the rings see one ridge and the fit takes one
// of the two. Such a junction is refused (beside_*).
//
// Solids: a compact blob several yarn widths across, a corner mass, is no yarn: its rim is
// masked from the ridges and its centre is a circle fitted to its sub-pixel outline. A corner
// knot sits inside its corner mass: Find Node returns the solid's centre (Junction::solid) when
// the brush holds no yarn junction.
//
// Find Node (the circular brush): every junction inside the brush, refined and merged; exactly
// one is returned as found, none or several (with the candidates) are said so — never a guess.

#include <Eigen/Core>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace netlab::recon {

struct KnotDetectorOptions {
  double ridge_sigma_px = 1.2;  // Gaussian scale of the Hessian (about the thread's half width)
  // Branches are counted on rings_count circles from ring_radius_px to twice that (all but one
  // must agree). The inner ring must clear the knot's own bump (a knot ball is three yarn
  // widths across, its rim a ridge too: at 6 px it gave false peaks as strong as dim yarns).
  double ring_radius_px = 9.0;
  int rings_count = 3;
  // A branch peak (of the ridge strength along the radius) exceeds the largest of:
  double noise_factor = 15.0;   // this many times the median ridge strength (the noise),
  double peak_fraction = 0.03;  // this fraction of the strong ridges (99th percentile),
  double min_peak = 1e-4;       // and this (ridge units: foreground (0..1) / px^2).
  double min_branch_separation_deg = 25.0;
  double straight_angle_deg = 150.0;  // two branches this far apart are one yarn passing through
  double merge_px = 2.5;              // refined junctions closer than this are one
  // Sub-pixel fit of each branch (false: the lines through the branch's ring peaks, biased by
  // demosaicing, see above).
  bool fit_yarns = true;
  double fit_from_px = 5.0;        // along each branch from here (clear of the knot's bump) to
                                   // 2 ring_radius_px
  double fit_half_width_px = 3.0;  // samples this far either side of the branch line, px
  // The check of each refined junction on the yarns' first pixels: its branches found again on
  // rings half as far out as near_fit_to_px and fitted from near_fit_from_px to near_fit_to_px
  // (0: off). Where that settles more than bend_px away, the yarns bend within the strip above
  // and the near fit is the junction.
  double near_fit_from_px = 3.0;
  double near_fit_to_px = 12.0;
  double bend_px = 1.5;
  // A yarn that alone fixes the junction's place along the others (an edge knot's inner yarn)
  // is fitted on each half of its strip too; where the two lines' offsets at the junction differ
  // by more than this (px), the yarn bends and the junction is refused (0: not checked); where
  // it bends within the near strip, the junction is refused whatever the default strip says.
  double lone_bend_px = 0.7;
  // A junction with such a yarn is refused where its near fit and its default fit disagree by
  // more than this, px (but not by more than bend_px: then the near fit is taken).
  double lone_agree_px = 0.7;
  // The near fit overrules the default only when it fitted every yarn and places the junction
  // to this (px, the largest standard deviation from its lines' offsets): a dim yarn of one dye
  // on its few pixels can take a wrong turn (docs/benchmarks.md, labeling).
  double near_sigma_px = 0.15;
  // A fit whose junction still moves this much (px) on its last pass has not settled: refused.
  double settle_px = 0.1;
  // A yarn with a second one beside it (parallel, from beside_gap_px to fit_half_width_px off
  // its line) is not a junction's: refused where the second lowers the yarn's residuals by more
  // than beside_significance times their variance with at least beside_fraction of its area
  // (0: not checked).
  double beside_gap_px = 1.5;
  double beside_significance = 8.0;
  double beside_fraction = 0.15;
  // Junction::colour_step of every edge junction (knotless nets; a knot ball moves the change).
  // Off, it costs nothing; on, a few per cent of Find Node's time (docs/benchmarks.md).
  bool colour_step = false;
  double yarn_blur_px = 0.5;        // Gaussian blur of the yarn's edges in the model (pixel
                                    // footprint, lens, motion), px
  int background_window_px = 11;    // median window of the local background (odd, >> a yarn)
  double solid_fraction = 0.3;      // foreground above this fraction of the brightest that stays
  double max_solid_area_px = 3000;  // under an opening, in a blob up to this area: a solid
                                    // (corner mass), where no ridge is taken
  // A solid whose outline's RMS distance from its fitted circle exceeds this is not round
  // (something covers or cuts it): Junction::solid_cut (px).
  double solid_round_px = 0.5;
  // Where the local background changes this fast (per px, 0..1 colour units), at an edge of a
  // target behind the net, ridges along the edge are weakened (fully at this rate) and the
  // yarn model takes no samples (from half of it); 0: off.
  double background_edge = 0.05;
};

struct Junction {
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // OpenCV pixel convention
  int branches = 0;
  std::vector<double> branch_angles_rad;  // image angles (atan2(dy, dx)) of the yarns leaving it
  double fit_rms_px = 0.0;                // RMS distance of px from the branch lines
  int fitted_branches = 0;  // branches whose yarn was fitted (a branch of four may be left out)
  double sigma_px = 0.0;    // the largest standard deviation of px from the lines' offsets
  double contrast = 0.0;    // weakest branch peak / the peak threshold (> 1)
  // An edge junction (three yarns, two of them one straight line): where on that line the
  // colour changes from one link's dye to the other's (KnotDetectorOptions::colour_step); NaN
  // where the two links' colours are too alike to tell, not an edge junction, or not asked.
  Eigen::Vector2d colour_step = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double confidence = 0.0;  // 0..1 from contrast and fit
  bool solid = false;       // the centre of a solid (corner mass), not a yarn junction;
                            // branches: the yarns leaving it, fit_rms_px: its outline's RMS
                            // distance from the fitted circle
  // A solid whose outline is cut, so that its centre is uncertain: its outline is not round
  // (RMS distance from its circle over KnotDetectorOptions::solid_round_px), as a corner mass
  // lying half over the target's face is.
  bool solid_cut = false;
};

class KnotDetector {
 public:
  // Works on `roi` of `image` (CV_8UC3, CV_16UC3 or CV_32FC3 BGR, or one channel); the whole
  // image when roi is empty.
  KnotDetector(const cv::Mat& image, cv::Rect roi = {}, KnotDetectorOptions options = {});

  // The junction at a point (branches counted there, position refined from it); nullopt when
  // the point is not at a junction.
  std::optional<Junction> Examine(const Eigen::Vector2d& px) const;
  // Every junction inside the circle, refined and merged.
  std::vector<Junction> FindInCircle(const Eigen::Vector2d& centre, double radius) const;
  // Every solid whose centre is inside the circle: its centre, the yarns leaving it as
  // branches (counted on a ring just outside it), solid = true.
  std::vector<Junction> SolidsInCircle(const Eigen::Vector2d& centre, double radius) const;
  // Each junction on a round solid (within its radius; not solid_cut) replaced by the solid's
  // centre, once per solid: such a junction is the yarns leaving the solid, their lines
  // extrapolated into it, and meets at its centre only where the yarns leave it straight.
  std::vector<Junction> SolidsFor(const std::vector<Junction>& junctions) const;

  // How many of the image angles (rad) a yarn leaves `px` along: a branch peak within
  // tolerance_rad of the angle on every ring but one (the rings of Examine). For a place known
  // otherwise (the other cameras'), where no junction is found: whether its yarns are there.
  // `seen`, when given: per angle, whether a yarn leaves along it.
  int YarnsAlong(const Eigen::Vector2d& px, const std::vector<double>& angles, double tolerance_rad,
                 std::vector<bool>* seen = nullptr) const;

  // The junction near `px` whose yarns leave along `angles` (image angles, rad: the knot's links,
  // known from its neighbours): each yarn fitted as Examine fits them, on a strip from `from_px`
  // to from_px + near_fit_to_px along it; all but one of four must fit, their lines meeting in
  // one point at 25 degrees or more. Its branches are the yarns fitted; nullopt when too few fit
  // or they do not meet. FitAlongLinks chooses the strip.
  std::optional<Junction> FitAlong(const Eigen::Vector2d& px, const std::vector<double>& angles,
                                   double from_px) const;

  // Whether an edge of the background (the target's outline: KnotDetectorOptions::
  // background_edge) passes within `radius` px of `px`: a knot there may be just behind it.
  bool NearBackgroundEdge(const Eigen::Vector2d& px, double radius) const;

  const cv::Mat& ridge() const { return ridge_; }  // CV_32F, the ROI
  double peak_threshold() const { return threshold_; }
  // The Bayer pattern (BayerPattern, bayer.h; at the ROI's top-left pixel) the image was
  // demosaiced from; kNone (0) when it was not a bilinearly demosaiced mosaic.
  int bayer_pattern() const { return pattern_; }

 private:
  struct Solid {
    Eigen::Vector2d centre;  // image px
    double radius = 0.0;     // px
    double rms_px = 0.0;     // of the outline about the fitted circle
  };
  // The ridge strength along the radius, R cos^2 of the angle between the ridge and the radius,
  // on a circle (bilinear samples from angle 0).
  std::vector<double> SampleRing(const Eigen::Vector2d& centre, double radius) const;
  // A solid as a junction: its centre, the yarns leaving it as branches (SolidsInCircle).
  Junction SolidJunction(const Solid& s) const;
  // Peak angles (rad, sub-sample) of a ring's profile above the threshold; the weakest peak
  // over the threshold in *weakest.
  std::vector<double> Peaks(const std::vector<double>& profile, double* weakest) const;
  // The junction at a point from the rings alone: position from the lines through the branch
  // peaks.
  std::optional<Junction> ExamineRings(const Eigen::Vector2d& px) const;
  std::optional<Junction> ExamineRings(const Eigen::Vector2d& px, double ring_radius_px) const;
  // A junction's position refined by fitting the yarn model to each branch; nullopt when too
  // few branches fit, or the fitted lines do not meet in one point near the rings' junction.
  std::optional<Junction> Refine(const Junction& j) const;
  // Refine over the strip `from` to `to` px along each branch; *lone_bends (when given) is set
  // when the junction was refused because a yarn that alone places it bends (lone_bend_px).
  std::optional<Junction> RefineOver(const Junction& j, double from, double to,
                                     bool* lone_bends = nullptr) const;
  // ColourStep: the colour step along a straight pair of fitted yarns `a`, `b` (lines: a point
  // and the direction away from the junction `px`; fits: their colours), with the lone yarn `l`
  // ending at px; NaN where a's and b's colours are too alike.
  using Line = std::pair<Eigen::Vector2d, Eigen::Vector2d>;
  double ColourStep(const Eigen::Vector2d& px, const Line& a, const Line& b, const Line& l,
                    const Eigen::VectorXd& pa, const Eigen::VectorXd& pb,
                    const Eigen::VectorXd& pl) const;
  // The solids among the blobs (CV_8U), their centres from the outline in `level` (CV_32F, the
  // distance of each pixel's colour from the region's median colour); sets masked_ and solids_.
  void FindSolids(const cv::Mat& blobs, const cv::Mat& level);
  // The constructor's steps. The solids of the region `f` (CV_32FC(n), 0..1) found and masked
  // (FindSolids).
  void MaskSolids(const cv::Mat& f);
  // ridge_ and field_ from the foreground `fg` (CV_32F), each ridge weakened along the
  // background's edges (edge_c2, edge_s2: the gradient's doubled-angle direction times its
  // weight, CV_32F; empty: none).
  void ComputeRidges(const cv::Mat& fg, const cv::Mat& edge_c2, const cv::Mat& edge_s2);
  // The threshold a branch peak must exceed, from the ridges outside solids.
  double PeakThreshold() const;

  KnotDetectorOptions o_;
  cv::Rect roi_;
  cv::Mat ridge_;
  cv::Mat field_;   // CV_32FC3: R, R cos 2 theta, R sin 2 theta (theta: the ridge's direction)
  cv::Mat diff_;    // CV_32FC(n): the image minus its local background, 0..1
  cv::Mat masked_;  // CV_8U: 255 on (dilated) solids, 128 on the background's edges, else 0
  std::vector<Solid> solids_;
  int pattern_ = 0;  // BayerPattern
  double threshold_ = 0.0;
};

// Whether a junction lies where the colour of its straight pair changes, within max_px of it:
// true where that is not checked (max_px <= 0) or cannot be told (no Junction::colour_step).
bool ColourChangesAt(const Junction& j, double max_px);

// The knot near `px` where the rings find none because its crossing is too acute for them: in
// a fold the mesh is seen sheared (links 25-40 degrees apart in the image) with another layer's
// yarns beside, and the inner ring sees two yarns as one while the outer ones cross the other
// layer. Its yarns fitted along `links` (image vectors from the knot to its neighbours, as they
// last lay; KnotDetector::FitAlong on a detector built over the strips' reach), from where the
// closest two are `gap_px` apart: nullopt where two links are within 5 degrees of each other
// (the strips would start 57 px out, past most neighbours) or the yarns do not fit there.
std::optional<Junction> FitAlongLinks(const cv::Mat& image, const Eigen::Vector2d& px,
                                      const std::vector<Eigen::Vector2d>& links, double gap_px,
                                      const KnotDetectorOptions& options);

// How far from a point the detector reads (px): its outer ring and the ridge filter's support.
// A KnotDetector's ROI needs this margin around the points it examines.
double DetectorReach(const KnotDetectorOptions& options);

enum class FindNodeStatus { kFound, kNone, kSeveral };

struct FindNodeResult {
  FindNodeStatus status = FindNodeStatus::kNone;
  Junction knot;                     // when found
  std::vector<Junction> candidates;  // when several (and the one found)
  std::string why;                   // when not found
  // Found by the other cameras, not in this image (LabelEngine::FindNodeAt): `knot` is where
  // their labels put the knot (no junction: branches 0).
  bool projected = false;
};

// The knot inside the brush (centre, radius in px) of `image`: the one yarn junction there, or
// when there is none, the one solid (corner mass) whose centre is there (Junction::solid). For
// a corner knot (`corner_mass`), a junction on a round solid is that solid's centre
// (KnotDetector::SolidsFor); elsewhere a small solid may be a knot ball, its yarns' junction
// the better place. About 2 ms for a 6 px brush (a 68 x 68 px region; 4.7 ms at most on a
// rendered shot).
FindNodeResult FindNode(const cv::Mat& image, const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options = {}, bool corner_mass = false);
// The same with a detector built by the caller (FindNodeRegion: its ROI around the brush).
FindNodeResult FindNode(const KnotDetector& detector, const Eigen::Vector2d& centre, double radius,
                        bool corner_mass = false);
cv::Rect FindNodeRegion(const Eigen::Vector2d& centre, double radius,
                        const KnotDetectorOptions& options);

// Find Path: the knots strictly between two labeled knots of one row or column, found by
// following the yarn (the cheapest path on 1 / ridge strength from one knot to the other) and
// taking the junctions on it in order. Refused (ok false, with the reason) when the knots are not
// in one row or column, when the number of junctions found differs from the knots between, or
// when they are unevenly spaced along the yarn (a gap under half or over 1.6 times the mean: a
// knot missed and a false junction taken instead).
struct FindPathResult {
  bool ok = false;
  std::string why;
  std::vector<int> knots;             // row * cols + col of each knot between, from a towards b
  std::vector<Junction> junctions;    // their junctions, in the same order
  std::vector<Eigen::Vector2d> path;  // the followed yarn, pixel by pixel
};

FindPathResult FindPath(const cv::Mat& image, int cols, int knot_a, const Eigen::Vector2d& px_a,
                        int knot_b, const Eigen::Vector2d& px_b,
                        const KnotDetectorOptions& options = {});

}  // namespace netlab::recon
