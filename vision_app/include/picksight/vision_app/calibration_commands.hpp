// Robot protocol commands for calibration: CALCAM (camera scale), STORE,
// DELETE, LIST, COMPUTE and RESIDUALS (robot-camera), docs/PROTOCOL.md.
#pragma once

#include "picksight/vision_app/cell_calibration.hpp"
#include "picksight/vision_app/command_table.hpp"
#include "picksight/vision_app/vision_service.hpp"

namespace picksight::app {

// Registers the commands; `vision` and `calibration` outlive `table`.
void addCalibrationCommands(CommandTable& table, VisionService& vision,
                            CellCalibration& calibration);

}  // namespace picksight::app
