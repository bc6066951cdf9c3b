// Robot protocol command for the vision settings at run time: VISION
// (docs/PROTOCOL.md).
#pragma once

#include "picksight/cell/vision_service.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

// Registers VISION; `vision` (with its model library) outlives `table`.
void addVisionSettingsCommands(CommandTable& table, cell::VisionService& vision);

}  // namespace picksight::protocol
