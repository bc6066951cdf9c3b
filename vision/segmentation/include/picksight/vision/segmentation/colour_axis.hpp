// Colour for colour cameras: a part told from its surroundings by its colour
// where grey levels cannot tell them (a green part on a grey belt of the same
// brightness). Each pixel is projected on the axis from the part's colour to
// the surface's, giving a grey image with the part dark and the surface light
// that the rest of the pipeline reads as it reads any grey image: linear in
// each pixel's mix of the two colours, so edges keep their sub-pixel reading.
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

namespace picksight::vision {

// A part's colour and its surface's, BGR, 0..255.
struct ColourAxis {
  cv::Vec3d part;
  cv::Vec3d background;
};

// Grey levels of the projection: the part's colour lands here, the surface's
// there (dark parts on a light surface, whatever their brightness).
constexpr double kColourPartLevel = 40;
constexpr double kColourBackgroundLevel = 200;

// CV_8UC1 of a BGR image (CV_8UC3): each pixel projected on every axis, the
// darkest projection kept (so that parts of every taught colour are dark).
cv::Mat projectOnColourAxes(const cv::Mat& bgr, const std::vector<ColourAxis>& axes);

// The colour axis of the one part in `bgr` within `rect`: the surface's
// colour is the median along the rectangle's rim, the part's the median of
// the pixels Otsu's split of the colour distance from it sets apart. None
// when the rectangle is too small, or the two colours differ by no more than
// noise does.
std::optional<ColourAxis> colourAxisIn(const cv::Mat& bgr, const cv::Rect& rect);

// Whether the colour tells the part from its surface clearly better than
// grey levels do: the colour distance more than `factor` times the
// difference of their grey levels (luma).
bool colourSeparatesBetter(const ColourAxis& axis, double factor = 2.0);

}  // namespace picksight::vision
