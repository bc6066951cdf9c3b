// Pins angle differences modulo a part's symmetry period and the wraps into
// [0, period), [0, 360), (-180, 180] and (-period / 2, period / 2], edge
// cases included.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "picksight/common/angles.hpp"

using Catch::Detail::Approx;
using picksight::angleDiffDeg;
using picksight::centredDeg;
using picksight::nearestTurnDeg;
using picksight::normalizeDeg;
using picksight::signedDeg;
using picksight::wrapDeg;

TEST_CASE("angleDiffDeg wraps around 360", "[common]") {
  CHECK(angleDiffDeg(359, 1) == Approx(2));
  CHECK(angleDiffDeg(1, 359) == Approx(2));
  CHECK(angleDiffDeg(10, 350) == Approx(20));
  CHECK(angleDiffDeg(0, 180) == Approx(180));
  CHECK(angleDiffDeg(90, 90) == Approx(0));
  CHECK(angleDiffDeg(-1, 1) == Approx(2));
  CHECK(angleDiffDeg(720, 0) == Approx(0).margin(1e-12));
  CHECK(angleDiffDeg(30, 60, 360) == Approx(30));
}

TEST_CASE("angleDiffDeg with period 180 treats opposite directions as equal", "[common]") {
  CHECK(angleDiffDeg(10, 190, 180) == Approx(0).margin(1e-12));
  CHECK(angleDiffDeg(179, 1, 180) == Approx(2));
  CHECK(angleDiffDeg(5, 175, 180) == Approx(10));
  CHECK(angleDiffDeg(0, 90, 180) == Approx(90));
  CHECK(angleDiffDeg(359, 1, 180) == Approx(2));
}

TEST_CASE("angleDiffDeg with period 90 and period 0", "[common]") {
  CHECK(angleDiffDeg(0, 89, 90) == Approx(1));
  CHECK(angleDiffDeg(10, 280, 90) == Approx(0).margin(1e-12));
  // Period 0: an isotropic part has no angle, so any two angles agree.
  CHECK(angleDiffDeg(0, 123, 0) == 0.0);
  CHECK(angleDiffDeg(17, 300, 0) == 0.0);
}

TEST_CASE("normalizeDeg maps into 0 up to but excluding 360", "[common]") {
  CHECK(normalizeDeg(0) == 0.0);
  CHECK(normalizeDeg(360) == 0.0);
  CHECK(normalizeDeg(-30) == Approx(330));
  CHECK(normalizeDeg(725) == Approx(5));
  CHECK(normalizeDeg(-720) == 0.0);
  // fmod(-tiny, 360) + 360 rounds to exactly 360, which is outside the range.
  const double tiny = normalizeDeg(-1e-20);
  CHECK(tiny >= 0.0);
  CHECK(tiny < 360.0);
}

TEST_CASE("normalizeDeg never returns negative zero", "[common]") {
  CHECK_FALSE(std::signbit(normalizeDeg(-0.0)));
  CHECK_FALSE(std::signbit(normalizeDeg(-360.0)));
  CHECK_FALSE(std::signbit(normalizeDeg(-720.0)));
}

TEST_CASE("wrapDeg maps into 0 up to but excluding the period", "[common]") {
  CHECK(wrapDeg(190, 180) == Approx(10));
  CHECK(wrapDeg(-10, 180) == Approx(170));
  CHECK(wrapDeg(180, 180) == 0.0);
  CHECK(wrapDeg(-180, 180) == 0.0);
  CHECK(wrapDeg(95, 90) == Approx(5));
  CHECK(wrapDeg(359.5, 120) == Approx(119.5));
  CHECK(wrapDeg(725, 360) == Approx(5));
  const double tiny = wrapDeg(-1e-20, 90);
  CHECK(tiny >= 0.0);
  CHECK(tiny < 90.0);
  CHECK_FALSE(std::signbit(wrapDeg(-0.0, 180)));
}

TEST_CASE("wrapDeg with period 0 or not a number means no angle", "[common]") {
  CHECK(wrapDeg(123, 0) == 0.0);
  CHECK(wrapDeg(-5, -90) == 0.0);
  CHECK(wrapDeg(45, std::numeric_limits<double>::quiet_NaN()) == 0.0);
}

TEST_CASE("wrapDeg of a non-negative angle is fmod", "[common]") {
  for (double deg : {0.0, 0.1, 59.999, 60.0, 119.5, 359.9, 1000.25})
    CHECK(wrapDeg(deg, 60) == std::fmod(deg, 60.0));
}

TEST_CASE("signedDeg maps into minus 180 excluded up to 180", "[common]") {
  CHECK(signedDeg(0) == 0.0);
  CHECK(signedDeg(180) == Approx(180));
  CHECK(signedDeg(-180) == Approx(180));
  CHECK(signedDeg(190) == Approx(-170));
  CHECK(signedDeg(-190) == Approx(170));
  CHECK(signedDeg(540) == Approx(180));
  CHECK(signedDeg(359) == Approx(-1));
  CHECK(signedDeg(-359) == Approx(1));
  CHECK(signedDeg(720) == 0.0);
}

TEST_CASE("angleDiffDeg is symmetric and at most half the period", "[common]") {
  for (double a = -400; a <= 400; a += 37.5)
    for (double b = -400; b <= 400; b += 41.25)
      for (double period : {360.0, 180.0, 90.0, 120.0}) {
        const double d = angleDiffDeg(a, b, period);
        CHECK(d >= 0.0);
        CHECK(d <= period / 2 + 1e-9);
        CHECK(d == angleDiffDeg(b, a, period));
      }
}

TEST_CASE("centredDeg maps into minus half the period excluded up to half of it", "[common]") {
  // A bar lying a hair either side of its taught angle: 0.1 and -0.1, not
  // 0.1 and 179.9.
  CHECK(centredDeg(179.9, 180) == Approx(-0.1));
  CHECK(centredDeg(-0.1, 180) == Approx(-0.1));
  CHECK(centredDeg(0.1, 180) == Approx(0.1));
  CHECK(centredDeg(90, 180) == Approx(90));
  CHECK(centredDeg(-90, 180) == Approx(90));
  CHECK(centredDeg(270, 180) == Approx(90));
  CHECK(centredDeg(91, 180) == Approx(-89));
  CHECK(centredDeg(44, 90) == Approx(44));
  CHECK(centredDeg(46, 90) == Approx(-44));
  CHECK(centredDeg(-45, 90) == Approx(45));
  CHECK(centredDeg(359, 360) == Approx(-1));
  CHECK(centredDeg(180, 360) == Approx(180));
  CHECK(centredDeg(-180, 360) == Approx(180));
  CHECK(centredDeg(725, 360) == Approx(5));
  CHECK_FALSE(std::signbit(centredDeg(-0.0, 180)));
  CHECK_FALSE(std::signbit(centredDeg(-180.0, 180)));
  // No angle: a disc.
  CHECK(centredDeg(123, 0) == 0.0);
  CHECK(centredDeg(45, std::numeric_limits<double>::quiet_NaN()) == 0.0);
  for (double a = -800; a <= 800; a += 13.75) {
    for (double period : {360.0, 180.0, 120.0, 90.0, 60.0}) {
      const double c = centredDeg(a, period);
      CHECK(c > -period / 2);
      CHECK(c <= period / 2);
      CHECK(angleDiffDeg(c, a, period) == Approx(0).margin(1e-9));
    }
  }
}

TEST_CASE("nearestTurnDeg picks the turn within half a period of the reference", "[common]") {
  CHECK(nearestTurnDeg(359.9, 30, 360) == Approx(-0.1));
  CHECK(nearestTurnDeg(209.99, 30, 180) == Approx(29.99));
  CHECK(nearestTurnDeg(30.01, 30, 180) == Approx(30.01));
  CHECK(nearestTurnDeg(10, 350, 360) == Approx(370));
  CHECK(nearestTurnDeg(10, 350, 0) == 350);
}
