// Pixel format standardization: every source layout to mono8 or bgr8.
#include "picksight/video_server/pixel_format.hpp"

#include "picksight/video_server/mjpeg_frame.hpp"

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include <cstdint>
#include <optional>
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
// A Bayer layout's 2x2 pattern (as its 8-bit layout) and the full scale of
// its values; nullopt for layouts that are not Bayer.
struct BayerInfo {
  PixelLayout pattern;
  double max;
};
std::optional<BayerInfo> bayerInfo(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kBayerRG8:
    case PixelLayout::kBayerGR8:
    case PixelLayout::kBayerBG8:
    case PixelLayout::kBayerGB8:
      return BayerInfo{layout, 255.0};
    case PixelLayout::kBayerRG10:
      return BayerInfo{PixelLayout::kBayerRG8, 1023.0};
    case PixelLayout::kBayerGR10:
      return BayerInfo{PixelLayout::kBayerGR8, 1023.0};
    case PixelLayout::kBayerBG10:
      return BayerInfo{PixelLayout::kBayerBG8, 1023.0};
    case PixelLayout::kBayerGB10:
      return BayerInfo{PixelLayout::kBayerGB8, 1023.0};
    case PixelLayout::kBayerRG12:
      return BayerInfo{PixelLayout::kBayerRG8, 4095.0};
    case PixelLayout::kBayerGR12:
      return BayerInfo{PixelLayout::kBayerGR8, 4095.0};
    case PixelLayout::kBayerBG12:
      return BayerInfo{PixelLayout::kBayerBG8, 4095.0};
    case PixelLayout::kBayerGB12:
      return BayerInfo{PixelLayout::kBayerGB8, 4095.0};
    case PixelLayout::kBayerRG16:
      return BayerInfo{PixelLayout::kBayerRG8, 65535.0};
    case PixelLayout::kBayerGR16:
      return BayerInfo{PixelLayout::kBayerGR8, 65535.0};
    case PixelLayout::kBayerBG16:
      return BayerInfo{PixelLayout::kBayerBG8, 65535.0};
    case PixelLayout::kBayerGB16:
      return BayerInfo{PixelLayout::kBayerGB8, 65535.0};
    default:
      return std::nullopt;
  }
}
BayerCodes bayerCodes(PixelLayout pattern) {
  switch (pattern) {
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

// Packed mono rows to 16-bit words: each row holds whole groups of
// `pixels` pixels in `bytes` bytes.
struct Packing {
  int bytes;
  int pixels;
};
Packing packingOf(PixelLayout layout) {
  return layout == PixelLayout::kMono10p ? Packing{5, 4} : Packing{3, 2};
}
void unpackGroup(PixelLayout layout, const uint8_t* b, uint16_t* p) {
  const auto u = [](unsigned v) { return static_cast<uint16_t>(v); };
  switch (layout) {
    case PixelLayout::kMono10p:  // 4 pixels, 40 bits, least significant first
      p[0] = u(b[0] | (b[1] & 0x03u) << 8);
      p[1] = u(b[1] >> 2 | (b[2] & 0x0Fu) << 6);
      p[2] = u(b[2] >> 4 | (b[3] & 0x3Fu) << 4);
      p[3] = u(b[3] >> 6 | b[4] << 2);
      break;
    case PixelLayout::kMono12p:  // 2 pixels, 24 bits, least significant first
      p[0] = u(b[0] | (b[1] & 0x0Fu) << 8);
      p[1] = u(b[1] >> 4 | b[2] << 4);
      break;
    case PixelLayout::kMono10Packed:  // high 8 bits outside, low 2 bits at 0-1 and 4-5
      p[0] = u(b[0] << 2 | (b[1] & 0x03u));
      p[1] = u(b[2] << 2 | (b[1] >> 4 & 0x03u));
      break;
    default:  // kMono12Packed: high 8 bits outside, low 4 bits in the nibbles
      p[0] = u(b[0] << 4 | (b[1] & 0x0Fu));
      p[1] = u(b[2] << 4 | b[1] >> 4);
      break;
  }
}
Result<cv::Mat> unpackMono(const cv::Mat& raw, PixelLayout layout) {
  const Packing packing = packingOf(layout);
  if (raw.type() != CV_8UC1 || raw.cols % packing.bytes != 0) {
    return mismatch(
        layout, raw,
        packing.bytes == 5 ? "CV_8UC1 rows of 5-byte groups" : "CV_8UC1 rows of 3-byte groups");
  }
  const int groups = raw.cols / packing.bytes;
  cv::Mat out(raw.rows, groups * packing.pixels, CV_16UC1);
  for (int y = 0; y < raw.rows; ++y) {
    const uint8_t* in = raw.ptr<uint8_t>(y);
    uint16_t* o = out.ptr<uint16_t>(y);
    for (int g = 0; g < groups; ++g) {
      unpackGroup(layout, in + g * packing.bytes, o + g * packing.pixels);
    }
  }
  return out;
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

Result<cv::Mat> decodeJpeg(const cv::Mat& raw, bool mono) {
  if (raw.type() != CV_8UC1 || !raw.isContinuous() || raw.empty()) {
    return mismatch(PixelLayout::kMJPEG, raw, "one continuous row of bytes");
  }
  // Tables put in where the camera left them out, padding cut off.
  const Result<cv::Mat> jpeg = completeMjpegFrame(raw);
  if (!jpeg) return jpeg.error();
  // Decoding to grey skips the colour planes entirely (libjpeg reads Y only).
  cv::Mat out = picksight::codecs::imdecode(*jpeg, mono ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
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
    case PixelLayout::kMono10p:
    case PixelLayout::kMono12p:
    case PixelLayout::kMono10Packed:
    case PixelLayout::kMono12Packed: {
      const Result<cv::Mat> words = unpackMono(raw, layout);
      if (!words) return words;
      const bool ten = layout == PixelLayout::kMono10p || layout == PixelLayout::kMono10Packed;
      return convert(*words, ten ? PixelLayout::kMono10 : PixelLayout::kMono12, mono);
    }
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
    case PixelLayout::kBayerGB8:
    case PixelLayout::kBayerRG10:
    case PixelLayout::kBayerGR10:
    case PixelLayout::kBayerBG10:
    case PixelLayout::kBayerGB10:
    case PixelLayout::kBayerRG12:
    case PixelLayout::kBayerGR12:
    case PixelLayout::kBayerBG12:
    case PixelLayout::kBayerGB12:
    case PixelLayout::kBayerRG16:
    case PixelLayout::kBayerGR16:
    case PixelLayout::kBayerBG16:
    case PixelLayout::kBayerGB16: {
      const BayerInfo info = *bayerInfo(layout);
      const bool wide = info.max > 255;
      if (raw.type() != (wide ? CV_16UC1 : CV_8UC1) || raw.cols < 2 || raw.rows < 2) {
        return mismatch(layout, raw, wide ? "CV_16UC1, at least 2x2" : "CV_8UC1, at least 2x2");
      }
      // Scaled to 8 bits first: demosaicing is linear, and an 8-bit mosaic
      // is a third of the work of a 16-bit one.
      cv::Mat mosaic = raw;
      if (wide) raw.convertTo(mosaic, CV_8U, 255.0 / info.max);
      const BayerCodes codes = bayerCodes(info.pattern);
      cv::cvtColor(mosaic, out, mono ? codes.to_gray : codes.to_bgr);
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
    case PixelLayout::kMono10p:
      return "Mono10p";
    case PixelLayout::kMono12p:
      return "Mono12p";
    case PixelLayout::kMono10Packed:
      return "Mono10Packed";
    case PixelLayout::kMono12Packed:
      return "Mono12Packed";
    case PixelLayout::kBayerRG10:
      return "BayerRG10";
    case PixelLayout::kBayerGR10:
      return "BayerGR10";
    case PixelLayout::kBayerBG10:
      return "BayerBG10";
    case PixelLayout::kBayerGB10:
      return "BayerGB10";
    case PixelLayout::kBayerRG12:
      return "BayerRG12";
    case PixelLayout::kBayerGR12:
      return "BayerGR12";
    case PixelLayout::kBayerBG12:
      return "BayerBG12";
    case PixelLayout::kBayerGB12:
      return "BayerGB12";
    case PixelLayout::kBayerRG16:
      return "BayerRG16";
    case PixelLayout::kBayerGR16:
      return "BayerGR16";
    case PixelLayout::kBayerBG16:
      return "BayerBG16";
    case PixelLayout::kBayerGB16:
      return "BayerGB16";
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
