// Why a camera or robot-camera calibration failed: the calibration
// library's error domain.
#pragma once

#include "picksight/common/error.hpp"

namespace picksight::calibration {

// Why a calibration could not be computed.
enum class CalibrationErrc {
  kTooFewPoints = 1,  // robot-camera: fewer than 3 usable points
  kDegeneratePoints,  // robot-camera: points on one line, or too close
  kBadTarget,         // camera: the target's measurements are unusable
  kBadInput,          // an argument out of its range
  kBadFile,           // a lens or calibration file that cannot be read
};
const char* errorName(CalibrationErrc e);
PICKSIGHT_ERROR_DOMAIN(CalibrationErrc, "calibration")

}  // namespace picksight::calibration

PICKSIGHT_ERROR_ENUM(picksight::calibration::CalibrationErrc)
