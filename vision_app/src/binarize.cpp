// Binarization. The adaptive method divides out the illumination: it
// estimates the lit background at low resolution (a maximum filter wider than
// any part erases the dark parts, a blur smooths it), finds with Otsu the
// ratio part/background that separates the two populations, and compares
// every pixel with that ratio of its local background. All heavy work is at
// 1/8 resolution; the full-resolution cost is one resize and one compare.
#include "picksight/vision/binarize.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace picksight::vision {
namespace {
constexpr int kReduce = 8;
// Limits of the part/background ratio. Above the upper one, the "parts"
// Otsu finds are sensor noise on an empty field; below the lower one, the
// contrast estimate is unreliable.
constexpr double kMaxRatio = 0.85;
constexpr double kMinRatio = 0.25;

cv::Mat adaptive(const cv::Mat& grey, int window) {
  const int reduce = std::min({kReduce, std::max(1, grey.cols / 16), std::max(1, grey.rows / 16)});
  cv::Mat small;
  cv::resize(grey, small, cv::Size(std::max(1, grey.cols / reduce), std::max(1, grey.rows / reduce)), 0, 0,
             cv::INTER_AREA);
  if (window <= 0) window = std::min(grey.cols, grey.rows) / 6;
  const int k = std::max(3, (window / reduce) | 1);
  cv::Mat background;
  cv::dilate(small, background, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)), cv::Point(-1, -1), 1,
             cv::BORDER_REPLICATE);
  cv::blur(background, background, cv::Size(k, k), cv::Point(-1, -1), cv::BORDER_REPLICATE);

  // Ratio image at low resolution, 200 = background level.
  cv::Mat small_f;
  cv::Mat background_f;
  small.convertTo(small_f, CV_32F);
  background.convertTo(background_f, CV_32F);
  cv::Mat ratio;
  cv::divide(small_f, cv::max(background_f, 1.0f), ratio, 200.0);
  cv::Mat ratio8;
  ratio.convertTo(ratio8, CV_8U);
  cv::Mat upper;
  const double otsu = cv::threshold(ratio8, upper, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  // Otsu's level is the first of a flat optimum: with two clean populations it
  // sits on the edge of the darker one. Split halfway between the two class
  // means instead, where noise on either side is least likely to cross.
  double k_ratio = kMaxRatio;
  const int bright = cv::countNonZero(upper);
  if (bright > 0 && bright < upper.rows * upper.cols) {
    const double mean_bright = cv::mean(ratio8, upper)[0];
    const double mean_dark = cv::mean(ratio8, ~upper)[0];
    k_ratio = std::clamp(0.5 * (mean_bright + mean_dark) / 200.0, kMinRatio, kMaxRatio);
  } else {
    k_ratio = std::clamp(otsu / 200.0, kMinRatio, kMaxRatio);
  }

  cv::Mat threshold_small;
  background.convertTo(threshold_small, CV_8U, k_ratio);
  cv::Mat threshold_full;
  cv::resize(threshold_small, threshold_full, grey.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat mask;
  cv::compare(grey, threshold_full, mask, cv::CMP_LT);
  return mask;
}
}  // namespace

cv::Mat binarize(const cv::Mat& grey, const BinarizeOptions& options) {
  CV_Assert(grey.type() == CV_8UC1);
  // Light parts on a dark background are dark parts on a light one, inverted.
  // (A fresh Mat: inverting into a header that shares `grey` would write
  // into the caller's frame.)
  cv::Mat input;
  if (options.polarity == Polarity::kLightOnDark) {
    cv::bitwise_not(grey, input);
  } else {
    input = grey;
  }
  cv::Mat mask;
  switch (options.method) {
    case ThresholdMethod::kFixed: {
      const int t = options.polarity == Polarity::kLightOnDark ? 255 - options.fixed_threshold
                                                                : options.fixed_threshold;
      cv::threshold(input, mask, t, 255, cv::THRESH_BINARY_INV);
      break;
    }
    case ThresholdMethod::kOtsu:
      cv::threshold(input, mask, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
      break;
    case ThresholdMethod::kAdaptive:
      mask = adaptive(input, options.adaptive_window);
      break;
  }
  return mask;
}

}  // namespace picksight::vision
