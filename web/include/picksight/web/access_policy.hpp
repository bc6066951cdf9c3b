// Which role each request of the web HMI needs (docs/SECURITY.md): reads
// and the robot lines that only read or locate are an operator's; lines
// that teach, set tolerances or calibrate and every camera setting are an
// engineer's; the users an admin's. An unknown command word needs an
// engineer: a new command is not an operator's until someone says so.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "picksight/web/user_store.hpp"

namespace picksight::web {

// The role a robot-protocol line sent from the page needs.
Role roleForCommand(std::string_view line);

// Whether the line changes the cell (models, calibration, camera), so that
// the audit trail records it: every engineer's line but TRYLEARN, a teach
// preview that stores nothing (an engineer's, since only engineers teach).
bool changesCell(std::string_view line);
// The read-only line whose reply shows what the change `line` changes
// ("TOLERANCE 3 area_tolerance 0.2" -> "TOLERANCE 3", "GRASP 2 ADD ..." ->
// "GRASP 2 LIST", "EXPOSURE 900" -> "EXPOSURE"), asked before and after it
// for the audit trail; nullopt for a line that changes nothing or whose
// state no cheap read shows (LEARN, CALCAM...).
std::optional<std::string> readBackLine(std::string_view line);
// A piece of a job import (JOB IMPORT <name> <offset> <total> <base64>):
// longer than other lines, and recorded once, when the last piece makes
// the import (the app replies MORE before it).
bool isJobImportPiece(std::string_view line);
// The role a camera action (POST /api/cameras/<camera>/<action>) needs.
Role roleForCameraAction(std::string_view action);

}  // namespace picksight::web
