// Region features against values computed by hand or in closed form.
#include <catch2/catch.hpp>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "picksight/common/angles.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "same_region.hpp"

using picksight::angleDiffDeg;
using picksight::vision::findRegions;
using picksight::vision::Region;

namespace {
// Parts drawn 8x larger and averaged down, as a camera sees them (edge pixels
// partly covered), with the centroid and axis of what was drawn from the
// moments of the 8x drawing. drawL: an L shape (long leg 120, short leg 70,
// thickness 30) turned by `deg` about (200, 200), optionally mirrored.
struct Drawn {
  cv::Mat grey;  // by default a dark part (50) on a light background (220)
  cv::Point2d centroid;
  double axis_deg = 0;  // axis of least inertia, modulo 180
};

struct Look {
  double part = 50;
  double background = 220;
  // Light falling unevenly: every level times 1 + slope . (p - (200, 200)).
  cv::Vec2d light_slope{0, 0};
};

// The polygon `local` (its own axes, about (45, 25)) turned by `deg` about
// `centre`, optionally mirrored, in a 400x400 image.
Drawn drawShape(const std::vector<cv::Point2d>& local, double deg, bool mirrored,
                cv::Point2d centre = {200, 200}, Look look = {}) {
  constexpr int kSuper = 8;
  const double a = deg * M_PI / 180.0;
  std::vector<cv::Point> pts;
  for (auto p : local) {
    p -= cv::Point2d(45, 25);
    if (mirrored) p.y = -p.y;
    const double x = centre.x + p.x * std::cos(a) - p.y * std::sin(a);
    const double y = centre.y + p.x * std::sin(a) + p.y * std::cos(a);
    // Pixel centres at integers at both scales: u = (x + 0.5) * S - 0.5.
    pts.emplace_back(static_cast<int>(std::lround(((x + 0.5) * kSuper - 0.5) * 256)),
                     static_cast<int>(std::lround(((y + 0.5) * kSuper - 0.5) * 256)));
  }
  cv::Mat big(400 * kSuper, 400 * kSuper, CV_8UC1, cv::Scalar(0));
  cv::fillPoly(big, std::vector<std::vector<cv::Point>>{pts}, cv::Scalar(255), cv::LINE_8, 8);
  Drawn d;
  cv::Mat coverage;
  cv::resize(big, coverage, cv::Size(400, 400), 0, 0, cv::INTER_AREA);
  cv::Mat level;
  coverage.convertTo(level, CV_32F, (look.part - look.background) / 255.0, look.background);
  for (int y = 0; y < level.rows; ++y) {
    float* v = level.ptr<float>(y);
    for (int x = 0; x < level.cols; ++x) {
      v[x] *=
          static_cast<float>(1 + look.light_slope[0] * (x - 200) + look.light_slope[1] * (y - 200));
    }
  }
  level.convertTo(d.grey, CV_8U);
  const cv::Moments m = cv::moments(big, true);
  d.centroid =
      cv::Point2d((m.m10 / m.m00 + 0.5) / kSuper - 0.5, (m.m01 / m.m00 + 0.5) / kSuper - 0.5);
  d.axis_deg = 0.5 * std::atan2(2 * m.mu11, m.mu20 - m.mu02) * 180.0 / M_PI;
  return d;
}

Drawn drawL(double deg, bool mirrored, Look look = {}) {
  return drawShape({{0, 0}, {120, 0}, {120, 30}, {30, 30}, {30, 70}, {0, 70}}, deg, mirrored,
                   {200, 200}, look);
}

// The regions of a drawing, the mask cut half way between part and
// background, whichever is darker.
std::vector<Region> regionsOf(const Drawn& d, bool use_grey, Look look = {}) {
  const double middle = (look.part + look.background) / 2;
  const cv::Mat mask = look.part < look.background ? d.grey < middle : d.grey > middle;
  return findRegions(mask, {}, use_grey ? d.grey : cv::Mat());
}
}  // namespace

TEST_CASE("rectangle moments match the closed form", "[vision][regions]") {
  cv::Mat img(100, 100, CV_8UC1, cv::Scalar(0));
  img(cv::Rect(10, 20, 50, 20)).setTo(255);
  const auto regions = findRegions(img);
  REQUIRE(regions.size() == 1);
  const Region& r = regions[0];
  CHECK(r.area == 1000);
  CHECK(r.centroid.x == Approx(34.5));
  CHECK(r.centroid.y == Approx(29.5));
  // sum over a run of n pixels of (k - mean)^2 = n (n^2 - 1) / 12
  CHECK(r.moments.mu20 == Approx(20 * 50 * (50 * 50 - 1) / 12.0));
  CHECK(r.moments.mu02 == Approx(50 * 20 * (20 * 20 - 1) / 12.0));
  CHECK(r.moments.mu11 == Approx(0).margin(1e-6));
  CHECK(r.holes == 0);
  CHECK(r.bbox == cv::Rect(10, 20, 50, 20));
  // The long axis is x; a rectangle's direction along it is ambiguous.
  CHECK(angleDiffDeg(r.angle_deg, 0, 180) < 1e-9);
}

TEST_CASE("holes are counted and regions come largest first", "[vision][regions]") {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {80, 80}, 50, cv::Scalar(255), cv::FILLED);
  cv::circle(img, {70, 80}, 10, cv::Scalar(0), cv::FILLED);
  cv::circle(img, {100, 80}, 8, cv::Scalar(0), cv::FILLED);
  cv::rectangle(img, cv::Rect(200, 200, 30, 30), cv::Scalar(255), cv::FILLED);
  const auto regions = findRegions(img);
  REQUIRE(regions.size() == 2);
  CHECK(regions[0].holes == 2);
  CHECK(regions[0].hole_boundaries.size() == 2);
  CHECK(regions[1].holes == 0);
  CHECK(regions[0].area > regions[1].area);
  // A disc's area, less its holes, within the rasterization error.
  CHECK(regions[0].area == Approx(M_PI * (2500 - 100 - 64)).epsilon(0.02));
}

// Regions are traced, not labelled: a region's pixels are what its boundary
// encloses less its holes. A part lying in another's hole, or close enough
// that their boxes overlap, must count for itself alone.
TEST_CASE("a part in a hole and a close neighbour keep their own pixels", "[vision][regions]") {
  cv::Mat ring(300, 300, CV_8UC1, cv::Scalar(0));
  cv::circle(ring, {100, 100}, 50, cv::Scalar(255), cv::FILLED);
  cv::circle(ring, {100, 100}, 30, cv::Scalar(0), cv::FILLED);
  cv::Mat island(ring.size(), CV_8UC1, cv::Scalar(0));
  cv::circle(island, {100, 100}, 12, cv::Scalar(255), cv::FILLED);
  cv::Mat square(ring.size(), CV_8UC1, cv::Scalar(0));
  square(cv::Rect(153, 70, 20, 20)).setTo(255);  // 3 px right of the ring's box
  const cv::Mat img = ring | island | square;
  cv::Mat grey;
  img.convertTo(grey, CV_8U, -170.0 / 255.0, 220.0);
  for (const bool use_grey : {false, true}) {
    const auto regions = findRegions(img, {}, use_grey ? grey : cv::Mat());
    REQUIRE(regions.size() == 3);
    CHECK(regions[0].holes == 1);
    CHECK(regions[0].area == Approx(cv::countNonZero(ring)).epsilon(1e-3));
    CHECK(regions[0].centroid.x == Approx(100).margin(0.01));
    // Largest first: the island (441 px), then the square (400 px).
    CHECK(regions[1].area == Approx(cv::countNonZero(island)).epsilon(1e-3));
    CHECK(regions[2].area == Approx(cv::countNonZero(square)).epsilon(1e-3));
    CHECK(regions[2].bbox == cv::Rect(153, 70, 20, 20));
  }
}

TEST_CASE("a disc has no elongation, a bar has a lot", "[vision][regions]") {
  cv::Mat img(300, 300, CV_8UC1, cv::Scalar(0));
  cv::circle(img, {80, 80}, 60, cv::Scalar(255), cv::FILLED);
  cv::rectangle(img, cv::Rect(180, 50, 20, 200), cv::Scalar(255), cv::FILLED);
  const auto regions = findRegions(img);
  REQUIRE(regions.size() == 2);
  const Region& disc = regions[0].bbox.x < 150 ? regions[0] : regions[1];
  const Region& bar = regions[0].bbox.x < 150 ? regions[1] : regions[0];
  CHECK(disc.elongation < 0.01);
  CHECK(bar.elongation > 0.95);
  CHECK(angleDiffDeg(bar.angle_deg, 90, 180) < 1e-6);
}

TEST_CASE("small regions and regions cut by the border are left out", "[vision][regions]") {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(0));
  img(cv::Rect(0, 50, 40, 40)).setTo(255);    // touches the left edge
  img(cv::Rect(100, 100, 5, 5)).setTo(255);   // 25 px: noise
  img(cv::Rect(120, 20, 30, 30)).setTo(255);  // a part
  auto regions = findRegions(img);
  REQUIRE(regions.size() == 1);
  CHECK(regions[0].bbox == cv::Rect(120, 20, 30, 30));
  picksight::vision::RegionOptions keep;
  keep.keep_border_regions = true;
  keep.min_area = 10;
  regions = findRegions(img, keep);
  REQUIRE(regions.size() == 3);
  CHECK(regions[0].touches_border);
}

TEST_CASE("an L shape's angle follows its rotation over the full turn", "[vision][regions]") {
  const auto base = regionsOf(drawL(0, false), true);
  REQUIRE(base.size() == 1);
  for (double deg = 0; deg < 360; deg += 17.5) {
    const Drawn d = drawL(deg, false);
    const auto turned = regionsOf(d, true);
    REQUIRE(turned.size() == 1);
    INFO("rotation " << deg);
    CHECK(angleDiffDeg(turned[0].angle_deg, base[0].angle_deg + deg) < 0.1);
    CHECK(angleDiffDeg(turned[0].angle_deg, d.axis_deg, 180) < 0.1);
    CHECK(turned[0].centroid.x == Approx(d.centroid.x).margin(0.02));
    CHECK(turned[0].centroid.y == Approx(d.centroid.y).margin(0.02));
  }
}

TEST_CASE("a mirrored L shape turns the other way", "[vision][regions]") {
  const auto base = regionsOf(drawL(0, false), true);
  REQUIRE(base.size() == 1);
  for (double deg = 0; deg < 360; deg += 45) {
    const auto mirrored = regionsOf(drawL(deg, true), true);
    REQUIRE(mirrored.size() == 1);
    INFO("rotation " << deg);
    // Mirroring about the x axis maps an angle t to -t, then the turn adds.
    CHECK(angleDiffDeg(mirrored[0].angle_deg, -base[0].angle_deg + deg) < 0.1);
  }
}

// The direction along the axis is not a convention of the code under test:
// it points from the centroid towards the boundary point farthest from it,
// and angles turn clockwise on screen (image y grows downwards).
TEST_CASE("the angle points towards the far end of a part and turns clockwise on screen",
          "[vision][regions]") {
  // A 100x30 bar with a 30x6 spike at its right end: the far end is right.
  cv::Mat right(300, 300, CV_8UC1, cv::Scalar(0));
  right(cv::Rect(90, 135, 100, 30)).setTo(255);
  right(cv::Rect(190, 147, 30, 6)).setTo(255);
  const std::vector<std::pair<int, double>> turns = {{-1, 0},
                                                     {cv::ROTATE_90_CLOCKWISE, 90},
                                                     {cv::ROTATE_180, 180},
                                                     {cv::ROTATE_90_COUNTERCLOCKWISE, 270}};
  for (const auto& [turn, expected] : turns) {
    cv::Mat img;
    if (turn >= 0) {
      cv::rotate(right, img, turn);
    } else {
      img = right;
    }
    const auto regions = findRegions(img);
    REQUIRE(regions.size() == 1);
    INFO("expected " << expected << " got " << regions[0].angle_deg);
    CHECK(angleDiffDeg(regions[0].angle_deg, expected) < 1e-6);
  }
}

TEST_CASE("regions cut by any of the four borders are left out", "[vision][regions]") {
  cv::Mat img(200, 300, CV_8UC1, cv::Scalar(0));
  img(cv::Rect(0, 50, 40, 40)).setTo(255);     // left
  img(cv::Rect(100, 0, 40, 40)).setTo(255);    // top
  img(cv::Rect(260, 100, 40, 40)).setTo(255);  // right
  img(cv::Rect(200, 160, 40, 40)).setTo(255);  // bottom
  img(cv::Rect(120, 80, 30, 30)).setTo(255);   // the only whole part
  const auto regions = findRegions(img);
  REQUIRE(regions.size() == 1);
  CHECK(regions[0].bbox == cv::Rect(120, 80, 30, 30));
  CHECK_FALSE(regions[0].touches_border);
}

TEST_CASE("grey-level moments beat binary ones on diagonal edges for dark and light parts",
          "[vision][regions]") {
  // At 45 degrees every edge pixel of a side has the same coverage, so the
  // binary cut errs the same way all along the side. Dark parts on a lit
  // background (also at low contrast), light parts (the contrast changes
  // sign), and light parts on a black background, read additively (there is
  // no light to divide by, down to none at all): the grey centroid keeps its
  // accuracy in every case.
  for (const Look& look :
       {Look{50, 220}, Look{180, 220}, Look{240, 100}, Look{200, 5}, Look{220, 0}}) {
    INFO("part " << look.part << " on " << look.background);
    const Drawn d = drawL(315, false, look);
    const auto grey = regionsOf(d, true, look);
    const auto binary = regionsOf(d, false, look);
    REQUIRE(grey.size() == 1);
    REQUIRE(binary.size() == 1);
    const double grey_error = cv::norm(grey[0].centroid - d.centroid);
    const double binary_error = cv::norm(binary[0].centroid - d.centroid);
    CHECK(grey_error < 0.02);
    CHECK(binary_error > 5 * grey_error);
    // The L's area: 120 x 30 + 40 x 30 px (read 0.3 % high today).
    CHECK(grey[0].area == Approx(4800).epsilon(0.005));
  }
}

TEST_CASE("parts are placed under uneven light whichever is darker, part or background",
          "[vision][regions]") {
  // Light 8 % stronger on one side of the L than on the other (a lamp off to
  // one side). Both levels follow the light; each edge pixel is read between
  // the two as the light there gives them. Read against the background's
  // light alone (or, on a near-black background, against fixed levels), a
  // light part was placed up to 0.11 px off here, and a low-contrast one
  // 0.024 px.
  for (const cv::Vec2d& slope : {cv::Vec2d(0.0006, -0.0003), cv::Vec2d(-0.0002, 0.0007)}) {
    for (const Look& base : {Look{50, 220}, Look{200, 30}, Look{230, 15}, Look{150, 200}}) {
      Look look = base;
      look.light_slope = slope;
      INFO("part " << look.part << " on " << look.background << ", light slope " << slope[0] << ", "
                   << slope[1]);
      for (const double deg : {10.0, 100.0, 215.0}) {
        INFO("turned " << deg);
        const Drawn d = drawL(deg, false, look);
        const auto grey = regionsOf(d, true, look);
        REQUIRE(grey.size() == 1);
        CHECK(cv::norm(grey[0].centroid - d.centroid) < 0.02);
        CHECK(grey[0].area == Approx(4800).epsilon(0.005));
      }
    }
  }
}

TEST_CASE("an upright rectangle at a subpixel position is measured from its grey levels",
          "[vision][regions]") {
  // Its box hugs it: the background ring for the light must come from the
  // margin around the box, 4 px wide, not from the box's corners.
  const Drawn d = drawShape({{0, 0}, {90, 0}, {90, 50}, {0, 50}}, 0, false, {200.3, 150.6});
  const auto grey = regionsOf(d, true);
  REQUIRE(grey.size() == 1);
  CHECK(cv::norm(grey[0].centroid - d.centroid) < 0.02);
  CHECK(grey[0].area == Approx(4500).epsilon(0.005));
}

TEST_CASE("coverage is a fraction between 0 and 1 even under noise", "[vision][regions]") {
  Drawn d = drawL(20, false);
  cv::Mat noise(d.grey.size(), CV_16S);
  cv::randn(noise, 0, 12);
  cv::Mat noisy;
  d.grey.convertTo(noisy, CV_16S);
  noisy += noise;
  noisy.convertTo(d.grey, CV_8U);
  const auto regions = regionsOf(d, true);
  REQUIRE(regions.size() == 1);
  double least = 0, most = 0;
  cv::minMaxLoc(regions[0].coverage, &least, &most);
  CHECK(least >= 0.0);
  CHECK(most <= 1.0);
  CHECK(most == 1.0);  // the interior is covered, whatever its noise
}

TEST_CASE("the area of a defocused part is read from beyond its edge blur", "[vision][regions]") {
  // Blurred by sigma 2 px, a part's edge spreads light 4 to 6 px out. The
  // background the grey levels are read against comes from a ring just
  // outside the blurred edge (3 and 4 px beyond the cut): the nearer its
  // pixels, the more part they see, the lower the contrast and the area.
  // From the 2 px ring the L's area is read up to 1.7 % off; from its inner
  // 1 px alone, 2.3 %.
  double worst = 0;
  for (double deg = 0; deg < 360; deg += 23) {
    Drawn d = drawShape({{0, 0}, {120, 0}, {120, 30}, {30, 30}, {30, 70}, {0, 70}}, deg, false,
                        {200.3, 199.6});
    cv::GaussianBlur(d.grey, d.grey, cv::Size(0, 0), 2.0);
    const auto grey = regionsOf(d, true);
    REQUIRE(grey.size() == 1);
    worst = std::max(worst, std::abs(grey[0].area - 4800) / 4800);
  }
  INFO("area off by up to " << 100 * worst << " %");
  CHECK(worst < 0.02);
}

TEST_CASE("a highlight inside a part does not move its centroid", "[vision][regions]") {
  // A shiny spot on the long leg, 6 px round, lighter than the part but not
  // enough to be cut out of it: the part's pixels all the same. Read from
  // its grey levels as partly uncovered, it would pull the centroid about a
  // third of a pixel away; the interior is the part's whole. On a light part
  // (whose own levels give the light it is read under) the spot is a dark
  // mark, and it must not tilt that light either.
  struct Case {
    Look look;
    double spot_level;
  };
  for (const Case& c : {Case{Look{50, 220}, 110}, Case{Look{200, 30}, 140}}) {
    for (const double deg : {0.0, 37.0, 141.0}) {
      INFO("part " << c.look.part << " on " << c.look.background << ", turned " << deg);
      Drawn d = drawL(deg, false, c.look);
      const double a = deg * M_PI / 180.0;
      // The long leg's middle, 40 px along it from the L's own origin.
      const cv::Point2d local(100 - 45, 15 - 25);
      const cv::Point2d spot(200 + local.x * std::cos(a) - local.y * std::sin(a),
                             200 + local.x * std::sin(a) + local.y * std::cos(a));
      cv::circle(d.grey,
                 cv::Point(static_cast<int>(std::lround(spot.x * 16)),
                           static_cast<int>(std::lround(spot.y * 16))),
                 6 * 16, cv::Scalar(c.spot_level), cv::FILLED, cv::LINE_AA, 4);
      const auto regions = regionsOf(d, true, c.look);
      REQUIRE(regions.size() == 1);
      CHECK(regions[0].holes == 0);
      CHECK(cv::norm(regions[0].centroid - d.centroid) < 0.02);
      CHECK(regions[0].area == Approx(4800).epsilon(0.005));
    }
  }
}

TEST_CASE("a defocused part is placed as well as a sharp one", "[vision][regions]") {
  // Blurred by sigma 1.5 or 2.5 px, an edge spreads its light 4 to 7 px each
  // side: the band of edge pixels read from grey levels widens with it. A
  // band left at 2 px cuts the blur's tail off, more where the L is concave
  // than where it is convex, and places it 0.05 to 0.1 px off.
  for (const double sigma : {1.5, 2.5}) {
    double worst = 0;
    for (double deg = 0; deg < 360; deg += 37) {
      Drawn d = drawShape({{0, 0}, {120, 0}, {120, 30}, {30, 30}, {30, 70}, {0, 70}}, deg, false,
                          {200.3, 199.6});
      cv::GaussianBlur(d.grey, d.grey, cv::Size(0, 0), sigma);
      const auto grey = regionsOf(d, true);
      REQUIRE(grey.size() == 1);
      worst = std::max(worst, cv::norm(grey[0].centroid - d.centroid));
    }
    INFO("sigma " << sigma << ": centroid off by up to " << worst << " px");
    CHECK(worst < 0.02);
  }
}

TEST_CASE("a one-pixel speck in a part's box changes nothing of the part", "[vision][regions]") {
  // A speck inside the box a part's grey levels are read over, beyond the
  // band and the background ring, makes the part share its box: its pixels
  // are then told from the speck's by connectivity, with the same result.
  // A part with a hole, sharp and blurred.
  for (const double blur : {0.0, 1.5}) {
    cv::Mat mask(240, 260, CV_8UC1, cv::Scalar(0));
    cv::circle(mask, {120, 120}, 60, cv::Scalar(255), cv::FILLED);
    cv::circle(mask, {120, 120}, 25, cv::Scalar(0), cv::FILLED);
    cv::Mat grey;
    mask.convertTo(grey, CV_8U, -170.0 / 255.0, 220.0);
    if (blur > 0) cv::GaussianBlur(grey, grey, cv::Size(0, 0), blur);
    const cv::Mat cut = grey < 135;
    cv::Mat specked = cut.clone();
    cv::Mat specked_grey = grey.clone();
    // The disc's box is (60, 60) to (180, 180); its corner is 17 px from
    // the disc's edge, well beyond the band and the ring.
    specked.at<uint8_t>(55, 55) = 255;
    specked_grey.at<uint8_t>(55, 55) = 50;
    for (const bool use_grey : {false, true}) {
      INFO("blur " << blur << " grey " << use_grey);
      const auto alone = findRegions(cut, {}, use_grey ? grey : cv::Mat());
      const auto shared = findRegions(specked, {}, use_grey ? specked_grey : cv::Mat());
      REQUIRE(alone.size() == 1);  // the speck is noise
      REQUIRE(shared.size() == 1);
      picksight::test::checkSameRegion(alone[0], shared[0]);
      CHECK(alone[0].holes == 1);
    }
  }
}

TEST_CASE("a pinhole of a pixel or two is no hole of the part, a hole of three is",
          "[vision][regions]") {
  // A defective pixel of the sensor, dust or JPEG ringing inside a dark
  // part (tests/data/scenes/pca_test1.jpg: one pixel of level 107 in a bar
  // at 10 on a table at 230) is not a hole the part has: filled, as a glint
  // is, with or without grey levels. A hole 3 x 3 pixels wide is counted.
  for (const cv::Size hole : {cv::Size(1, 1), cv::Size(2, 1), cv::Size(2, 2), cv::Size(3, 3)}) {
    cv::Mat grey(240, 260, CV_8UC1, cv::Scalar(220));
    cv::circle(grey, {130, 120}, 60, cv::Scalar(20), cv::FILLED);
    grey(cv::Rect(cv::Point(110, 100), hole)).setTo(cv::Scalar(200));
    const cv::Mat mask = grey < 120;
    REQUIRE(cv::countNonZero(mask(cv::Rect(cv::Point(110, 100), hole))) == 0);
    for (const bool use_grey : {false, true}) {
      INFO("hole " << hole.width << " x " << hole.height << " grey " << use_grey);
      const auto regions = findRegions(mask, {}, use_grey ? grey : cv::Mat());
      REQUIRE(regions.size() == 1);
      const bool counted = hole.width > 2 || hole.height > 2;
      CHECK(regions[0].holes == (counted ? 1 : 0));
      CHECK(regions[0].hole_boundaries.size() == (counted ? 1u : 0u));
      CHECK(regions[0].glints == 0);
      CHECK(regions[0].pinholes == (counted ? 0 : 1));
      // Filled: the pinhole's pixels count for the part.
      if (!counted && !use_grey) CHECK(regions[0].area == cv::countNonZero(mask) + hole.area());
    }
  }
}

TEST_CASE("a part cut by the frame's edge is measured inside the frame", "[vision][regions]") {
  // Kept on request, its box clipped by the frame, the band and the ring
  // meet the edge: the coverage stays a fraction, zero outside the covered
  // runs, and the area the part's share of the frame.
  Drawn d = drawShape({{0, 0}, {120, 0}, {120, 30}, {30, 30}, {30, 70}, {0, 70}}, 30, false,
                      {30.4, 200.2});
  cv::GaussianBlur(d.grey, d.grey, cv::Size(0, 0), 1.0);
  const cv::Mat mask = d.grey < 135;
  picksight::vision::RegionOptions keep;
  keep.keep_border_regions = true;
  const auto regions = findRegions(mask, keep, d.grey);
  REQUIRE(regions.size() == 1);
  const Region& r = regions[0];
  CHECK(r.touches_border);
  CHECK(r.bbox.x == 0);
  CHECK(r.coverage_origin.x == 0);
  REQUIRE(r.covered.width() == r.coverage.cols);
  REQUIRE(r.covered.height() == r.coverage.rows);
  double least = 0, most = 0;
  cv::minMaxLoc(r.coverage, &least, &most);
  CHECK(least >= 0.0);
  CHECK(most == 1.0);
  cv::Mat outside;
  cv::bitwise_not(r.covered.toMask(), outside);
  CHECK(cv::countNonZero((r.coverage != 0) & outside) == 0);
  // The drawn part's pixels inside the frame, from its grey levels.
  cv::Mat part;
  d.grey.convertTo(part, CV_32F, -1.0 / 170.0, 220.0 / 170.0);
  CHECK(r.area == Approx(cv::sum(part)[0]).epsilon(0.01));
}
