// picksight-cam: writes a snapped frame to an image file.
#pragma once

#include <ostream>
#include <string>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"

namespace picksight::cam {

// Writes the frame of `snap` to `file` in the format its extension names and
// prints what was saved (text or JSON). Errors: CliErrc::kBadReply when the frame's
// payload does not match its header, CliErrc::kSaveFailed when the file cannot be
// written; nothing is printed then.
Result<void> saveSnap(const std::string& camera, const proto::SnapReply& snap,
                      const std::string& file, bool as_json, std::ostream& out);

}  // namespace picksight::cam
