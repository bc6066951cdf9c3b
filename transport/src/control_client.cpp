// Control client. A REQ socket that timed out is stuck waiting for its reply,
// so on timeout the socket is dropped and a new one connected.
#include "picksight/transport/control_client.hpp"

namespace picksight::transport {
namespace {
ControlErrc fromWire(proto::Error::Code code) {
  // Same numbers; a code this client does not know is the server's problem.
  const bool known = code >= proto::Error::BAD_REQUEST && code <= proto::Error::BUSY;
  return known ? static_cast<ControlErrc>(code) : ControlErrc::kInternal;
}
}  // namespace

const char* errorName(ControlErrc e) {
  switch (e) {
    case ControlErrc::kNoReply:
      return "no reply";
    case ControlErrc::kBadRequest:
      return "bad request";
    case ControlErrc::kUnknownCamera:
      return "unknown camera";
    case ControlErrc::kOutOfRange:
      return "out of range";
    case ControlErrc::kNotSupported:
      return "not supported";
    case ControlErrc::kCameraUnavailable:
      return "camera unavailable";
    case ControlErrc::kInternal:
      return "internal";
    case ControlErrc::kUnknownFeature:
      return "unknown feature";
    case ControlErrc::kTimeout:
      return "timeout";
    case ControlErrc::kBusy:
      return "busy";
  }
  return "unknown";
}

ControlClient::ControlClient(zmq::context_t& context, std::string endpoint,
                             std::chrono::milliseconds timeout,
                             std::optional<CurveClientKeys> curve)
    : context_(context),
      endpoint_(std::move(endpoint)),
      timeout_(timeout),
      curve_(std::move(curve)) {
  reconnect();
}

void ControlClient::reconnect() {
  socket_ = std::make_unique<zmq::socket_t>(context_, zmq::socket_type::req);
  socket_->set(zmq::sockopt::linger, 0);
  secureClientSocket(*socket_, curve_);
  socket_->connect(endpoint_);
}

Result<proto::ControlReply> ControlClient::call(const proto::ControlRequest& request) {
  const std::string bytes = request.SerializeAsString();
  if (bytes.size() > kMaxControlRequestBytes) {
    return makeError(ControlErrc::kBadRequest,
                     "control request of " + std::to_string(bytes.size()) +
                         " bytes exceeds the video server's limit of " +
                         std::to_string(kMaxControlRequestBytes) + " bytes");
  }
  // A REQ socket whose only connection failed its handshake (a CURVE server
  // that refused our key, or a plain client of a CURVE server) may have no
  // pipe left to send on: a blocking send would then wait forever. The
  // send waits within the timeout like the reply.
  zmq::pollitem_t out{socket_->handle(), 0, ZMQ_POLLOUT, 0};
  if (zmq::poll(&out, 1, timeout_) == 0 ||
      !socket_->send(zmq::buffer(bytes), zmq::send_flags::dontwait)) {
    reconnect();
    return makeError(ControlErrc::kNoReply, "could not send to the video server at " + endpoint_ +
                                                " within " + std::to_string(timeout_.count()) +
                                                " ms (not connected, or refused by CURVE)");
  }
  zmq::pollitem_t item{socket_->handle(), 0, ZMQ_POLLIN, 0};
  if (zmq::poll(&item, 1, timeout_) == 0) {
    reconnect();
    return makeError(ControlErrc::kNoReply, "video server at " + endpoint_ +
                                                " did not answer within " +
                                                std::to_string(timeout_.count()) +
                                                " ms (is it running and reachable? a request "
                                                "over 64 KiB is dropped without a reply)");
  }
  zmq::message_t reply_bytes;
  if (!socket_->recv(reply_bytes)) {
    reconnect();
    return makeError(ControlErrc::kNoReply, "no reply from " + endpoint_);
  }
  proto::ControlReply reply;
  if (!reply.ParseFromArray(reply_bytes.data(), static_cast<int>(reply_bytes.size()))) {
    return makeError(ControlErrc::kInternal, "malformed reply from " + endpoint_);
  }
  if (reply.has_error() && reply.error().code() != proto::Error::OK) {
    return makeError(fromWire(reply.error().code()), reply.error().text());
  }
  return reply;
}

}  // namespace picksight::transport
