// The control socket: a ZeroMQ REP socket on its own thread, decoding
// ControlRequest messages and encoding the handler's ControlReply.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight.pb.h"

namespace picksight::video {

class ControlServer {
 public:
  using Handler = std::function<proto::ControlReply(const proto::ControlRequest&)>;

  // Binds at once so a bad endpoint fails at start-up.
  ControlServer(zmq::context_t& context, const std::string& endpoint, Handler handler);
  ~ControlServer();

  const std::string& boundEndpoint() const { return bound_endpoint_; }
  void start();
  void stop();

 private:
  void run();

  zmq::socket_t socket_;  // control thread only (after start)
  std::string bound_endpoint_;
  Handler handler_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace picksight::video
