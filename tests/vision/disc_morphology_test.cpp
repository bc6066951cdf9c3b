// Disc dilation and erosion against OpenCV's own, pixel for pixel: random
// masks and grey images, every radius from 0 to 9, boxes smaller than the
// disc, views into larger images (whose neighbours OpenCV reads) and
// results written in place.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>

#include "picksight/vision/segmentation/disc_morphology.hpp"

namespace pv = picksight::vision;

namespace {
// Discs, bars and speckle on a black image, some cut by its edges; or
// random grey levels (a morphology of any levels, not only masks).
cv::Mat randomImage(std::mt19937& rng, int width, int height, bool grey) {
  cv::Mat image(height, width, CV_8UC1, cv::Scalar(0));
  if (grey) {
    cv::randu(image, 0, 256);
    return image;
  }
  std::uniform_int_distribution<int> x(-8, width + 8);
  std::uniform_int_distribution<int> y(-8, height + 8);
  std::uniform_int_distribution<int> size(1, 30);
  std::uniform_int_distribution<int> kind(0, 2);
  for (int i = 0; i < 10; ++i) {
    const cv::Point p(x(rng), y(rng));
    const int s = size(rng);
    switch (kind(rng)) {
      case 0:
        cv::circle(image, p, s, cv::Scalar(255), cv::FILLED);
        break;
      case 1:
        cv::line(image, p, p + cv::Point(s, s / 2), cv::Scalar(255), 1 + s % 3);
        break;
      default: {
        std::uniform_int_distribution<int> in_x(0, width - 1);
        std::uniform_int_distribution<int> in_y(0, height - 1);
        for (int k = 0; k < 3 * s; ++k) image.at<uint8_t>(in_y(rng), in_x(rng)) = 255;
      }
    }
  }
  return image;
}

// A random rectangle of the image (the whole of an image too small for
// one).
cv::Rect randomView(std::mt19937& rng, const cv::Mat& image) {
  if (image.cols <= 2 || image.rows <= 2) return {0, 0, image.cols, image.rows};
  cv::Rect view;
  view.x = std::uniform_int_distribution<int>(0, image.cols - 2)(rng);
  view.y = std::uniform_int_distribution<int>(0, image.rows - 2)(rng);
  view.width = std::uniform_int_distribution<int>(1, image.cols - view.x)(rng);
  view.height = std::uniform_int_distribution<int>(1, image.rows - view.y)(rng);
  return view;
}

// The canvas's pixels outside its centre (src's size, 2 px in) are 7 still:
// a result written into a view stays in it.
bool borderUntouched(const cv::Mat& canvas) {
  return canvas.at<uint8_t>(0, 0) == 7 && canvas.at<uint8_t>(canvas.rows - 1, canvas.cols - 1) == 7;
}

int differing(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return -1;
  return cv::countNonZero(a != b);
}

// f(image, image, radius) on a copy of src, in place: its pixels differing
// from `expected`.
template <class F>
int differingInPlace(const cv::Mat& src, int radius, F f, const cv::Mat& expected) {
  cv::Mat in_place = src.clone();
  f(in_place, in_place, radius);
  return differing(in_place, expected);
}

// f(src, view, radius) into a view of src's size in a larger image of 7s:
// its pixels differing from `expected`, or -2 when it wrote outside the
// view.
template <class F>
int differingIntoView(const cv::Mat& src, int radius, F f, const cv::Mat& expected) {
  cv::Mat canvas(src.rows + 4, src.cols + 4, CV_8UC1, cv::Scalar(7));
  cv::Mat into = canvas(cv::Rect(2, 2, src.cols, src.rows));
  f(src, into, radius);
  if (!borderUntouched(canvas)) return -2;
  return differing(canvas(cv::Rect(2, 2, src.cols, src.rows)), expected);
}
}  // namespace

TEST_CASE("a disc's dilation and erosion are OpenCV's to the last pixel",
          "[vision][segmentation]") {
  std::mt19937 rng(20261207);
  std::uniform_int_distribution<int> side(1, 90);
  int compared = 0;
  for (int radius = 0; radius <= 9; ++radius) {
    const cv::Mat element = pv::discElement(radius);
    for (int trial = 0; trial < 24; ++trial) {
      const bool grey = trial % 4 == 3;
      const cv::Mat image = randomImage(rng, side(rng), side(rng), grey);
      // The whole image, and a view into it (OpenCV reads the view's
      // neighbours in the larger image, up to the disc's reach).
      const cv::Rect view =
          trial % 2 == 1 ? randomView(rng, image) : cv::Rect(0, 0, image.cols, image.rows);
      const cv::Mat src = image(view);
      std::ostringstream what;
      what << "radius " << radius << ", " << image.cols << "x" << image.rows << " view " << view
           << (grey ? " grey" : " mask");
      INFO(what.str());
      cv::Mat expected;
      cv::Mat got;
      cv::dilate(src, expected, element);
      pv::dilateDisc(src, got, radius);
      CHECK(differing(got, expected) == 0);
      cv::erode(src, expected, element);
      pv::erodeDisc(src, got, radius);
      CHECK(differing(got, expected) == 0);
      // In place, as `cv::erode(rest, rest, ...)` is written (a copy reads
      // no neighbours), and into a view of a larger image: written there.
      cv::dilate(src.clone(), expected, element);
      CHECK(differingInPlace(src, radius, pv::dilateDisc, expected) == 0);
      cv::erode(src, expected, element);
      CHECK(differingIntoView(src, radius, pv::erodeDisc, expected) == 0);
      ++compared;
    }
  }
  CHECK(compared == 240);
}

TEST_CASE("a mask's dilation and erosion on rows of bits are OpenCV's to the last pixel",
          "[vision][segmentation]") {
  std::mt19937 rng(20261208);
  // Up to 200 columns: rows of one to four 64-pixel words, runs crossing
  // from one word into the next.
  std::uniform_int_distribution<int> side(1, 200);
  int compared = 0;
  // The elements' runs are kept for radii up to 16 and made afresh beyond.
  for (const int radius : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 16, 17, 23}) {
    const cv::Mat element = pv::discElement(radius);
    for (int trial = 0; trial < 24; ++trial) {
      cv::Mat image = randomImage(rng, side(rng), side(rng), false);
      // Any non-zero value is set; OpenCV's answer is read as such.
      if (trial % 3 == 2) image.setTo(cv::Scalar(1), image);
      const cv::Rect view =
          trial % 2 == 1 ? randomView(rng, image) : cv::Rect(0, 0, image.cols, image.rows);
      const cv::Mat src = image(view);
      // OpenCV's answer on the same view of the image as 0 and 255 (a view:
      // its neighbours read as they are).
      const cv::Mat binary = image != 0;
      const cv::Mat set = binary(view);
      std::ostringstream what;
      what << "radius " << radius << ", " << image.cols << "x" << image.rows << " view " << view;
      INFO(what.str());
      cv::Mat expected;
      cv::Mat got;
      cv::dilate(set, expected, element);
      pv::dilateMask(src, got, radius);
      CHECK(differing(got, expected) == 0);
      cv::erode(set, expected, element);
      pv::erodeMask(src, got, radius);
      CHECK(differing(got, expected) == 0);
      // In place, and into a view of a larger image.
      cv::dilate(set.clone(), expected, element);
      CHECK(differingInPlace(src, radius, pv::dilateMask, expected) == 0);
      cv::erode(set.clone(), expected, element);
      CHECK(differingInPlace(src, radius, pv::erodeMask, expected) == 0);
      cv::dilate(set, expected, element);
      CHECK(differingIntoView(src, radius, pv::dilateMask, expected) == 0);
      ++compared;
    }
  }
  CHECK(compared == 312);
}
