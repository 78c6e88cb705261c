#pragma once
// The colour type every stage shares: the renderer draws with it, the colour identity reads it.

#include <opencv2/core.hpp>

namespace netlab::recon {

// Linear-light colour in BGR order, each channel in [0, 1] (1 = sensor white).
using Colour = cv::Vec3f;

}  // namespace netlab::recon
