#pragma once
// Identity check by colour: is the knot a label names the knot whose yarns the image shows?
//
// Every link of the net is dyed (coloring.yaml, net_coloring.h); a labeled knot's yarns must have
// the colours of that knot's links. The colours are read with IdentifyKnot (color_identify.h) and
// compared with the labeled knot's links; a contradiction is a kMismatch, for review, never a
// silent relabel. A wrong label that is not caught costs a wrong track, a false alarm costs the
// user a look: kMismatch is reported only on a confident contradiction, anything unsure is
// kUnreadable.
//
// Which yarn is which link. The yarn directions come from one of two sources:
// - the labeled neighbours: the yarn towards the labeled right neighbour IS the knot's right link
//   (whatever side the net is seen from), so each yarn is compared with its own link's colour;
// - the detector's branch angles (Junction::branch_angles_rad, knot_detect.h): the yarns in image
//   angle order, with no link attached. Distinct branches are distinct links, whatever the rule:
//   some one-to-one assignment of the yarns to the knot's links must fit (with as many branches
//   as links, a permutation of its link colours). Under the cyclic rule, with as many branches
//   as links, the angle order counts too: it is a rotation or mirror image of the geometric
//   order right, down, left, up. With more branches than links (a spurious one) the links must
//   be distinct branches.
// A yarn is READ when its best dye fits (ΔE00 <= IdentifyOptions::max_delta_e); its plausible
// dyes are those within the ambiguity margin of the best (YarnReading::plausible). A read yarn
// contradicts a link when the link's dye is not plausible for it.

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libreconstruct/coloring/color_identify.h"
#include "libreconstruct/coloring/net_coloring.h"

namespace netlab::recon {

// The codebook of a coloured net as the cameras see it: palette colour i is lighting.Seen(dye i's
// sRGB), the colour `netlab render` draws the yarn in times its illumination (for rendered frames
// lighting.exposure = RenderJob::illumination, 0.85, unit gains; a dye without sRGB takes the
// render's fallback, DefaultColoring's palette in order); knot k = row * cols + col with its link
// colours in geometric order (right, down, left, up; KnotLinkColours); rule = the colouring's.
// Throws std::invalid_argument on an invalid lighting or a colouring without colours.
KnotCodebook CodebookFromColoring(const NetColoring& coloring,
                                  const std::vector<std::array<int, 3>>& palette_srgb,
                                  const Lighting& lighting);

enum class IdentityVerdict {
  kConsistent,  // enough yarns read with certainty (see options), every read yarn fits the knot
  kMismatch,    // the read yarns contradict the labeled knot's links: review the label
  kUnreadable,  // too few yarns read with certainty: the colours say nothing either way
};
std::string IdentityVerdictName(IdentityVerdict verdict);  // "consistent", "mismatch", ...

struct IdentityCheck {
  IdentityVerdict verdict = IdentityVerdict::kUnreadable;
  std::string why;  // one line for the reviewer: the yarns read and the contradiction
  // What the colours say: the codebook knots fitting the reading (IdentifyKnot over the whole
  // codebook): one when they identify a knot, several when ambiguous, empty when nothing fits
  // or fewer yarns than links were seen.
  std::vector<int> knots_read;
  int yarns = 0;          // yarns looked at
  int yarns_certain = 0;  // read with one plausible dye
  int yarns_contradicting = 0;
};

// Where the labeled knot's yarns leave it in the image.
struct YarnDirections {
  // Image angles atan2(dy, dx) of the branches the detector measured (2..4, any order). When
  // empty, the directions towards the labeled neighbours are used.
  std::vector<double> branch_angles_rad;
  // Pixels of the labeled neighbours, slots right (col + 1), down (row + 1), left, up; nullopt
  // when not labeled. A slot the net does not have (the border) must be nullopt. They also give
  // the links' image length (how far along the yarns to read), with branch angles too.
  std::array<std::optional<Eigen::Vector2d>, 4> neighbour_px;
};

struct IdentityCheckOptions {
  // How the yarn colours are read (IdentifyKnot). Its bayer must be the camera's; its
  // candidate_knots are ignored (what the colours say is judged over the whole codebook).
  IdentifyOptions identify;
  // Each yarn is read out to this fraction of the shortest labeled link (image px), within
  // [identify.outer_radius_px, max_outer_radius_px]. A longer segment crosses more mosaic rows, so
  // a yarn a few degrees off an image axis is still phase-averaged (docs/labeling.md).
  // Sagging links leave the chord towards the neighbour in the middle: stay well short of it.
  double link_fraction = 0.4;
  double max_outer_radius_px = 60.0;
  // A solid at the knot (corner mass, knot ball) would be read as a yarn: the yarns are read from
  // its rim outwards, the rim being the last ring around the knot on which at least this fraction
  // of the pixels stands out from the background (identify.min_contrast).
  double solid_occupancy = 0.6;
  // kConsistent needs this many yarns read with certainty (all of them at a knot with fewer
  // links): one agreeing yarn is weak support (a pure swap of two labels, with directions from
  // the stale neighbours, agrees on the one link the two knots share).
  int min_certain_yarns = 2;
  // A neighbour nearer than this is not used for a direction or a link length (px): the yarn
  // between them is too short to read.
  double min_link_px = 12.0;

  bool IsValid(std::string* error) const;
};

// Checks that the knot labeled `knot` at `px` of a demosaiced 8-bit frame (linear BGR, as
// SynchronizedSequence::ReadDisplay level 0 gives it) has the link colours of `knot` in
// `codebook` (a whole net, knot k = row * cols + col, as CodebookFromColoring makes it).
// Throws std::invalid_argument on a frame that is not CV_8UC3, a non-finite px, a codebook that
// is not a whole net in row-major order, invalid options, branch angles outside 2..4 or not
// finite, or a neighbour in a slot the knot does not have; std::out_of_range on a knot outside
// the codebook. A knot near the border, inside a solid, or with fewer than two usable
// directions is kUnreadable.
IdentityCheck CheckIdentity(const cv::Mat& bgr8, const KnotCodebook& codebook, int knot,
                            const Eigen::Vector2d& px, const YarnDirections& yarns,
                            const IdentityCheckOptions& options = {});

// What the colours of an unlabeled junction say about which knot it is: the knot picker's hint
// when the person seeds a knot. The junction's yarns leave it along the detector's branches
// (`branch_angles_rad`, 2..4, any order; their links unknown); each is read out to
// options.link_fraction of `link_px` (the net's link length in this image; <= 0: unknown, the
// reading stops at identify.outer_radius_px), from beyond any solid at the junction. A knot fits
// when its links and the yarns pair up one to one with each link's dye plausible for its yarn (a
// spurious branch or a missed one allowed), and in cyclic order under the cyclic rule with as
// many yarns as links. Knots in `exclude` (labeled elsewhere in this view) are not offered.
//
// Offered, never applied: kIdentified only when exactly one knot fits and at least
// options.min_certain_yarns yarns (all of them at a junction with fewer) are read with one
// plausible dye; kAmbiguous lists every knot that fits; kUnknown says why nothing was read (no
// yarn's colour read at all is kUnknown too: the whole net would fit).
struct JunctionReading {
  IdentifyStatus status = IdentifyStatus::kUnknown;
  std::vector<int> knots;  // codebook indices, row-major (the net's knot numbers)
  int yarns = 0;           // yarns looked at
  int yarns_certain = 0;   // read with one plausible dye
  int excluded = 0;        // knots that fit but were excluded
  std::string why;         // one line for the person: the yarns read and what they fit
};

// Throws std::invalid_argument on a frame that is not CV_8UC3, a non-finite px, branch angles
// outside 2..4 or not finite, invalid options, or a codebook that is not a whole net.
JunctionReading ReadJunctionIdentity(const cv::Mat& bgr8, const KnotCodebook& codebook,
                                     const Eigen::Vector2d& px,
                                     const std::vector<double>& branch_angles_rad, double link_px,
                                     const IdentityCheckOptions& options = {},
                                     const std::vector<int>& exclude = {});

}  // namespace netlab::recon
