// Pixel format standardization.
#include "picksight/video_server/pixel_format.hpp"

#include <opencv2/imgproc.hpp>

namespace picksight::video {

const char* pixelLayoutName(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kMono8: return "Mono8";
    case PixelLayout::kMono10: return "Mono10";
    case PixelLayout::kMono12: return "Mono12";
    case PixelLayout::kMono16: return "Mono16";
    case PixelLayout::kBayerRG8: return "BayerRG8";
    case PixelLayout::kBayerGR8: return "BayerGR8";
    case PixelLayout::kBayerBG8: return "BayerBG8";
    case PixelLayout::kBayerGB8: return "BayerGB8";
    case PixelLayout::kRGB8: return "RGB8";
    case PixelLayout::kBGR8: return "BGR8";
    case PixelLayout::kYUYV: return "YUYV";
    case PixelLayout::kUYVY: return "UYVY";
    case PixelLayout::kMJPEG: return "MJPEG";
  }
  return "unknown";
}

Result<cv::Mat> toOutputFormat(const cv::Mat& raw, PixelLayout layout, OutputFormat format) {
  const bool mono = format == OutputFormat::kMono8;
  cv::Mat out;
  switch (layout) {
    case PixelLayout::kMono8:
      if (raw.type() != CV_8UC1) break;
      if (mono) return raw;
      cv::cvtColor(raw, out, cv::COLOR_GRAY2BGR);
      return out;
    case PixelLayout::kBGR8:
      if (raw.type() != CV_8UC3) break;
      if (!mono) return raw;
      cv::cvtColor(raw, out, cv::COLOR_BGR2GRAY);
      return out;
    default:
      return makeError(kSourceNotSupported,
                       std::string("pixel layout ") + pixelLayoutName(layout) + " is not converted yet");
  }
  return makeError(kSourceBadValue, std::string("buffer does not match layout ") + pixelLayoutName(layout));
}

}  // namespace picksight::video
