// The pixel formats the V4L2 driver streams: fourcc, the URI's format= name,
// the layout published and how a buffer maps onto an image.
#pragma once

#include <linux/videodev2.h>

#include <cstdint>
#include <string>

#include "picksight/sources/source.hpp"

namespace picksight::video {

struct V4l2PixelFormat {
  uint32_t fourcc;
  const char* option;  // the URI's format= value
  PixelLayout layout;
  int cv_type;  // -1: compressed, one row of bytesused bytes
};

// In order of preference when the URI names no format: YUYV is exact and
// cheap; MJPEG is what USB 2 webcams need for large sizes at full rate.
inline constexpr V4l2PixelFormat kV4l2PixelFormats[] = {
    {V4L2_PIX_FMT_YUYV, "yuyv", PixelLayout::kYUYV, CV_8UC2},
    {V4L2_PIX_FMT_MJPEG, "mjpeg", PixelLayout::kMJPEG, -1},
    {V4L2_PIX_FMT_JPEG, "jpeg", PixelLayout::kMJPEG, -1},
    {V4L2_PIX_FMT_UYVY, "uyvy", PixelLayout::kUYVY, CV_8UC2},
    {V4L2_PIX_FMT_GREY, "grey", PixelLayout::kMono8, CV_8UC1},
    {V4L2_PIX_FMT_Y16, "y16", PixelLayout::kMono16, CV_16UC1},
    {V4L2_PIX_FMT_Y12, "y12", PixelLayout::kMono12, CV_16UC1},
    {V4L2_PIX_FMT_Y10, "y10", PixelLayout::kMono10, CV_16UC1},
    {V4L2_PIX_FMT_BGR24, "bgr24", PixelLayout::kBGR8, CV_8UC3},
    {V4L2_PIX_FMT_RGB24, "rgb24", PixelLayout::kRGB8, CV_8UC3},
    // V4L2 names Bayer orders like GenICam: by the first row's first two pixels.
    {V4L2_PIX_FMT_SRGGB8, "rggb", PixelLayout::kBayerRG8, CV_8UC1},
    {V4L2_PIX_FMT_SGRBG8, "grbg", PixelLayout::kBayerGR8, CV_8UC1},
    {V4L2_PIX_FMT_SBGGR8, "bggr", PixelLayout::kBayerBG8, CV_8UC1},
    {V4L2_PIX_FMT_SGBRG8, "gbrg", PixelLayout::kBayerGB8, CV_8UC1},
};

// The entry for a fourcc; null for one the driver cannot stream.
const V4l2PixelFormat* findPixelFormat(uint32_t fourcc);
// Position in the preference order; past the end for an unknown fourcc.
int pixelFormatRank(uint32_t fourcc);
// "YUYV", "MJPG"...: the fourcc's characters, spaces dropped.
std::string fourccName(uint32_t fourcc);

}  // namespace picksight::video
