// Pixel format standardization: every layout a source delivers, to the
// published mono8 or bgr8.
#pragma once

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"
#include "picksight/sources/source.hpp"
#include "picksight/video_server/frame_pipeline.hpp"

namespace picksight::video {

// Converts `raw` (laid out as `layout`) to CV_8UC1 (kMono8) or CV_8UC3 BGR
// (kBgr8). The result may share memory with `raw` when no conversion is
// needed. Errors for a buffer that does not match its layout (a truncated
// MJPEG, a wrong size).
Result<cv::Mat> toOutputFormat(const cv::Mat& raw, PixelLayout layout, OutputFormat format);

}  // namespace picksight::video
