// Frame wire format decoding.
#include "picksight/transport/frame_message.hpp"

#include "picksight/common/clock.hpp"

namespace picksight {

int bytesPerPixel(proto::PixelFormat format) {
  switch (format) {
    case proto::MONO8:
      return 1;
    case proto::BGR8:
      return 3;
    default:
      return 0;
  }
}

bool frameIsConsistent(const proto::FrameHeader& header, size_t payload_size) {
  const int bpp = bytesPerPixel(header.pixel_format());
  if (bpp == 0 || header.width() == 0 || header.height() == 0) return false;
  if (static_cast<uint64_t>(header.stride()) < static_cast<uint64_t>(header.width()) * bpp) {
    return false;
  }
  return static_cast<uint64_t>(header.stride()) * header.height() <= payload_size;
}

cv::Mat ReceivedFrame::image() const {
  const int type = header.pixel_format() == proto::BGR8 ? CV_8UC3 : CV_8UC1;
  return cv::Mat(static_cast<int>(header.height()), static_cast<int>(header.width()), type,
                 const_cast<void*>(pixels.data()), header.stride());
}

FrameSubscriber::FrameSubscriber(zmq::context_t& context, const std::string& endpoint,
                                 const std::string& camera, int queue_frames)
    : socket_(context, zmq::socket_type::sub), camera_(camera) {
  // HWM counts message parts; a frame is three.
  socket_.set(zmq::sockopt::rcvhwm, queue_frames * 3);
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::subscribe, camera);
  socket_.connect(endpoint);
}

std::optional<ReceivedFrame> FrameSubscriber::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq::poll(&item, 1,
                  std::max<std::chrono::milliseconds>(left, std::chrono::milliseconds(0))) == 0) {
      return std::nullopt;
    }
    zmq::message_t topic;
    zmq::message_t header_bytes;
    ReceivedFrame frame;
    if (!socket_.recv(topic, zmq::recv_flags::dontwait)) continue;
    // Read every part of the message, whatever it looks like, so the next
    // receive starts on a message boundary.
    int parts = 1;
    bool more = topic.more();
    while (more) {
      zmq::message_t part;
      if (!socket_.recv(part)) break;
      more = part.more();
      if (parts == 1) header_bytes = std::move(part);
      if (parts == 2) frame.pixels = std::move(part);
      ++parts;
    }
    // Subscriptions match prefixes: "cam1" also receives "cam10".
    if (!camera_.empty() && topic.to_string_view() != camera_) continue;
    if (parts != 3 ||
        !frame.header.ParseFromArray(header_bytes.data(), static_cast<int>(header_bytes.size())) ||
        !frameIsConsistent(frame.header, frame.pixels.size())) {
      ++malformed_;
      continue;
    }
    frame.received_ns = monotonicNs();
    ++received_;
    const uint64_t seq = frame.header.sequence();
    auto [last, first] = last_sequence_.try_emplace(frame.header.camera(), seq);
    if (!first) {
      if (seq > last->second + 1) lost_ += seq - last->second - 1;
      last->second = seq;
    }
    return frame;
  }
}

}  // namespace picksight
