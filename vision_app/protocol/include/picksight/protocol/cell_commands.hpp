// Robot protocol commands that run the cell: LOCATE and LOCATE ALL (grasp
// poses in the reply frame), WHY, GRASP and GRIPPER (per model), STATUS,
// and the camera settings passed through to the video server (EXPOSURE,
// ROI); docs/PROTOCOL.md. The cell's work is cell_locate's; these only
// parse and format.
#pragma once

#include <string>
#include <vector>

#include "picksight/cell/cell_locate.hpp"
#include "picksight/protocol/command_table.hpp"

namespace picksight::protocol {

// The LOCATE reply a robot reads: "OK <n>" then x y rz of each pose.
std::string locateReply(const cell::CellPick& pick);

// The LOCATE ALL reply: "OK <n>" then type x y rz of each pose.
std::string locateAllReply(const cell::CellLocate& located);

// The camera feature names EXPOSURE tries, in order: GenICam SFNC, older
// GenICam cameras, V4L2.
const std::vector<std::string>& exposureFeatureNames();

// Registers the commands; `cell` outlives `table`. LOCATE leaves its
// record in the session (Publishes::kRecord) for WHY and the results
// stream.
void addCellCommands(CommandTable& table, cell::CellContext& cell);

}  // namespace picksight::protocol
