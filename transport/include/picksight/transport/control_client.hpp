// Client of the video server's control socket: one request, one reply, with
// a timeout that leaves the client usable.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"

namespace picksight {

// Error codes of ControlClient results: the server's proto::Error codes, plus
// this one for a server that did not answer.
constexpr int kControlTimeout = 1000;

class ControlClient {
 public:
  ControlClient(zmq::context_t& context, std::string endpoint,
                std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

  // Sends `request`; the reply when the server answered with code OK, else an
  // Error carrying the server's code and text (or kControlTimeout).
  Result<proto::ControlReply> call(const proto::ControlRequest& request);

  const std::string& endpoint() const { return endpoint_; }

 private:
  void reconnect();

  zmq::context_t& context_;
  std::string endpoint_;
  std::chrono::milliseconds timeout_;
  std::unique_ptr<zmq::socket_t> socket_;
};

}  // namespace picksight
