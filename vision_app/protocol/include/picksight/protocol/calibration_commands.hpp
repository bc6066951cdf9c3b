// Robot protocol commands for calibration: CALCAM (camera scale), STORE,
// DELETE, LIST, COMPUTE and RESIDUALS (robot-camera), docs/PROTOCOL.md.
#pragma once

#include "picksight/cell/vision_service.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/store/cell_calibration.hpp"

namespace picksight::protocol {

// Registers the commands; `vision` and `calibration` outlive `table`.
void addCalibrationCommands(CommandTable& table, cell::VisionService& vision,
                            store::CellCalibration& calibration);

}  // namespace picksight::protocol
