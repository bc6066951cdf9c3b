// Angle arithmetic in degrees, shared by the locator, tests and tools.
#pragma once

#include <cmath>

namespace picksight {

// Into [0, 360).
inline double normalizeDeg(double deg) {
  double d = std::fmod(deg, 360.0);
  if (d < 0) d += 360.0;
  return d >= 360.0 ? 0.0 : d;
}

// Into (-180, 180]: a turn or a difference of directions.
inline double signedDeg(double deg) {
  double d = std::fmod(deg, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

// Smallest absolute difference between two angles, modulo `period` degrees
// (360 for a directed part, 180 for one whose direction is ambiguous, 90 for a
// square...). A period of 0 means no angle exists: the difference is 0.
inline double angleDiffDeg(double a, double b, double period = 360.0) {
  if (period <= 0) return 0.0;
  double d = std::fmod(std::fabs(a - b), period);
  return std::fmin(d, period - d);
}

}  // namespace picksight
