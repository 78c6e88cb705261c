#pragma once
// A point moving at constant velocity over a few adjacent frames, fitted to its views in all of
// them: where it is in one frame when that frame's views alone do not fix it (one camera sees
// it, or two whose rays meet at a shallow angle).
//
// At 179 frames/s a knot of the flying net moves a few millimetres a frame and its velocity
// hardly changes from one frame to the next (docs/benchmarks.md, labeling, "The defaults"). What
// a straight path cannot follow (a knot stopped by the target, a jerk) shows in the fit's
// residuals.
//
//   std::vector<TimedObservation> views = ...;  // frames t-5 .. t, every camera that labels it
//   const PointEstimate at_t = FitConstantVelocity(rig, views, t);
//   if (at_t.valid && at_t.sum_squares_px2 <= limit) use(at_t.position, at_t.unit_covariance);

#include <vector>

#include "calibration/rig.h"
#include "libreconstruct/geometry/triangulation.h"

namespace netlab::recon {

// A view of the point at a time (any unit, e.g. frame rows).
struct TimedObservation {
  double time = 0.0;
  Observation view;
};

// The point's place at `time` on the straight path at constant velocity that best explains
// `views` (least squares on their pixel residuals; a linear start, then Gauss-Newton). The
// estimate's unit_covariance is that place's (for 1 px of noise per axis in each view, the
// velocity marginalised out), residual_px and sum_squares_px2 the views', inliers all of them
// (no outliers are taken out: the caller judges the residuals). Not valid where the views do
// not fix the path (fewer than three; one camera alone cannot tell how far the point is), or
// it leaves the front of a camera.
PointEstimate FitConstantVelocity(const calib::Rig& rig, const std::vector<TimedObservation>& views,
                                  double time);

}  // namespace netlab::recon
