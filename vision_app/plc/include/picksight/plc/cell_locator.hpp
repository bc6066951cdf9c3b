// The PLC device's view of a cell: its trigger runs the robot port's LOCATE
// path (locateAndPick), its error codes are the robot protocol's, its
// calibration state is the cell's reply frame.
#pragma once

#include "picksight/plc/plc_device.hpp"
#include "picksight/protocol/cell_commands.hpp"

namespace picksight::plc {

uint16_t frameCode(app::CoordinateFrame frame);  // kFrame*

// A LOCATE's poses as the PLC registers hold them: each pose with its
// part's type and score.
PlcResult plcResult(const app::CellLocate& located);

// The three callbacks of a PlcDevice over `cell` (borrowed; outlives the
// device).
PlcDevice::Locator cellLocator(app::CellContext& cell);
PlcDevice::FrameState cellFrameState(const app::CellCalibration& calibration);
int robotErrorCodeOf(const Error& error);

}  // namespace picksight::plc
