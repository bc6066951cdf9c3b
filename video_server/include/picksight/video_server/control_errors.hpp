// The one table from errors to the control socket's wire codes
// (proto::Error::Code), and the error reply built from it.
#pragma once

#include "picksight.pb.h"
#include "picksight/common/error.hpp"

namespace picksight::video {

// The wire code for an error of any domain; INTERNAL for one the table does
// not know (a programming error, logged by the caller).
proto::Error::Code controlCode(const std::error_code& code);

// A reply carrying `error` with its wire code and message.
proto::ControlReply errorReply(const Error& error);

}  // namespace picksight::video
