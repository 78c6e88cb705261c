#pragma once
// Tracking labeled knots from one frame to the next (or the previous) of one camera.
//
// Pyramidal Lucas-Kanade optical flow on the blurred grey image, forwards and back: a knot whose
// forward-backward error exceeds max_fb_error_px has no trusted flow. A knot with trusted flow
// is snapped with the knot detector at the flow's end; it is accepted when a junction of the
// knot's degree (2 corner, 3 edge, 4 inner; a corner's junction is its corner mass, see
// FindNode; or one yarn short, each yarn leading to one of the knot's neighbours) is the only
// one within snap_radius_px there; where the rings find none, the yarns are fitted along the
// knot's links as they ran in the frame before (KnotDetector::FitAlong: the mesh seen sheared
// in a fold). A knot without trusted flow is
// predicted from its grid neighbours' motion (an occluded knot moves with the net: accepted
// neighbours' junctions, else their flow) and snapped there alike, in rounds as neighbours get
// accepted; it is accepted when, besides, at least two accepted neighbours move as one (within
// max_neighbour_spread_px). Last, every accepted knot must have moved as its accepted grid
// neighbours did (within max_relative_motion_px of one of the motions they make it expect: the
// mean of two opposite neighbours', a parallelogram's with a diagonal one, the mean of all its
// side neighbours'): between frames a net moves, turns and stretches nearly evenly over a mesh,
// and a junction that did not is something beside the knot (a yarn's end at the knot ball). No
// knot whose result lies within the snap radius of another's is accepted. A knot not accepted
// needs review, with the reason, at the best position there is.

#include <Eigen/Core>
#include <cmath>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "libreconstruct/labeling/knot_detect.h"

namespace netlab::recon {

struct TrackOptions {
  double max_fb_error_px = 0.5;
  double snap_radius_px = 3.0;
  int window_px = 31;
  int pyramid_levels = 4;
  double flow_blur_px = 2.5;  // Gaussian blur of the images for the flow (thin yarns)
  // Lucas-Kanade's least eigenvalue of the window's gradient matrix (per pixel, OpenCV's
  // minEigThreshold). OpenCV's 1e-4 lost a knot in twenty of the far cameras, whose dim dyes
  // give little gradient in grey; the forward-backward check guards the flow.
  double min_eigenvalue = 1e-5;
  // A knot without trusted flow is accepted on its neighbours' motion when at least two grid
  // neighbours are accepted and their motions (their junctions', from the previous frame) lie
  // within this many px of their median (the net there moves as one), and the checks on the
  // junction pass as for flow; 0: never.
  double max_neighbour_spread_px = 1.0;
  // An accepted knot's motion may differ from the motion its accepted neighbours make it
  // expect by at most this (px; the truth's own differ by under 0.6 px on Net A); 0: not
  // checked.
  double max_relative_motion_px = 1.2;
  // A junction one yarn short of the knot's degree (an inner knot with three yarns, an edge
  // knot with two; a dim dye fading into the background) is the knot when each of its yarns
  // leaves within this angle of the direction to a different labeled grid neighbour; 0: the
  // degree must be met.
  double max_yarn_angle_deg = 15.0;
  // Knotless nets: such a junction is the knot only where the colour of its straight pair of
  // yarns changes within this of it (px, Junction::colour_step): its lone yarn alone places it
  // along the pair, as an edge knot's. 0: not checked (LabelEngine sets it from
  // edge_colour_step_px). Needs detector.colour_step.
  double edge_colour_step_px = 0.0;
  // A junction within this of the edge of a body behind the net (the target's outline,
  // KnotDetector::NearBackgroundEdge) is accepted only where it has the knot's degree and each
  // of its yarns leads to a different neighbour (max_yarn_angle_deg): the knot may have just
  // passed behind the body, its yarns on this side making a junction at the edge. 0: not
  // checked.
  double body_edge_px = 2.0;
  // Where the detector's rings find no junction at the flow's end, the knot's yarns fitted along
  // its links' directions in the frame before (all of its neighbours labeled there), from
  // where the closest two are this far apart (px; KnotDetector::FitAlong): a crossing too acute
  // for the rings (a folded net). 0: not tried.
  double fit_along_gap_px = 5.0;
  KnotDetectorOptions detector;
};

struct TrackedKnot {
  int knot = 0;                                  // row * cols + col
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // in the next frame
  bool accepted = false;
  double confidence = 0.0;
  std::string why;  // when not accepted
  // Its junction has one yarn fewer than the knot's degree: accepted only where its accepted
  // neighbours' motion could check it (a junction in a fold, a yarn beside its own, passes
  // the yarn-direction test 2-3 px off).
  bool one_yarn_short = false;
  // The yarns of the junction it was snapped to (image angles, rad; Junction::branch_angles_rad).
  std::vector<double> branch_angles_rad;
  // Where the flow (or its neighbours' motion) carried it, the snap's centre.
  Eigen::Vector2d predicted = Eigen::Vector2d::Constant(NAN);
};

// A knot not tracked but labeled in both frames (accepted there: a person's fix, a label kept
// from an earlier run): its motion is known, and it counts as an accepted neighbour.
struct KnownMotion {
  int knot = 0;
  Eigen::Vector2d from = Eigen::Vector2d::Zero(), to = Eigen::Vector2d::Zero();
};

// `knots`: (knot index, position in `from`). Images: the same camera's consecutive frames, BGR or
// grey, 8 or 16 bit. `known`: other knots whose motion is known (not tracked; their motion
// enters the neighbours' checks and predictions, their place in `from` the yarn directions).
std::vector<TrackedKnot> TrackKnots(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<std::pair<int, Eigen::Vector2d>>& knots,
                                    int rows, int cols, const TrackOptions& options = {},
                                    const std::vector<KnownMotion>& known = {});

}  // namespace netlab::recon
