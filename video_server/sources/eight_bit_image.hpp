// Image files as the file and dir sources serve them: whatever depth and
// channel count imread gives, as 8-bit mono or BGR.
#pragma once

#include <opencv2/core.hpp>

namespace picksight::video {

// 16-bit scaled by 1/257, other depths stretched to 0..255, BGRA to BGR; an
// 8-bit image is returned as it is (sharing its pixels).
cv::Mat toEightBit(const cv::Mat& image);

}  // namespace picksight::video
