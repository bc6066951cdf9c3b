// Pins angle differences modulo a part's symmetry period and normalization to [0, 360).
#include <catch2/catch.hpp>

#include "picksight/common/angles.hpp"

using Catch::Detail::Approx;
using picksight::angleDiffDeg;
using picksight::normalizeDeg;

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
