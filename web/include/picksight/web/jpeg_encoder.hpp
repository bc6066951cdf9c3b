// JPEG encoding of frames with libjpeg-turbo, for the MJPEG streams and
// /frame: mono8 frames become greyscale JPEGs, bgr8 ones colour.
//
// Threading: an encoder owns a turbojpeg handle and is used by one thread at
// a time (CameraFeed keeps one per camera, under its encode lock).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {

class JpegEncoder {
 public:
  explicit JpegEncoder(int quality = 80);
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  // The JPEG file of a CV_8UC1 or CV_8UC3 (BGR) image.
  Result<std::string> encode(const cv::Mat& image);

 private:
  void* handle_ = nullptr;  // tjhandle
  int quality_;
};

}  // namespace picksight::web
