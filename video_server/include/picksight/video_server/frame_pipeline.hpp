// The per-camera output transform: region of interest, resize and output
// pixel format, applied to every sensor frame before it is published.
#pragma once

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"

namespace picksight::video {

struct SourceFrame;

// Output frames beyond these are a typing error, not a camera: a side of
// 16384 pixels, and 64 Mi pixels in all (192 MiB in bgr8), however the size
// is derived (explicit, or the ROI times the scale).
constexpr int kMaxOutputSide = 16384;
constexpr long long kMaxOutputPixels = 64LL * 1024 * 1024;
constexpr double kMaxOutputScale = 16;

enum class OutputFormat { kMono8, kBgr8 };

struct OutputSettings {
  cv::Rect roi;      // in sensor pixels; empty = full sensor
  cv::Size size;     // output size; empty = ROI size (or scaled)
  double scale = 0;  // used when `size` is empty; 0 = 1
  OutputFormat format = OutputFormat::kMono8;
};

struct OutputFrame {
  cv::Mat image;  // continuous, owned
  cv::Point roi_offset;
  double scale_x = 1;  // output pixels per sensor pixel
  double scale_y = 1;
  cv::Size sensor_size;  // of the standardized frame the settings were applied to
};

// Checks settings against a sensor size; the error names what is wrong. With
// a sensor size, the derived output size is checked against the bounds too.
Result<void> validateOutputSettings(const OutputSettings& settings, cv::Size sensor);

// Applies the settings to a sensor frame (CV_8UC1 or CV_8UC3 BGR). Settings
// that do not fit this frame (a sensor that changed size) are clamped. The
// output never shares memory with `sensor`.
// `sensor_is_private`: the caller made `sensor` for this frame alone (a
// format conversion, or a keepable source frame), so it may be published as
// it is instead of copied.
OutputFrame applyOutputSettings(const cv::Mat& sensor, const OutputSettings& settings,
                                bool sensor_is_private = false);

// The same for a frame in any source layout: standardized first.
Result<OutputFrame> applyOutputSettings(const SourceFrame& frame, const OutputSettings& settings);

}  // namespace picksight::video
