// Two parts lying across each other (silhouettes: where they overlap, each
// one's outline is hidden inside the other): both are found, though they
// share a quarter of their area, and nothing else is reported.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "drawn_parts.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

using namespace picksight::vision;
namespace pt = picksight::test;
namespace ps = picksight::synthetic;

namespace {
// A 240 x 80 bar with a bore near one end (so that it has one orientation).
ps::Shape bar() {
  return pt::centred(ps::Shape{{pt::rectLoop(240, 80), pt::circleLoop(12, {-70, 0})}});
}

cv::Point2d turned(cv::Point2d p, double deg) {
  const double a = deg * M_PI / 180;
  return {std::cos(a) * p.x - std::sin(a) * p.y, std::sin(a) * p.x + std::cos(a) * p.y};
}
}  // namespace

TEST_CASE(
    "two bars lying across each other are both found though they share a quarter of "
    "their area",
    "[vision][locator][overlap]") {
  const cv::Mat alone = pt::drawParts(400, 300, {{bar(), 200.3, 149.6, 17, false}}, 5);
  auto trained = trainModel(alone, 1, "bar", {});
  REQUIRE(trained.ok());
  const PartModel model = trained.value();
  // In the first bar's frame: the second bar stands across its bore-free
  // end, the two overlapping on 65 x 75 px (25 % of each bar's area) and
  // each hiding 140 of the other's 640 px of outline (22 %), the bores
  // clear of the overlap.
  const cv::Point2d across(95, 85);
  const cv::Point2d centre(500, 330);
  for (const double deg : {7.0, 100.0, 215.0}) {
    INFO("turned " << deg);
    const cv::Point2d second = centre + turned(across, deg);
    const std::vector<pt::DrawnPart> parts{{bar(), centre.x, centre.y, deg, false},
                                           {bar(), second.x, second.y, deg - 90, false}};
    const cv::Mat grey = pt::drawParts(1000, 700, parts, 21);
    const auto regions = findRegions(binarize(grey, {}), {}, grey);
    REQUIRE(regions.size() == 1);  // one blob: the locator of touching parts is asked
    const auto matches = recognize(regions, {&model});
    CHECK(matches.size() == 2);
    for (const auto& part : parts) {
      INFO("bar at " << part.x << ", " << part.y << " turned " << part.angle_deg);
      const auto found = std::count_if(matches.begin(), matches.end(), [&](const Match& m) {
        return std::hypot(m.centroid.x - part.x, m.centroid.y - part.y) < 1.0 &&
               std::abs(std::remainder(m.angle_deg - (part.angle_deg - 17), 360.0)) < 1.0;
      });
      CHECK(found == 1);
    }
  }
}
