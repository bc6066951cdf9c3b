// ROI, resize and pixel format for published frames.
#include "picksight/video_server/frame_pipeline.hpp"
#include "picksight/video_server/video_errors.hpp"

#include "picksight/video_server/pixel_format.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace picksight::video {
namespace {

cv::Rect effectiveRoi(const OutputSettings& s, cv::Size sensor) {
  if (s.roi.empty()) return cv::Rect(0, 0, sensor.width, sensor.height);
  return s.roi & cv::Rect(0, 0, sensor.width, sensor.height);
}

cv::Size outputSize(const OutputSettings& s, cv::Size roi) {
  if (!s.size.empty()) return s.size;
  if (s.scale > 0 && s.scale != 1.0) {
    return cv::Size(std::max(1, static_cast<int>(std::lround(roi.width * s.scale))),
                    std::max(1, static_cast<int>(std::lround(roi.height * s.scale))));
  }
  return roi;
}

std::string shown(cv::Size size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

// The bound on what is allocated per frame, whichever way the size was set.
Result<void> checkOutputSize(cv::Size size, const char* how) {
  const long long pixels = static_cast<long long>(size.width) * size.height;
  if (size.width <= kMaxOutputSide && size.height <= kMaxOutputSide && pixels <= kMaxOutputPixels) {
    return {};
  }
  return makeError(VideoErrc::kOutOfRange,
                   std::string(how) + " " + shown(size) + " exceeds the output limit (" +
                       std::to_string(kMaxOutputSide) + " pixels a side, " +
                       std::to_string(kMaxOutputPixels) + " pixels in all)");
}

// The ROI and output size `s` gives on a sensor of `sensor` pixels.
cv::Size derivedSize(const OutputSettings& s, cv::Size sensor) {
  cv::Rect roi = effectiveRoi(s, sensor);
  if (roi.empty()) roi = cv::Rect(0, 0, sensor.width, sensor.height);
  return outputSize(s, roi.size());
}
}  // namespace

Result<void> validateOutputSettings(const OutputSettings& s, cv::Size sensor) {
  // Only the all-zero ROI means the full sensor: one with a zero or negative
  // side (a uint32 from a control request that did not fit an int) is an error.
  if (s.roi != cv::Rect()) {
    if (s.roi.x < 0 || s.roi.y < 0 || s.roi.width <= 0 || s.roi.height <= 0) {
      return makeError(VideoErrc::kOutOfRange,
                       "roi must have a non-negative offset and a positive size");
    }
    // In 64 bits: x + width may overflow an int, and cv::Rect arithmetic with it.
    const int64_t right = int64_t{s.roi.x} + s.roi.width;
    const int64_t bottom = int64_t{s.roi.y} + s.roi.height;
    if (right > std::numeric_limits<int>::max() || bottom > std::numeric_limits<int>::max() ||
        (sensor.area() > 0 && (right > sensor.width || bottom > sensor.height))) {
      return makeError(VideoErrc::kOutOfRange,
                       "roi " + std::to_string(s.roi.x) + "," + std::to_string(s.roi.y) + " " +
                           std::to_string(s.roi.width) + "x" + std::to_string(s.roi.height) +
                           " exceeds the sensor " + std::to_string(sensor.width) + "x" +
                           std::to_string(sensor.height));
    }
  }
  if ((s.size.width == 0) != (s.size.height == 0)) {
    return makeError(VideoErrc::kOutOfRange, "size needs both a width and a height");
  }
  if (s.size.width < 0 || s.size.height < 0 || s.size.width > kMaxOutputSide ||
      s.size.height > kMaxOutputSide) {
    return makeError(VideoErrc::kOutOfRange,
                     "size must be between 1 and " + std::to_string(kMaxOutputSide));
  }
  if (s.size.area() > 0) {
    if (auto ok = checkOutputSize(s.size, "size"); !ok) return ok;
  }
  // Written so that NaN fails too.
  if (!(s.scale >= 0 && s.scale <= kMaxOutputScale))
    return makeError(VideoErrc::kOutOfRange, "scale must be in (0, 16]");
  if (sensor.area() > 0 && s.size.area() == 0) {
    return checkOutputSize(derivedSize(s, sensor), "scaled size");
  }
  return {};
}

OutputFrame applyOutputSettings(const cv::Mat& sensor, const OutputSettings& settings,
                                bool sensor_is_private) {
  OutputFrame out;
  out.sensor_size = sensor.size();
  cv::Rect roi = effectiveRoi(settings, sensor.size());
  if (roi.empty()) roi = cv::Rect(0, 0, sensor.cols, sensor.rows);
  const cv::Size size = outputSize(settings, roi.size());
  out.roi_offset = roi.tl();
  out.scale_x = static_cast<double>(size.width) / roi.width;
  out.scale_y = static_cast<double>(size.height) / roi.height;

  cv::Mat view = sensor(roi);
  cv::Mat sized;
  if (size == roi.size()) {
    sized = view;
  } else {
    // INTER_AREA when shrinking keeps the centroid of every blob where it was;
    // linear when enlarging.
    const int interp = size.area() < roi.area() ? cv::INTER_AREA : cv::INTER_LINEAR;
    cv::resize(view, sized, size, 0, 0, interp);
  }
  const bool want_mono = settings.format == OutputFormat::kMono8;
  if (want_mono && sized.channels() == 3) {
    cv::cvtColor(sized, out.image, cv::COLOR_BGR2GRAY);
  } else if (!want_mono && sized.channels() == 1) {
    cv::cvtColor(sized, out.image, cv::COLOR_GRAY2BGR);
  } else if ((!sensor_is_private && sized.datastart == sensor.datastart) || !sized.isContinuous()) {
    // Never publish the source's own buffer (it is reused for the next
    // frame), and publish only continuous images (sent as one block).
    out.image = sized.clone();
  } else {
    out.image = sized;
  }
  return out;
}

Result<OutputFrame> applyOutputSettings(const SourceFrame& frame, const OutputSettings& settings) {
  auto standard = toOutputFormat(frame.image, frame.layout, settings.format);
  if (!standard) return standard.error();
  // Settings checked before the first frame (or before the device changed
  // size) may give a frame too big on this one: dropped, with the reason.
  if (auto ok = checkOutputSize(derivedSize(settings, standard->size()), "output size"); !ok) {
    return ok.error();
  }
  return applyOutputSettings(*standard, settings,
                             frame.keepable || standard->datastart != frame.image.datastart);
}

}  // namespace picksight::video
