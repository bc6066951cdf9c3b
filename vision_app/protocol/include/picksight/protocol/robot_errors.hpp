// The one table from errors, of every domain a robot request can meet, to
// the robot protocol's ERROR codes (docs/PROTOCOL.md, "Errors"). The
// codes are the protocol's contract with robot programs: they never change
// when an error enum does.
#pragma once

#include <system_error>

namespace picksight::protocol {

// The ERROR code for `code`; 99 (internal error) for one the table does
// not know.
int robotErrorCode(const std::error_code& code);

}  // namespace picksight::protocol
