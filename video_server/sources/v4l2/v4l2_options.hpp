// The options of a "v4l2:" source string and their parser.
#pragma once

#include <cstdint>
#include <string>

#include "picksight/common/result.hpp"

namespace picksight::video {

// What "v4l2:" asks for: "/dev/video0?width=1280&height=720&format=mjpeg&fps=30&buffers=4".
// width and height (both or neither): the frame size; the nearest the device
// offers when it has not this one. format: yuyv, mjpeg, uyvy, grey, y16,
// rgb24, bgr24 or a Bayer order (rggb, grbg, bggr, gbrg); without it YUYV,
// else MJPEG, is chosen at that size, MJPEG first when only it reaches the
// requested fps. fps: the initial frame rate, which the camera's own
// frame-rate setting then overrides only when it changes at run time.
// buffers: mmap buffers to request (2..32, default 4; the driver may grant another count).
// skip: frames dropped after every start of streaming (0..100, default 3):
// a webcam's first frames come before its automatic exposure settles.
struct V4l2Options {
  std::string path;
  int width = 0;
  int height = 0;
  uint32_t fourcc = 0;  // 0 = choose
  double fps = 0;       // 0 = the camera's setting
  int buffers = 4;
  int skip = 3;
};

// The error names the key or value that is wrong.
Result<V4l2Options> parseV4l2Options(const std::string& text);

}  // namespace picksight::video
