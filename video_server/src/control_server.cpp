// Control socket loop. A malformed request gets an error reply, so a REQ
// client is never left waiting.
#include "picksight/video_server/control_server.hpp"

#include "picksight/common/log.hpp"

namespace picksight::video {

ControlServer::ControlServer(zmq::context_t& context, const std::string& endpoint, Handler handler)
    : socket_(context, zmq::socket_type::rep), handler_(std::move(handler)) {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.bind(endpoint);
  bound_endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
}

ControlServer::~ControlServer() { stop(); }

void ControlServer::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void ControlServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ControlServer::run() {
  while (!stop_) {
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    try {
      if (zmq::poll(&item, 1, std::chrono::milliseconds(100)) == 0) continue;
      zmq::message_t request_bytes;
      if (!socket_.recv(request_bytes, zmq::recv_flags::dontwait)) continue;
      // REP requires reading every part before replying.
      while (request_bytes.more()) {
        zmq::message_t extra;
        if (!socket_.recv(extra)) break;
        if (!extra.more()) break;
      }
      proto::ControlRequest request;
      proto::ControlReply reply;
      if (!request.ParseFromArray(request_bytes.data(), static_cast<int>(request_bytes.size())) ||
          request.request_case() == proto::ControlRequest::REQUEST_NOT_SET) {
        reply.mutable_error()->set_code(proto::Error::BAD_REQUEST);
        reply.mutable_error()->set_text("malformed or empty control request");
      } else {
        reply = handler_(request);
      }
      const std::string bytes = reply.SerializeAsString();
      socket_.send(zmq::buffer(bytes), zmq::send_flags::none);
    } catch (const zmq::error_t& e) {
      // Never let an exception out of the thread loop.
      logError("control: ", e.what());
    }
  }
  socket_.close();
}

}  // namespace picksight::video
