// Two regions compared field by field, to the bit: what a change that must
// not move anything (a neighbour's speck, the number of threads) is checked
// with.
#pragma once

#include <catch2/catch.hpp>

#include <opencv2/core.hpp>

#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::test {

// Every field of two regions, to the bit (== on doubles, on purpose).
inline void checkSameRegion(const vision::Region& a, const vision::Region& b) {
  CHECK(a.area == b.area);
  CHECK(a.centroid == b.centroid);
  CHECK(a.angle_deg == b.angle_deg);
  CHECK(a.elongation == b.elongation);
  CHECK(a.holes == b.holes);
  CHECK(a.bbox == b.bbox);
  CHECK(a.touches_border == b.touches_border);
  CHECK(a.moments.m00 == b.moments.m00);
  CHECK(a.moments.m10 == b.moments.m10);
  CHECK(a.moments.m01 == b.moments.m01);
  CHECK(a.moments.mu20 == b.moments.mu20);
  CHECK(a.moments.mu11 == b.moments.mu11);
  CHECK(a.moments.mu02 == b.moments.mu02);
  CHECK(a.moments.mu30 == b.moments.mu30);
  CHECK(a.moments.mu03 == b.moments.mu03);
  CHECK(a.outer == b.outer);
  CHECK(a.hole_boundaries == b.hole_boundaries);
  CHECK(a.coverage_origin == b.coverage_origin);
  REQUIRE(a.coverage.size() == b.coverage.size());
  CHECK(cv::norm(a.coverage, b.coverage, cv::NORM_INF) == 0);
  CHECK(cv::countNonZero(a.covered.toMask() != b.covered.toMask()) == 0);
}

}  // namespace picksight::test
