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
// The role a camera action (POST /api/cameras/<camera>/<action>) needs.
Role roleForCameraAction(std::string_view action);

}  // namespace picksight::web
