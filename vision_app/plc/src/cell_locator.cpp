// PLC triggers through the cell's one LOCATE path.
#include "picksight/plc/cell_locator.hpp"

#include "picksight/protocol/robot_errors.hpp"

namespace picksight::plc {

uint16_t frameCode(app::CoordinateFrame frame) {
  switch (frame) {
    case app::CoordinateFrame::kVisionPixels:
      return kFrameVisionPixels;
    case app::CoordinateFrame::kVisionMm:
      return kFrameVisionMm;
    case app::CoordinateFrame::kRobot:
      return kFrameRobot;
  }
  return kFrameVisionPixels;
}

PlcResult plcResult(const app::CellLocate& located) {
  PlcResult result;
  result.frame_sequence = located.outcome.frame.sequence;
  result.frame = frameCode(located.pick.frame);
  result.parts.reserve(located.pick.poses.size());
  for (size_t i = 0; i < located.pick.poses.size(); ++i) {
    const auto& pose = located.pick.poses[i];
    const auto& part = located.outcome.parts[located.pick.parts[i]];
    result.parts.push_back({part.type, pose.x, pose.y, pose.rz_deg, part.score});
  }
  return result;
}

PlcDevice::Locator cellLocator(app::CellContext& cell) {
  return [&cell](int type) -> Result<PlcResult> {
    auto located = app::locateAndPick(cell, type);
    if (!located) return located.error();
    return plcResult(*located);
  };
}

PlcDevice::FrameState cellFrameState(const app::CellCalibration& calibration) {
  return [&calibration] {
    const auto geometry = calibration.geometry();
    return geometry ? frameCode(geometry->frame()) : kFrameDamaged;
  };
}

int robotErrorCodeOf(const Error& error) { return app::robotErrorCode(error.code); }

}  // namespace picksight::plc
