// Angle arithmetic in degrees, shared by the vision, calibration and grasp
// libraries, the cell, tests and tools: one definition of each wrap so that
// every component agrees on the edge cases.
#pragma once

#include <cmath>

namespace picksight {

// Unit conversions, by multiplication: rad = deg * kRadPerDeg.
constexpr double kRadPerDeg = M_PI / 180.0;
constexpr double kDegPerRad = 180.0 / M_PI;

// Into [0, period): the angle of a part whose look repeats every `period`
// degrees (360 directed, 180 axis only, 90 square...). A period of 0 (or
// not a number) means no angle exists: the result is 0. Never returns
// `period` itself (fmod of a tiny negative plus period rounds up to it) nor
// negative zero.
inline double wrapDeg(double deg, double period) {
  if (!(period > 0)) return 0.0;
  double d = std::fmod(deg, period);
  if (d < 0) d += period;
  // `+ 0.0` turns -0 into +0 so that a sign never shows on a zero angle.
  return d >= period ? 0.0 : d + 0.0;
}

// Into [0, 360).
inline double normalizeDeg(double deg) { return wrapDeg(deg, 360.0); }

// Into (-180, 180]: a turn or a difference of directions.
inline double signedDeg(double deg) {
  double d = std::fmod(deg, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

// Into (-period / 2, period / 2]: of the turns a part with that period looks
// alike at, the one nearest 0 (a bar's turn of 179.9 is -0.1). Centred on 0
// so that a part lying near 0 (as it was taught) never crosses the wrap,
// which the [0, period) of wrapDeg has right there. A period of 0 (or not a
// number) means no angle exists: the result is 0. Never negative zero.
inline double centredDeg(double deg, double period) {
  if (!(period > 0)) return 0.0;
  const double half = period / 2;
  double d = std::fmod(deg, period);
  if (d > half) d -= period;
  if (d <= -half) d += period;
  return d + 0.0;
}

// The angle equal to `deg` modulo `period` that lies in (reference -
// period / 2, reference + period / 2]; `reference` itself for a period of 0.
inline double nearestTurnDeg(double deg, double reference, double period) {
  return reference + centredDeg(deg - reference, period);
}

// Smallest absolute difference between two angles, modulo `period` degrees
// (360 for a directed part, 180 for one whose direction is ambiguous, 90 for a
// square...), in [0, period / 2]. A period of 0 means no angle exists: the
// difference is 0.
inline double angleDiffDeg(double a, double b, double period = 360.0) {
  if (period <= 0) return 0.0;
  double d = std::fmod(std::fabs(a - b), period);
  return std::fmin(d, period - d);
}

}  // namespace picksight
