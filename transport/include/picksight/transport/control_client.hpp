// Client of the video server's control socket: one request, one reply, with
// a timeout that leaves the client usable.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"
#include "picksight/transport/curve_keys.hpp"

namespace picksight::transport {

// Why a control call failed: the server's answer, its wire code decoded
// (the values are proto::Error::Code's, so a tool can print the wire code),
// or no answer at all.
enum class ControlErrc {
  kBadRequest = 1,
  kUnknownCamera = 2,
  kOutOfRange = 3,
  kNotSupported = 4,
  kCameraUnavailable = 5,
  kInternal = 6,
  kUnknownFeature = 7,
  kTimeout = 8,     // the server waited in vain (e.g. for a frame)
  kBusy = 9,        // the server has too much slow work pending
  kNoReply = 1000,  // the server did not answer in time
};
const char* errorName(ControlErrc e);
PICKSIGHT_ERROR_DOMAIN(ControlErrc, "control")

// The largest control request a video server accepts (ZMQ_MAXMSGSIZE on its
// socket: ZeroMQ drops a bigger message and the connection, and no reply
// ever comes). call() refuses bigger requests itself, as kBadRequest.
constexpr size_t kMaxControlRequestBytes = 64 * 1024;

constexpr std::chrono::milliseconds kDefaultControlTimeout{2000};

class ControlClient {
 public:
  // With `curve` keys the socket talks CURVE: a server that refuses them (or
  // a plain server) never answers, which is kNoReply.
  ControlClient(zmq::context_t& context, std::string endpoint,
                std::chrono::milliseconds timeout = kDefaultControlTimeout,
                std::optional<CurveClientKeys> curve = std::nullopt);

  // Sends `request`; the reply when the server answered with code OK, else an
  // Error carrying the server's code and text (or kNoReply).
  Result<proto::ControlReply> call(const proto::ControlRequest& request);

  const std::string& endpoint() const { return endpoint_; }

 private:
  void reconnect();

  zmq::context_t& context_;
  std::string endpoint_;
  std::chrono::milliseconds timeout_;
  std::optional<CurveClientKeys> curve_;
  std::unique_ptr<zmq::socket_t> socket_;
};

}  // namespace picksight::transport

PICKSIGHT_ERROR_ENUM(picksight::transport::ControlErrc)
