// What a control request is about, whether the control socket's thread
// answers it itself (see the rule in control_server.hpp), and the one
// decode-and-check step every request body goes through.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"
#include "picksight/transport/control_client.hpp"

namespace picksight::video {

// The largest control request accepted is kMaxControlRequestBytes (64 KiB,
// transport/control_client.hpp). The ROUTER socket has it as ZMQ_MAXMSGSIZE,
// so ZeroMQ drops a bigger message (and the connection that sent it) before
// it is buffered whole; decodeRequest() checks it again for transports
// ZeroMQ does not limit (inproc). Real requests are under 1 KiB.
// Camera and feature names, and feature values, longer than these are refused.
constexpr size_t kMaxControlName = 256;
constexpr size_t kMaxControlValue = 4096;

// Decodes one request body and checks what needs no camera: the size, that it
// decodes and asks something, strings within their bounds, and numbers finite
// and in range (set_mode.fps, set_size.scale, a set_feature value spelled as
// nan or inf). The error is kBadRequest or kOutOfRange and names the field.
// Never throws; safe on any bytes.
Result<proto::ControlRequest> decodeRequest(const void* data, size_t size);

// The camera a request is about; nullopt for requests about the whole server
// (list_cameras, statistics) or of no known kind.
std::optional<std::string> requestCamera(const proto::ControlRequest& request);

// True for the requests the socket thread answers itself: trigger,
// list_cameras, statistics, and requests of no known kind.
bool answeredAtOnce(const proto::ControlRequest& request);

}  // namespace picksight::video
