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
