// Test parts of any outline drawn on a grey canvas: look-alike pairs the
// scene generator's fixed types cannot make (a hole more or less, a size a
// few percent off, a small off-axis notch), anti-aliased by supersampling,
// blurred and noisy like a camera image.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "picksight/synthetic/scene.hpp"

namespace picksight::test {

using Loop = std::vector<cv::Point2d>;

inline Loop rectLoop(double width, double height, cv::Point2d centre = {0, 0}) {
  const double a = width / 2;
  const double b = height / 2;
  return {centre + cv::Point2d(-a, -b), centre + cv::Point2d(a, -b), centre + cv::Point2d(a, b),
          centre + cv::Point2d(-a, b)};
}

inline Loop circleLoop(double radius, cv::Point2d centre = {0, 0}, int points = 96) {
  Loop loop;
  for (int i = 0; i < points; ++i) {
    const double a = 2 * M_PI * i / points;
    loop.push_back(centre + cv::Point2d(radius * std::cos(a), radius * std::sin(a)));
  }
  return loop;
}

// The shape moved so that its area centroid is the origin (the pose of a
// drawn part is then its centroid, as the recognizer reports it).
inline synthetic::Shape centred(synthetic::Shape shape) {
  const synthetic::ShapeMoments m = synthetic::shapeMoments(shape);
  for (auto& loop : shape.loops) {
    for (auto& p : loop) p -= cv::Point2d(m.cx, m.cy);
  }
  return shape;
}

// Scaled by `fx` along x and `fy` along y (a part longer, not larger).
inline synthetic::Shape scaled(synthetic::Shape shape, double fx, double fy) {
  for (auto& loop : shape.loops) {
    for (auto& p : loop) p = {p.x * fx, p.y * fy};
  }
  return shape;
}

inline synthetic::Shape scaled(synthetic::Shape shape, double factor) {
  return scaled(std::move(shape), factor, factor);
}

struct DrawnPart {
  synthetic::Shape shape;  // centred
  double x = 0;
  double y = 0;
  double angle_deg = 0;
  bool mirrored = false;  // y -> -y in the part's frame before the turn
};

// Dark parts (45) on a lit background (200), each pixel darkened by the part's
// area over it (4 x 4 supersampling), blurred by sigma 0.7 px and with
// Gaussian noise of sigma 3 grey levels drawn from `seed`.
inline cv::Mat drawParts(int width, int height, const std::vector<DrawnPart>& parts,
                         uint64_t seed) {
  constexpr int kScale = 4;
  constexpr int kShift = 4;  // fractional bits of the polygon corners
  cv::Mat fine(height * kScale, width * kScale, CV_8UC1, cv::Scalar(200));
  for (const auto& part : parts) {
    synthetic::Shape shape = part.shape;
    if (part.mirrored) {
      for (auto& loop : shape.loops) {
        for (auto& p : loop) p.y = -p.y;
      }
    }
    const synthetic::Shape placed = synthetic::placedShape(shape, part.x, part.y, part.angle_deg);
    for (size_t k = 0; k < placed.loops.size(); ++k) {
      // Pixel (u, v) of the image covers [u - 0.5, u + 0.5]: fine pixel
      // kScale u covers its first kScale-th.
      std::vector<cv::Point> polygon;
      for (const auto& q : placed.loops[k]) {
        polygon.emplace_back(
            static_cast<int>(std::lround(((q.x + 0.5) * kScale - 0.5) * (1 << kShift))),
            static_cast<int>(std::lround(((q.y + 0.5) * kScale - 0.5) * (1 << kShift))));
      }
      cv::fillPoly(fine, std::vector<std::vector<cv::Point>>{polygon},
                   cv::Scalar(k == 0 ? 45 : 200), cv::LINE_8, kShift);
    }
  }
  cv::Mat grey;
  cv::resize(fine, grey, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(grey, grey, cv::Size(0, 0), 0.7);
  cv::Mat noise(height, width, CV_16SC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::Mat out;
  cv::add(grey, noise, out, cv::noArray(), CV_8U);
  return out;
}

// The plate with a hole and the long bar the vision app's end-to-end tests
// teach: two types no test confuses (about 22000 and 15600 px).
inline const synthetic::Shape kPlate{{rectLoop(200, 120), circleLoop(25, {45, 0})}};
inline const synthetic::Shape kBar{{rectLoop(260, 60)}};

// `shape` alone in the middle of a 640 x 480 frame, turned by `angle_deg`.
inline cv::Mat aloneInFrame(const synthetic::Shape& shape, double angle_deg = 0) {
  return drawParts(640, 480, {{shape, 320, 240, angle_deg}}, 11);
}

// `count` parts of `shape` in a row of cells 180 px apart, turned by
// different angles (every other one mirrored when `alternate_mirror`).
inline std::vector<DrawnPart> partRow(const synthetic::Shape& shape, int count, double y,
                                      double first_angle, bool alternate_mirror = false,
                                      double x0 = 100) {
  std::vector<DrawnPart> row;
  for (int i = 0; i < count; ++i) {
    row.push_back({shape, x0 + 180.0 * i, y, std::fmod(first_angle + 73.7 * i, 360.0),
                   alternate_mirror && i % 2 == 1});
  }
  return row;
}

}  // namespace picksight::test
