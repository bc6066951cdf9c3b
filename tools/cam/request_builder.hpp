// picksight-cam: turns a parsed command into the control request it stands for.
#pragma once

#include "cam_command_line.hpp"
#include "picksight.pb.h"
#include "picksight/common/result.hpp"

namespace picksight::cam {

// Checks the values of the command's arguments (numbers, enum words, non-empty
// names, a writable image format) and fills the request. Errors are usage
// errors whose message names the command and the argument.
Result<proto::ControlRequest> buildRequest(const CamCommand& command);

}  // namespace picksight::cam
