#include "libreconstruct/labeling/label_identity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/recording/bayer.h"
#include "libreconstruct/twin/render.h"
#include "libreconstruct/twin/synthetic_experiment.h"
#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {

// Verdicts by name in test failures.
void PrintTo(IdentityVerdict verdict, std::ostream* os) { *os << IdentityVerdictName(verdict); }

namespace {

using testing::ScratchDir;

constexpr int kDr[4] = {0, 1, 0, -1}, kDc[4] = {1, 0, -1, 0};  // right, down, left, up

// ---------------------------------------------------------------------------------------------
// The codebook.

TEST(CodebookFromColoring, PaletteIsTheDyesAsRenderedAndKnotsAreRowMajorInGeometricOrder) {
  ColoringOptions options;
  options.rule = CodeRule::kMultiset;
  options.time_limit_s = 5;
  NetColoring coloring = SolveColoring(3, 4, options);
  ASSERT_GT(coloring.colors, 1);
  coloring.palette_names.clear();
  // The first dye has an sRGB, the others take the renderer's fallback.
  const std::vector<std::array<int, 3>> srgb = {{240, 120, 20}};
  Lighting lighting;
  lighting.exposure = 0.85;
  const KnotCodebook book = CodebookFromColoring(coloring, srgb, lighting);
  EXPECT_EQ(book.rule, CodeRule::kMultiset);
  ASSERT_EQ(static_cast<int>(book.palette.size()), coloring.colors);
  const Colour dye = 0.85f * SrgbToLinearBgr({240, 120, 20});
  EXPECT_LT(cv::norm(book.palette[0].linear_bgr - dye), 1e-6);
  EXPECT_EQ(book.palette[0].name, "colour 0");
  const YarnColoring fallback = DefaultColoring(2, 2);
  EXPECT_LT(cv::norm(book.palette[1].linear_bgr - 0.85f * fallback.palette[1]), 1e-6);
  ASSERT_EQ(book.knots.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    EXPECT_EQ(book.knots[k].row, k / 4);
    EXPECT_EQ(book.knots[k].col, k % 4);
    EXPECT_EQ(book.knots[k].link_colours, KnotLinkColours(coloring, k / 4, k % 4));
  }
  lighting.exposure = -1;
  EXPECT_THROW(CodebookFromColoring(coloring, srgb, lighting), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// A coloured net rendered the way `netlab render --coloring` draws it, with truth.

constexpr int kSide = 5;

struct RenderedColouring {
  KnotCodebook codebook;
  std::vector<Eigen::Vector2d> pixels;  // true pixel of knot k = row * kSide + col
  cv::Mat frame;                        // demosaiced, 8-bit linear BGR

  std::optional<Eigen::Vector2d> At(int r, int c) const {
    if (r < 0 || c < 0 || r >= kSide || c >= kSide) return std::nullopt;
    return pixels[r * kSide + c];
  }
  bool Has(int r, int c) const { return r >= 0 && c >= 0 && r < kSide && c < kSide; }
  // The labeled neighbours of a label on knot (r, c) when that label names knot (kr, kc): the
  // knots around (r, c), in the slots that (kr, kc) has.
  YarnDirections Neighbours(int r, int c, int kr, int kc) const {
    YarnDirections y;
    for (int s = 0; s < 4; ++s)
      if (Has(kr + kDr[s], kc + kDc[s])) y.neighbour_px[s] = At(r + kDr[s], c + kDc[s]);
    return y;
  }
  // The detector's view of knot (r, c): the angles of all its yarns (in an order of its own),
  // with the neighbours above for the links' length.
  YarnDirections Branches(int r, int c, int kr, int kc) const {
    YarnDirections y = Neighbours(r, c, kr, kc);
    const Eigen::Vector2d p = pixels[r * kSide + c];
    for (int s = 3; s >= 0; --s)
      if (const auto q = At(r + kDr[s], c + kDc[s]))
        y.branch_angles_rad.push_back(std::atan2(q->y() - p.y(), q->x() - p.x()));
    return y;
  }
};

// kSide^2 knots 0.2 m apart, 1.5 m in front of the paper's 16 mm camera at half resolution (links
// ~190 px), the net turned by `roll_deg` in the image and tilted 25 degrees away; 1 mm yarns
// dyed by a set-rule colouring written to coloring.yaml and read back as `netlab render` does;
// RGGB mosaic with 2 grey levels of noise, demosaiced.
RenderedColouring RenderColouring(double roll_deg, const ScratchDir& dir) {
  ColoringOptions options;
  options.time_limit_s = 5;
  NetColoring coloring = SolveColoring(kSide, kSide, options);
  EXPECT_GT(coloring.colors, 1);
  const std::vector<Candidate> candidates = DefaultYarnCandidates();
  Lighting choose;
  choose.background = Colour(0, 0, 0);
  std::vector<std::array<int, 3>> srgb;
  for (int i : ChoosePalette(candidates, coloring.colors, choose, nullptr)) {
    coloring.palette_names.push_back(candidates[i].name);
    const auto& s = candidates[i].srgb;
    srgb.push_back({int(std::lround(s[0])), int(std::lround(s[1])), int(std::lround(s[2]))});
  }
  const std::string path = dir / "coloring.yaml";
  WriteColoring(path, coloring, srgb);
  const YarnColoring yarns = LoadYarnColoring(path);  // what the renderer draws
  std::vector<std::array<int, 3>> srgb_read;
  const NetColoring read = ReadColoring(path, &srgb_read);
  const double illumination = RenderJob{}.illumination;
  Lighting lighting;
  lighting.exposure = illumination;

  RenderedColouring out;
  out.codebook = CodebookFromColoring(read, srgb_read, lighting);
  const calib::Camera camera = calib::PaperRig(0.5).cameras[0];
  const Eigen::Vector3d axis = camera.ViewDirection();
  const Eigen::Vector3d centre = camera.Center() + 1.5 * axis;
  const Eigen::Vector3d image_x =
      camera.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d image_y =
      camera.cam_from_world.rotation.conjugate() * Eigen::Vector3d::UnitY();
  const double roll = roll_deg * M_PI / 180, tilt = 25.0 * M_PI / 180;
  const Eigen::Vector3d right = std::cos(roll) * image_x + std::sin(roll) * image_y;
  const Eigen::Vector3d down =
      std::cos(tilt) * (-std::sin(roll) * image_x + std::cos(roll) * image_y) +
      std::sin(tilt) * axis;
  std::vector<Eigen::Vector3d> knots;
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c) {
      knots.push_back(centre + (c - 0.5 * (kSide - 1)) * 0.2 * right +
                      (r - 0.5 * (kSide - 1)) * 0.2 * down);
      out.pixels.push_back(camera.ProjectWorld(knots.back()));
    }
  Scene scene;
  for (int link = 0; link < NumLinks(kSide, kSide); ++link) {
    const auto k = LinkKnots(kSide, kSide, link);
    ThreadPolyline thread;
    thread.points = {knots[k[0] * kSide + k[1]], knots[k[2] * kSide + k[3]]};
    thread.radius = 0.0005;
    thread.colour = yarns.palette[yarns.link_colour[link]] * static_cast<float>(illumination);
    scene.threads.push_back(thread);
  }
  SensorOptions sensor;
  sensor.noise_sigma = 2.0;
  sensor.seed = 5;
  out.frame =
      Demosaic(Expose(RenderScene(camera, scene, SceneRenderOptions{}), camera.intrinsics, sensor),
               BayerPattern::kRGGB, ColorCorrection{});
  return out;
}

struct Count {
  int consistent = 0, mismatch = 0, unreadable = 0;
  void Add(IdentityVerdict v) {
    (v == IdentityVerdict::kConsistent ? consistent
     : v == IdentityVerdict::kMismatch ? mismatch
                                       : unreadable)++;
  }
  int total() const { return consistent + mismatch + unreadable; }
};

TEST(CheckIdentity, TrueLabelsAreNeverMismatchedOnARenderedNet) {
  const ScratchDir dir("label_identity");
  // 20 degrees: every yarn off the mosaic's axes. 0 degrees: the image's horizontal yarns run
  // along the pixel rows, where the colour is not read.
  for (double roll : {20.0, 0.0}) {
    const RenderedColouring net = RenderColouring(roll, dir);
    Count by_neighbours, by_branches;
    for (int k = 0; k < kSide * kSide; ++k) {
      const int r = k / kSide, c = k % kSide;
      const IdentityCheck a =
          CheckIdentity(net.frame, net.codebook, k, net.pixels[k], net.Neighbours(r, c, r, c));
      const IdentityCheck b =
          CheckIdentity(net.frame, net.codebook, k, net.pixels[k], net.Branches(r, c, r, c));
      by_neighbours.Add(a.verdict);
      by_branches.Add(b.verdict);
      EXPECT_NE(a.verdict, IdentityVerdict::kMismatch) << "roll " << roll << ": " << a.why;
      EXPECT_NE(b.verdict, IdentityVerdict::kMismatch) << "roll " << roll << ": " << b.why;
      // What the colours say includes the true knot when they say anything.
      if (!b.knots_read.empty()) {
        EXPECT_NE(std::find(b.knots_read.begin(), b.knots_read.end(), k), b.knots_read.end());
      }
    }
    std::printf(
        "roll %.0f deg, true labels: neighbours %d consistent %d unreadable; branches %d / %d\n",
        roll, by_neighbours.consistent, by_neighbours.unreadable, by_branches.consistent,
        by_branches.unreadable);
    if (roll > 10) {
      EXPECT_GE(by_neighbours.consistent, 22);  // of 25
      EXPECT_GE(by_branches.consistent, 22);
    } else {
      EXPECT_GE(by_neighbours.unreadable, 8);  // the near-axis yarns are left unread (13 of 25)
    }
  }
}

TEST(CheckIdentity, LabelsShiftedOntoANeighbourAreMismatched) {
  const ScratchDir dir("label_identity");
  const RenderedColouring net = RenderColouring(20.0, dir);
  Count by_neighbours, by_branches;
  for (int k = 0; k < kSide * kSide; ++k) {
    const int r = k / kSide, c = k % kSide;
    for (int s = 0; s < 4; ++s) {
      const int jr = r + kDr[s], jc = c + kDc[s];
      if (!net.Has(jr, jc)) continue;
      const int j = jr * kSide + jc;
      // Knot k's label on its neighbour j, the labels around shifted alike (a row labeled one
      // knot off): the yarns towards them are j's yarns, taken for k's links.
      const IdentityCheck a =
          CheckIdentity(net.frame, net.codebook, k, net.pixels[j], net.Neighbours(jr, jc, r, c));
      // The detector at j sees j's yarns.
      const IdentityCheck b =
          CheckIdentity(net.frame, net.codebook, k, net.pixels[j], net.Branches(jr, jc, r, c));
      by_neighbours.Add(a.verdict);
      by_branches.Add(b.verdict);
      const std::string where = "knot " + std::to_string(k) + " on " + std::to_string(j) + ": ";
      // Every yarn looked at read with certainty and one of them differs from k's link there:
      // never consistent.
      bool differs = false;
      for (int t = 0, link_k = 0, link_j = 0; t < 4; ++t) {
        const bool k_has = net.Has(r + kDr[t], c + kDc[t]),
                   j_has = net.Has(jr + kDr[t], jc + kDc[t]);
        if (k_has && j_has &&
            net.codebook.knots[k].link_colours[link_k] !=
                net.codebook.knots[j].link_colours[link_j])
          differs = true;
        link_k += k_has;
        link_j += j_has;
      }
      if (differs && a.yarns_certain == a.yarns) {
        EXPECT_EQ(a.verdict, IdentityVerdict::kMismatch) << where << a.why;
      }
      // All of j's yarns read with certainty, as many as k has links: the colours are j's code,
      // which is not k's (the colouring makes every code unique).
      if (b.yarns == net.codebook.knots[k].degree() && b.yarns_certain == b.yarns) {
        EXPECT_EQ(b.verdict, IdentityVerdict::kMismatch) << where << b.why;
      }
    }
  }
  std::printf(
      "shifted labels: neighbours %d mismatch %d consistent %d unreadable of %d; "
      "branches %d / %d / %d\n",
      by_neighbours.mismatch, by_neighbours.consistent, by_neighbours.unreadable,
      by_neighbours.total(), by_branches.mismatch, by_branches.consistent, by_branches.unreadable);
  EXPECT_EQ(by_neighbours.total(), 80);   // 2 * 2 * 5 * 4 neighbour pairs
  EXPECT_GE(by_neighbours.mismatch, 72);  // >= 90 %
  EXPECT_GE(by_branches.mismatch, 64);    // >= 80 %
}

// ---------------------------------------------------------------------------------------------
// Drawn knots (full-colour sensor): the mapping of yarns to links.

const std::vector<std::array<int, 3>> kSrgb = {
    {230, 30, 30}, {30, 200, 40}, {40, 60, 230}, {240, 220, 30}, {240, 240, 240}};
const std::vector<std::string> kNames = {"red", "green", "blue", "yellow", "white"};

// A 3 x 3 net whose centre knot (1, 1) has links right, down, left, up of `centre` colours (the
// other links colour 3).
NetColoring ThreeByThree(CodeRule rule, const std::array<int, 4>& centre) {
  NetColoring c;
  c.rows = c.cols = 3;
  c.colors = 5;
  c.options.rule = rule;
  c.palette_names = kNames;
  c.link_colour.assign(NumLinks(3, 3), 3);
  const std::vector<int> links = KnotLinks(3, 3, 1, 1);
  for (int s = 0; s < 4; ++s) c.link_colour[links[s]] = centre[s];
  return c;
}

KnotCodebook Book(const NetColoring& coloring) {
  return CodebookFromColoring(coloring, kSrgb, Lighting{});
}

// The centre knot at (100, 100) of a 200 x 200 frame, its yarns (2 px, anti-aliased) at 20, 110,
// 200 and 290 degrees in the colours `yarn` (palette indices; -1: no yarn); an optional grey disc
// (a corner mass) over the knot. The neighbours, 80 px out along the yarns, in slots right, down,
// left, up.
struct DrawnKnot {
  cv::Mat image;
  Eigen::Vector2d knot{100, 100};
  std::array<Eigen::Vector2d, 4> neighbours;
  std::vector<double> angles;
};
DrawnKnot Draw(const std::array<int, 4>& yarn, double disc_radius_px = 0) {
  DrawnKnot d;
  d.image = cv::Mat(200, 200, CV_8UC3, cv::Scalar(5, 5, 5));
  for (int s = 0; s < 4; ++s) {
    const double a = (20.0 + 90.0 * s) * M_PI / 180;
    d.neighbours[s] = d.knot + 80 * Eigen::Vector2d(std::cos(a), std::sin(a));
    if (yarn[s] < 0) continue;
    d.angles.push_back(std::remainder(a, 2 * M_PI));
    const Colour c = SrgbToLinearBgr({double(kSrgb[yarn[s]][0]), double(kSrgb[yarn[s]][1]),
                                      double(kSrgb[yarn[s]][2])}) *
                     255.0f;
    cv::line(
        d.image, cv::Point(100, 100),
        cv::Point(int(std::lround(d.neighbours[s].x())), int(std::lround(d.neighbours[s].y()))),
        cv::Scalar(c[0], c[1], c[2]), 2, cv::LINE_AA);
  }
  if (disc_radius_px > 0)
    cv::circle(d.image, cv::Point(100, 100), int(disc_radius_px), cv::Scalar(150, 150, 150),
               cv::FILLED, cv::LINE_AA);
  return d;
}

IdentityCheckOptions FullColour() {
  IdentityCheckOptions o;
  o.identify.bayer = BayerPattern::kNone;
  return o;
}

YarnDirections ByNeighbours(const DrawnKnot& d) {
  YarnDirections y;
  for (int s = 0; s < 4; ++s) y.neighbour_px[s] = d.neighbours[s];
  return y;
}
YarnDirections ByBranches(const DrawnKnot& d, int rotate_by) {
  YarnDirections y = ByNeighbours(d);
  y.branch_angles_rad = d.angles;
  std::rotate(y.branch_angles_rad.begin(), y.branch_angles_rad.begin() + rotate_by,
              y.branch_angles_rad.end());
  return y;
}

constexpr int kCentre = 4;

TEST(CheckIdentity, NeighbourDirectionsCompareEachYarnWithItsOwnLink) {
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kCyclic, {0, 1, 0, 2}));
  const DrawnKnot right = Draw({0, 1, 0, 2});
  const IdentityCheck ok =
      CheckIdentity(right.image, book, kCentre, right.knot, ByNeighbours(right), FullColour());
  EXPECT_EQ(ok.verdict, IdentityVerdict::kConsistent) << ok.why;
  EXPECT_EQ(ok.yarns_certain, 4);
  EXPECT_EQ(ok.knots_read, std::vector<int>{kCentre});
  // Rotated by one link: the same cyclic code, but the yarn towards the right neighbour is not
  // the right link's colour.
  const DrawnKnot rotated = Draw({2, 0, 1, 0});
  const IdentityCheck turned = CheckIdentity(rotated.image, book, kCentre, rotated.knot,
                                             ByNeighbours(rotated), FullColour());
  EXPECT_EQ(turned.verdict, IdentityVerdict::kMismatch) << turned.why;
  EXPECT_EQ(turned.yarns_contradicting, 4);
  EXPECT_NE(turned.why.find("right yarn is blue, (1, 1)'s right link is red"), std::string::npos)
      << turned.why;
}

TEST(CheckIdentity, BranchAnglesInAnyOrderFollowTheRule) {
  // Centre red, green, red, blue. Drawn: rotated (the cyclic code), and with the two reds
  // adjacent (the multiset, another cyclic code).
  const std::array<int, 4> centre{0, 1, 0, 2};
  const DrawnKnot rotated = Draw({2, 0, 1, 0});
  const DrawnKnot reordered = Draw({0, 0, 1, 2});
  for (int rotate_by = 0; rotate_by < 4; ++rotate_by) {
    const KnotCodebook cyclic = Book(ThreeByThree(CodeRule::kCyclic, centre));
    EXPECT_EQ(CheckIdentity(rotated.image, cyclic, kCentre, rotated.knot,
                            ByBranches(rotated, rotate_by), FullColour())
                  .verdict,
              IdentityVerdict::kConsistent);
    const IdentityCheck wrong_order =
        CheckIdentity(reordered.image, cyclic, kCentre, reordered.knot,
                      ByBranches(reordered, rotate_by), FullColour());
    EXPECT_EQ(wrong_order.verdict, IdentityVerdict::kMismatch) << wrong_order.why;
    EXPECT_NE(wrong_order.why.find("not the cyclic code"), std::string::npos) << wrong_order.why;
    for (CodeRule rule : {CodeRule::kSet, CodeRule::kMultiset}) {
      const KnotCodebook book = Book(ThreeByThree(rule, centre));
      EXPECT_EQ(CheckIdentity(reordered.image, book, kCentre, reordered.knot,
                              ByBranches(reordered, rotate_by), FullColour())
                    .verdict,
                IdentityVerdict::kConsistent);
    }
  }
  // Under the set rule too the branches are distinct links: red, red, green, green is not
  // red, green, red, blue although the set {red, green} is inside {red, green, blue}.
  const DrawnKnot two_greens = Draw({0, 1, 0, 1});
  const IdentityCheck counted =
      CheckIdentity(two_greens.image, Book(ThreeByThree(CodeRule::kSet, centre)), kCentre,
                    two_greens.knot, ByBranches(two_greens, 1), FullColour());
  EXPECT_EQ(counted.verdict, IdentityVerdict::kMismatch) << counted.why;
}

TEST(CheckIdentity, AForeignColourIsAMismatchAndAMissedBranchIsNot) {
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kSet, {0, 1, 0, 2}));
  // The up yarn white: no link of the knot is white.
  const DrawnKnot foreign = Draw({0, 1, 0, 4});
  for (const YarnDirections& y : {ByNeighbours(foreign), ByBranches(foreign, 2)}) {
    const IdentityCheck c =
        CheckIdentity(foreign.image, book, kCentre, foreign.knot, y, FullColour());
    EXPECT_EQ(c.verdict, IdentityVerdict::kMismatch) << c.why;
    EXPECT_EQ(c.yarns_contradicting, 1);
  }
  // The detector missed the up branch: three yarns, distinct links of the knot.
  const DrawnKnot missed = Draw({0, 1, 0, -1});
  const IdentityCheck three =
      CheckIdentity(missed.image, book, kCentre, missed.knot, ByBranches(missed, 0), FullColour());
  EXPECT_EQ(three.verdict, IdentityVerdict::kConsistent) << three.why;
  EXPECT_TRUE(three.knots_read.empty());  // fewer yarns than links: no identity
  // Three yarns all red cannot be three distinct links of red, green, red, blue.
  const DrawnKnot reds = Draw({0, 0, 0, -1});
  EXPECT_EQ(CheckIdentity(reds.image, book, kCentre, reds.knot, ByBranches(reds, 0), FullColour())
                .verdict,
            IdentityVerdict::kMismatch);
  // Four branches at the three-link knot (0, 1), one of them spurious: its links must be among
  // them. Knot (0, 1) is yellow, blue, yellow: not among red, green, red, white.
  const YarnDirections four{foreign.angles, {}};
  const IdentityCheck extra =
      CheckIdentity(foreign.image, book, 1, foreign.knot, four, FullColour());
  EXPECT_EQ(extra.verdict, IdentityVerdict::kMismatch) << extra.why;
  // Knot (0, 1) red, blue, green (its down link is the centre's up link): among red, green, red,
  // blue.
  NetColoring coloring = ThreeByThree(CodeRule::kSet, {0, 1, 0, 2});
  const std::vector<int> top = KnotLinks(3, 3, 0, 1);
  coloring.link_colour[top[0]] = 0;
  coloring.link_colour[top[2]] = 1;
  const DrawnKnot centre = Draw({0, 1, 0, 2});
  const IdentityCheck among = CheckIdentity(centre.image, Book(coloring), 1, centre.knot,
                                            YarnDirections{centre.angles, {}}, FullColour());
  EXPECT_EQ(among.verdict, IdentityVerdict::kConsistent) << among.why;
}

TEST(CheckIdentity, ASolidOverTheKnotIsNotReadAsAYarn) {
  // A grey disc of 12 px radius over the knot (a corner mass): read from its centre out, a yarn
  // would start grey, close to the white dye.
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kSet, {0, 1, 0, 2}));
  const DrawnKnot massed = Draw({0, 1, 0, 2}, 12);
  IdentityCheckOptions o = FullColour();
  o.min_certain_yarns = 4;
  const IdentityCheck c =
      CheckIdentity(massed.image, book, kCentre, massed.knot, ByNeighbours(massed), o);
  EXPECT_EQ(c.verdict, IdentityVerdict::kConsistent) << c.why;
  // A disc over most of the read segment: not read at all.
  const DrawnKnot buried = Draw({0, 1, 0, 2}, 25);
  const IdentityCheck b =
      CheckIdentity(buried.image, book, kCentre, buried.knot, ByNeighbours(buried), o);
  EXPECT_EQ(b.verdict, IdentityVerdict::kUnreadable) << b.why;
  EXPECT_NE(b.why.find("solid"), std::string::npos) << b.why;
}

TEST(CheckIdentity, DegenerateInputIsRejectedWithTheReason) {
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kSet, {0, 1, 0, 2}));
  const DrawnKnot d = Draw({0, 1, 0, 2});
  const YarnDirections y = ByNeighbours(d);
  auto message = [&](auto&& call) -> std::string {
    try {
      call();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_THROW(CheckIdentity(d.image, book, 9, d.knot, y), std::out_of_range);
  EXPECT_THROW(CheckIdentity(d.image, book, -1, d.knot, y), std::out_of_range);
  EXPECT_NE(message([&] {
              CheckIdentity(d.image, book, 9, d.knot, y);
            }).find("knot 9 is not in the net (0..8)"),
            std::string::npos);
  cv::Mat grey;
  cv::cvtColor(d.image, grey, cv::COLOR_BGR2GRAY);
  EXPECT_THROW(CheckIdentity(grey, book, kCentre, d.knot, y), std::invalid_argument);
  EXPECT_NE(message([&] { CheckIdentity(grey, book, kCentre, d.knot, y); }).find("not CV_8UC3"),
            std::string::npos);
  EXPECT_THROW(CheckIdentity(d.image, book, kCentre, {NAN, 3}, y), std::invalid_argument);
  // Knot (0, 0) has no up or left neighbour.
  EXPECT_THROW(CheckIdentity(d.image, book, 0, d.knot, y), std::invalid_argument);
  YarnDirections one_branch;
  one_branch.branch_angles_rad = {0.3};
  EXPECT_THROW(CheckIdentity(d.image, book, kCentre, d.knot, one_branch), std::invalid_argument);
  // Not a whole net in row-major order.
  EXPECT_THROW(CheckIdentity(d.image, book.Restrict({0, 1, 2, 4}), 3, d.knot, y),
               std::invalid_argument);
  IdentityCheckOptions bad = FullColour();
  bad.link_fraction = 1.5;
  EXPECT_THROW(CheckIdentity(d.image, book, kCentre, d.knot, y, bad), std::invalid_argument);
  // One labeled neighbour, or a knot at the frame's border: the colours say nothing.
  YarnDirections lone;
  lone.neighbour_px[0] = d.neighbours[0];
  EXPECT_EQ(CheckIdentity(d.image, book, kCentre, d.knot, lone, FullColour()).verdict,
            IdentityVerdict::kUnreadable);
  EXPECT_EQ(CheckIdentity(d.image, book, kCentre, {4, 100}, y, FullColour()).verdict,
            IdentityVerdict::kUnreadable);
}

// ---------------------------------------------------------------------------------------------
// ReadJunctionIdentity: the knot picker's hint at an unlabeled junction.

bool Has(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

TEST(ReadJunctionIdentity, ADistinctCodeIdentifiesItsKnotEvenWithABranchMissed) {
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kCyclic, {0, 1, 0, 2}));
  const DrawnKnot centre = Draw({2, 0, 1, 0});  // the cyclic code, rotated
  const JunctionReading all =
      ReadJunctionIdentity(centre.image, book, centre.knot, centre.angles, 80, FullColour());
  EXPECT_EQ(all.status, IdentifyStatus::kIdentified) << all.why;
  EXPECT_EQ(all.knots, std::vector<int>{kCentre});
  EXPECT_EQ(all.yarns_certain, 4);
  EXPECT_NE(all.why.find("only (1, 1) fits"), std::string::npos) << all.why;
  // The detector saw three of the four yarns: still only the centre has red, green and red.
  const DrawnKnot missed = Draw({0, 1, 0, -1});
  const JunctionReading three =
      ReadJunctionIdentity(missed.image, book, missed.knot, missed.angles, 80, FullColour());
  EXPECT_EQ(three.status, IdentifyStatus::kIdentified) << three.why;
  EXPECT_EQ(three.knots, std::vector<int>{kCentre});
  // The centre labeled elsewhere in the view: nothing is offered, and the reason says why.
  const JunctionReading taken = ReadJunctionIdentity(centre.image, book, centre.knot, centre.angles,
                                                     80, FullColour(), {kCentre});
  EXPECT_EQ(taken.status, IdentifyStatus::kUnknown);
  EXPECT_TRUE(taken.knots.empty());
  EXPECT_EQ(taken.excluded, 1);
  EXPECT_NE(taken.why.find("1 labeled elsewhere"), std::string::npos) << taken.why;
}

TEST(ReadJunctionIdentity, ASharedCodeOffersEveryKnotItFitsAndNeverOne) {
  // Two yellow yarns at a right angle: every corner (yellow, yellow) and every edge knot with
  // two yellow links fits; the centre (red, green, red, blue) does not.
  const KnotCodebook book = Book(ThreeByThree(CodeRule::kSet, {0, 1, 0, 2}));
  const DrawnKnot corner = Draw({3, 3, -1, -1});
  const JunctionReading r =
      ReadJunctionIdentity(corner.image, book, corner.knot, corner.angles, 80, FullColour());
  EXPECT_EQ(r.status, IdentifyStatus::kAmbiguous) << r.why;
  for (int k : {0, 2, 6, 8}) EXPECT_TRUE(Has(r.knots, k)) << "corner " << k << ": " << r.why;
  EXPECT_FALSE(Has(r.knots, kCentre));
  // Every other knot that fits labeled elsewhere: the one left is identified (both yarns read
  // with certainty), still only offered: the person picks it.
  const JunctionReading last = ReadJunctionIdentity(corner.image, book, corner.knot, corner.angles,
                                                    80, FullColour(), {0, 2, 6, 1, 3, 5, 7});
  EXPECT_EQ(last.status, IdentifyStatus::kIdentified) << last.why;
  EXPECT_EQ(last.knots, std::vector<int>{8}) << last.why;
  EXPECT_EQ(last.excluded, static_cast<int>(r.knots.size()) - 1);
  // A solid over the junction: nothing is read.
  const DrawnKnot buried = Draw({0, 1, 0, 2}, 25);
  const JunctionReading solid =
      ReadJunctionIdentity(buried.image, book, buried.knot, buried.angles, 80, FullColour());
  EXPECT_EQ(solid.status, IdentifyStatus::kUnknown);
  EXPECT_NE(solid.why.find("solid"), std::string::npos) << solid.why;
  // Bad input names what is wrong.
  EXPECT_THROW(ReadJunctionIdentity(buried.image, book, buried.knot, {0.5}, 80),
               std::invalid_argument);
  EXPECT_THROW(ReadJunctionIdentity(buried.image, book, {NAN, 1}, buried.angles, 80),
               std::invalid_argument);
}

TEST(ReadJunctionIdentity, TheTrueKnotIsAlwaysOfferedOnARenderedNet) {
  const ScratchDir dir("label_identity");
  for (double roll : {20.0, 0.0}) {
    const RenderedColouring net = RenderColouring(roll, dir);
    int identified = 0, offered = 0, unknown = 0;
    size_t candidates = 0;
    for (int k = 0; k < kSide * kSide; ++k) {
      const int r = k / kSide, c = k % kSide;
      const YarnDirections y = net.Branches(r, c, r, c);
      double link = std::numeric_limits<double>::infinity();
      for (const auto& nb : y.neighbour_px)
        if (nb) link = std::min(link, (*nb - net.pixels[k]).norm());
      const JunctionReading j =
          ReadJunctionIdentity(net.frame, net.codebook, net.pixels[k], y.branch_angles_rad, link);
      if (j.status == IdentifyStatus::kUnknown) {
        ++unknown;
        continue;
      }
      EXPECT_TRUE(Has(j.knots, k)) << "roll " << roll << ", knot " << k << ": " << j.why;
      if (j.status == IdentifyStatus::kIdentified) {
        ++identified;
        EXPECT_EQ(j.knots, std::vector<int>{k}) << j.why;
      } else {
        ++offered;
        candidates += j.knots.size();
      }
    }
    std::printf("roll %.0f deg: %d identified, %d offered (%.1f candidates each), %d unknown\n",
                roll, identified, offered, offered ? double(candidates) / offered : 0.0, unknown);
    // Measured: 6 identified, 17 offered (4 knots each), 2 unknown at 20 degrees; at 0 degrees
    // the near-axis yarns are unread and 25 are offered (15.6 each).
    if (roll > 10) {
      EXPECT_GE(identified, 5);
    }
  }
}

}  // namespace
}  // namespace netlab::recon
