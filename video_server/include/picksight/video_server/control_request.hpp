// What a control request is about, and whether the control socket's thread
// answers it itself (see the rule in control_server.hpp).
#pragma once

#include <optional>
#include <string>

#include "picksight.pb.h"

namespace picksight::video {

// The camera a request is about; nullopt for requests about the whole server
// (list_cameras, statistics) or of no known kind.
std::optional<std::string> requestCamera(const proto::ControlRequest& request);

// True for the requests the socket thread answers itself: trigger,
// list_cameras, statistics, and requests of no known kind.
bool answeredAtOnce(const proto::ControlRequest& request);

}  // namespace picksight::video
