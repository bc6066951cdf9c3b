// Converts image files' depths and channel counts to 8-bit mono or BGR.
#include "eight_bit_image.hpp"

#include <opencv2/imgproc.hpp>

namespace picksight::video {

cv::Mat toEightBit(const cv::Mat& in) {
  cv::Mat eight;
  if (in.depth() == CV_16U) {
    in.convertTo(eight, CV_8U, 1.0 / 257.0);
  } else if (in.depth() != CV_8U) {
    cv::normalize(in, eight, 0, 255, cv::NORM_MINMAX, CV_8U);
  } else {
    eight = in;
  }
  if (eight.channels() == 4) {
    cv::Mat bgr;
    cv::cvtColor(eight, bgr, cv::COLOR_BGRA2BGR);
    return bgr;
  }
  return eight;
}

}  // namespace picksight::video
