// Pixel format standardization: every source layout to mono8 or bgr8.
#include "picksight/video_server/pixel_format.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <string>

namespace picksight::video {
namespace {

Error mismatch(PixelLayout layout, const cv::Mat& raw, const char* expected) {
  return makeError(SourceErrc::kBadValue,
                   std::string("buffer does not match layout ") + pixelLayoutName(layout) +
                       ": expected " + expected + ", got " + std::to_string(raw.cols) + "x" +
                       std::to_string(raw.rows) + " of type " + std::to_string(raw.type()));
}

// OpenCV names a Bayer code after the colours of the second row's second and
// third pixels, GenICam (and V4L2) after the first row's first two: the 2x2
// cell seen from (1,1) instead of (0,0) swaps both axes, so GenICam RG is
// OpenCV BG and so on. Pinned by a test on a hand-made mosaic.
struct BayerCodes {
  int to_bgr;
  int to_gray;
};
BayerCodes bayerCodes(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kBayerRG8:
      return {cv::COLOR_BayerBG2BGR, cv::COLOR_BayerBG2GRAY};
    case PixelLayout::kBayerGR8:
      return {cv::COLOR_BayerGB2BGR, cv::COLOR_BayerGB2GRAY};
    case PixelLayout::kBayerBG8:
      return {cv::COLOR_BayerRG2BGR, cv::COLOR_BayerRG2GRAY};
    default:
      return {cv::COLOR_BayerGR2BGR, cv::COLOR_BayerGR2GRAY};  // kBayerGB8
  }
}

// Full-scale value of the unpacked 16-bit mono layouts.
double monoMax(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kMono10:
      return 1023.0;
    case PixelLayout::kMono12:
      return 4095.0;
    default:
      return 65535.0;
  }
}

// A truncated JPEG decodes "successfully" in libjpeg (the missing rows come
// out grey, with only a warning on stderr), so a frame cut short by a USB or
// network hiccup is caught here by its missing end-of-image marker. Some
// webcams pad the payload with zeros after the marker.
bool jpegLooksComplete(const cv::Mat& raw) {
  const auto* bytes = raw.ptr<uint8_t>();
  size_t n = raw.total();
  if (n < 4 || bytes[0] != 0xFF || bytes[1] != 0xD8) return false;
  while (n > 2 && bytes[n - 1] == 0x00) --n;
  return bytes[n - 2] == 0xFF && bytes[n - 1] == 0xD9;
}

Result<cv::Mat> decodeJpeg(const cv::Mat& raw, bool mono) {
  if (raw.type() != CV_8UC1 || !raw.isContinuous() || raw.empty()) {
    return mismatch(PixelLayout::kMJPEG, raw, "one continuous row of bytes");
  }
  if (!jpegLooksComplete(raw)) {
    return makeError(SourceErrc::kBadValue, "corrupt MJPEG frame (" + std::to_string(raw.total()) +
                                                " bytes): no JPEG start or end marker");
  }
  // Decoding to grey skips the colour planes entirely (libjpeg reads Y only).
  cv::Mat out = cv::imdecode(raw, mono ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  if (out.empty()) {
    return makeError(SourceErrc::kBadValue, "corrupt MJPEG frame (" + std::to_string(raw.total()) +
                                                " bytes): not decodable");
  }
  return out;
}

Result<cv::Mat> convert(const cv::Mat& raw, PixelLayout layout, bool mono) {
  cv::Mat out;
  switch (layout) {
    case PixelLayout::kMono8:
      if (raw.type() != CV_8UC1) return mismatch(layout, raw, "CV_8UC1");
      if (mono) return raw;
      cv::cvtColor(raw, out, cv::COLOR_GRAY2BGR);
      return out;
    case PixelLayout::kMono10:
    case PixelLayout::kMono12:
    case PixelLayout::kMono16: {
      if (raw.type() != CV_16UC1) return mismatch(layout, raw, "CV_16UC1");
      // One rounding pass; values above full scale (stray high bits) saturate.
      cv::Mat grey;
      raw.convertTo(grey, CV_8U, 255.0 / monoMax(layout));
      if (mono) return grey;
      cv::cvtColor(grey, out, cv::COLOR_GRAY2BGR);
      return out;
    }
    case PixelLayout::kBayerRG8:
    case PixelLayout::kBayerGR8:
    case PixelLayout::kBayerBG8:
    case PixelLayout::kBayerGB8: {
      if (raw.type() != CV_8UC1 || raw.cols < 2 || raw.rows < 2) {
        return mismatch(layout, raw, "CV_8UC1, at least 2x2");
      }
      const BayerCodes codes = bayerCodes(layout);
      cv::cvtColor(raw, out, mono ? codes.to_gray : codes.to_bgr);
      return out;
    }
    case PixelLayout::kRGB8:
      if (raw.type() != CV_8UC3) return mismatch(layout, raw, "CV_8UC3");
      cv::cvtColor(raw, out, mono ? cv::COLOR_RGB2GRAY : cv::COLOR_RGB2BGR);
      return out;
    case PixelLayout::kBGR8:
      if (raw.type() != CV_8UC3) return mismatch(layout, raw, "CV_8UC3");
      if (!mono) return raw;
      cv::cvtColor(raw, out, cv::COLOR_BGR2GRAY);
      return out;
    case PixelLayout::kYUYV:
    case PixelLayout::kUYVY: {
      // 4:2:2 pairs share U and V, so the width is even.
      if (raw.type() != CV_8UC2 || raw.cols % 2 != 0)
        return mismatch(layout, raw, "CV_8UC2, even width");
      const bool yuyv = layout == PixelLayout::kYUYV;
      // Grey is the Y channel as it is: no colour conversion at all.
      const int code = mono ? (yuyv ? cv::COLOR_YUV2GRAY_YUYV : cv::COLOR_YUV2GRAY_UYVY)
                            : (yuyv ? cv::COLOR_YUV2BGR_YUYV : cv::COLOR_YUV2BGR_UYVY);
      cv::cvtColor(raw, out, code);
      return out;
    }
    case PixelLayout::kMJPEG:
      return decodeJpeg(raw, mono);
  }
  return makeError(SourceErrc::kNotSupported,
                   std::string("pixel layout ") + pixelLayoutName(layout) + " is not converted");
}

}  // namespace

const char* pixelLayoutName(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kMono8:
      return "Mono8";
    case PixelLayout::kMono10:
      return "Mono10";
    case PixelLayout::kMono12:
      return "Mono12";
    case PixelLayout::kMono16:
      return "Mono16";
    case PixelLayout::kBayerRG8:
      return "BayerRG8";
    case PixelLayout::kBayerGR8:
      return "BayerGR8";
    case PixelLayout::kBayerBG8:
      return "BayerBG8";
    case PixelLayout::kBayerGB8:
      return "BayerGB8";
    case PixelLayout::kRGB8:
      return "RGB8";
    case PixelLayout::kBGR8:
      return "BGR8";
    case PixelLayout::kYUYV:
      return "YUYV";
    case PixelLayout::kUYVY:
      return "UYVY";
    case PixelLayout::kMJPEG:
      return "MJPEG";
  }
  return "unknown";
}

Result<cv::Mat> toOutputFormat(const cv::Mat& raw, PixelLayout layout, OutputFormat format) {
  if (raw.empty())
    return makeError(SourceErrc::kBadValue,
                     std::string("empty ") + pixelLayoutName(layout) + " frame");
  // The acquisition thread must never see an exception: an OpenCV assertion
  // on a malformed buffer becomes a dropped frame.
  try {
    return convert(raw, layout, format == OutputFormat::kMono8);
  } catch (const cv::Exception& e) {
    return makeError(SourceErrc::kBadValue, std::string("cannot convert ") +
                                                pixelLayoutName(layout) + " frame: " + e.what());
  }
}

}  // namespace picksight::video
