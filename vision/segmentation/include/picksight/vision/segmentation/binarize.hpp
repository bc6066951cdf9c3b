// Binarization of a grey image into part (255) and background (0) pixels.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace picksight::vision {

enum class Polarity { kDarkOnLight, kLightOnDark };
enum class ThresholdMethod { kAdaptive, kOtsu, kFixed };

struct BinarizeOptions {
  ThresholdMethod method = ThresholdMethod::kAdaptive;
  Polarity polarity = Polarity::kDarkOnLight;
  int fixed_threshold = 128;  // kFixed: grey level separating part and background
  // kAdaptive: size in pixels of the window over which the illumination is
  // estimated. It must exceed the width of the largest part, or that part's
  // middle is taken for background and the part breaks apart. 0 = a sixth of
  // the smaller image side.
  int adaptive_window = 0;
  // kAdaptive: the grey level of the part's faintest stretch as a share of
  // its surface's beside it (in this polarity: a dark part's lightest
  // pixels' level over the surface's; 0 = not known), where LEARN has read
  // it. Where the frame's levels do not fall into two populations (a part
  // alone on gravel or a textured belt: the frame is surface but for a
  // hundredth of it, and Otsu splits the surface's own grain), part and
  // surface are split by it instead.
  double part_level = 0;
};

// Returns a CV_8UC1 mask, 255 on parts. `grey` is CV_8UC1.
cv::Mat binarize(const cv::Mat& grey, const BinarizeOptions& options);

// Row `y` of the 3x3 mean of `grey` (CV_8UC1) into `out` (grey.cols
// levels), cv::blur's with BORDER_REPLICATE to the last bit; `sums` holds
// grey.cols + 2 values. binarize compares a noisy frame's mean so, row by
// row, instead of blurring the whole frame first.
void meanRow3x3(const cv::Mat& grey, int y, uint16_t* sums, uint8_t* out);

// The adaptive window (pixels) binarize uses on an image of `size`: the
// option, or its default (a sixth of the smaller side).
int adaptiveWindow(cv::Size size, const BinarizeOptions& options);

// The smallest adaptive window that keeps a part whole: its interior must
// lie within half a window of background, or the illumination estimate there
// is the part's own level and its middle breaks into holes. `radius`: the
// part's farthest boundary point from its centroid (pixels).
int windowForPart(double radius);

}  // namespace picksight::vision
