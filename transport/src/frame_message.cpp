// The frame codec: Frame to wire message and back, and the subscriber.
#include "picksight/transport/frame_message.hpp"

#include <algorithm>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <utility>

#include "picksight/common/clock.hpp"
#include "picksight/transport/control_client.hpp"

namespace picksight::transport {
namespace {

// What ZeroMQ holds while it sends a frame's pixels without copying them.
struct SentPixels {
  cv::Mat image;
  std::shared_ptr<const void> owner;
};

// ZeroMQ calls this from its I/O thread when the last subscriber has been
// sent the pixels.
void releasePixels(void* /*data*/, void* hint) { delete static_cast<SentPixels*>(hint); }

// The header of `f` sent with the pixels of `img` (its image, or a dense copy).
proto::FrameHeader headerOf(const Frame& f, const cv::Mat& img) {
  proto::FrameHeader h;
  h.set_camera(f.info.camera);
  h.set_sequence(f.info.sequence);
  h.set_device_timestamp_ns(f.info.device_timestamp_ns);
  h.set_host_timestamp_ns(f.info.host_timestamp_ns);
  h.set_width(static_cast<uint32_t>(img.cols));
  h.set_height(static_cast<uint32_t>(img.rows));
  h.set_stride(static_cast<uint32_t>(img.step[0]));
  h.set_pixel_format(img.channels() == 3 ? proto::BGR8 : proto::MONO8);
  h.set_roi_x(static_cast<uint32_t>(f.mapping.roi_x));
  h.set_roi_y(static_cast<uint32_t>(f.mapping.roi_y));
  h.set_scale_x(f.mapping.scale_x);
  h.set_scale_y(f.mapping.scale_y);
  h.set_triggered(f.info.triggered);
  h.set_compressed(f.info.compressed);
  for (const auto& t : f.truth) {
    auto* p = h.add_truth();
    p->set_type(t.type);
    p->set_x(t.x);
    p->set_y(t.y);
    p->set_angle_deg(t.angle_deg);
    p->set_symmetry_deg(t.symmetry_deg);
    p->set_area_px(t.area_px);
  }
  return h;
}

// The frame a serialized header and its pixels describe, or nullopt.
std::optional<Frame> parsedFrame(const void* header, size_t size, zmq::message_t pixels) {
  proto::FrameHeader h;
  if (!h.ParseFromArray(header, static_cast<int>(size))) return std::nullopt;
  return decodeFrame(h, std::move(pixels));
}

}  // namespace

proto::FrameHeader frameHeaderOf(const Frame& frame) { return headerOf(frame, frame.image); }

void sendFrame(zmq::socket_t& socket, const Frame& frame) {
  // The payload is rows of `stride` bytes, the last one included: a view
  // into a larger image is copied to a dense one first.
  auto* held =
      new SentPixels{frame.image.isContinuous() ? frame.image : frame.image.clone(), frame.owner};
  const std::string header = headerOf(frame, held->image).SerializeAsString();
  zmq::message_t pixels(held->image.data, held->image.total() * held->image.elemSize(),
                        releasePixels, held);
  // PUB never blocks: a subscriber whose pipe is full simply misses the message.
  socket.send(zmq::buffer(frame.info.camera), zmq::send_flags::sndmore);
  socket.send(zmq::buffer(header), zmq::send_flags::sndmore);
  socket.send(pixels, zmq::send_flags::none);
}

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

std::optional<Frame> decodeFrame(const proto::FrameHeader& h, zmq::message_t pixels) {
  if (!frameIsConsistent(h, pixels.size())) return std::nullopt;
  auto bytes = std::make_shared<zmq::message_t>(std::move(pixels));
  Frame frame;
  const int type = h.pixel_format() == proto::BGR8 ? CV_8UC3 : CV_8UC1;
  // Nobody writes into a frame: the const_cast only satisfies cv::Mat.
  frame.image =
      cv::Mat(static_cast<int>(h.height()), static_cast<int>(h.width()), type,
              const_cast<void*>(static_cast<const zmq::message_t&>(*bytes).data()), h.stride());
  frame.owner = std::move(bytes);
  frame.mapping.roi_x = h.roi_x();
  frame.mapping.roi_y = h.roi_y();
  // A sender that leaves the scale out means no resize.
  frame.mapping.scale_x = h.scale_x() > 0 ? h.scale_x() : 1.0;
  frame.mapping.scale_y = h.scale_y() > 0 ? h.scale_y() : 1.0;
  frame.info.camera = h.camera();
  frame.info.sequence = h.sequence();
  frame.info.device_timestamp_ns = h.device_timestamp_ns();
  frame.info.host_timestamp_ns = h.host_timestamp_ns();
  frame.info.width = h.width();
  frame.info.height = h.height();
  frame.info.triggered = h.triggered();
  frame.info.compressed = h.compressed();
  frame.truth.reserve(static_cast<size_t>(h.truth_size()));
  for (const auto& t : h.truth()) {
    frame.truth.push_back(
        TruthPart{t.type(), t.x(), t.y(), t.angle_deg(), t.symmetry_deg(), t.area_px()});
  }
  return frame;
}

FrameSubscriber::FrameSubscriber(zmq::context_t& context, const std::string& endpoint,
                                 const std::string& camera, int queue_frames,
                                 const std::optional<CurveClientKeys>& curve,
                                 const std::string& control_endpoint)
    : context_(context),
      socket_(context, zmq::socket_type::sub),
      camera_(camera),
      curve_(curve),
      control_endpoint_(control_endpoint) {
  // The frames' socket itself is plain: with CURVE they come sealed.
  if (curve_ && control_endpoint_.empty()) {
    throw std::invalid_argument(
        "a CURVE frame subscriber needs the video server's control endpoint (the frames' key)");
  }
  // HWM counts message parts; a frame is three.
  socket_.set(zmq::sockopt::rcvhwm, queue_frames * 3);
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::subscribe, camera);
  socket_.connect(endpoint);
  // The key asked now, while the subscription reaches the server: asked at
  // the first frame, the frames that come during the CURVE handshake and
  // the request would wait in a queue of `queue_frames`.
  if (curve_) askKey();
}

void FrameSubscriber::askKey() {
  key_asked_ = std::chrono::steady_clock::now();
  ControlClient control(context_, control_endpoint_, kDefaultControlTimeout, curve_);
  proto::ControlRequest request;
  request.mutable_frame_key();
  const auto reply = control.call(request);
  if (!reply || !reply->has_frame_key() || reply->frame_key().key().size() != 32) return;
  FrameKey k;
  std::memcpy(k.key.data(), reply->frame_key().key().data(), k.key.size());
  k.id = reply->frame_key().key_id();
  if (!key_ || key_->id != k.id) last_sequence_.clear();  // a new run of the server
  key_ = k;
}

std::optional<Frame> FrameSubscriber::receive(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  // Past the deadline after a message that gave no frame, give up: a
  // stream of messages that are all skipped (a plain server's frames to a
  // CURVE subscriber, or sealed ones whose key is refused) would keep the
  // poll below from ever timing out.
  for (bool once = true;; once = false) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (!once && left.count() <= 0) return std::nullopt;
    zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq::poll(&item, 1,
                  std::max<std::chrono::milliseconds>(left, std::chrono::milliseconds(0))) == 0) {
      return std::nullopt;
    }
    zmq::message_t topic;
    zmq::message_t header_bytes;
    zmq::message_t pixels;
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
      if (parts == 2) pixels = std::move(part);
      ++parts;
    }
    // Subscriptions match prefixes: "cam1" also receives "cam10".
    if (!camera_.empty() && topic.to_string_view() != camera_) continue;
    std::optional<Frame> frame;
    if (parts != 3) {
      ++malformed_;
      continue;
    }
    if (curve_) {
      frame = openSealed(topic, header_bytes, pixels);
      if (!frame) continue;
    } else {
      frame = parsedFrame(header_bytes.data(), header_bytes.size(), std::move(pixels));
      if (!frame) {
        ++malformed_;
        continue;
      }
    }
    const uint64_t seq = frame->info.sequence;
    auto [last, first] = last_sequence_.try_emplace(frame->info.camera, seq);
    if (!first) {
      // Under one key a sealed frame's sequence only grows: one that does
      // not is a recorded frame sent again (a restarted server has a new
      // key, and the sequences start afresh with it).
      if (curve_ && seq <= last->second) {
        ++malformed_;
        continue;
      }
      if (seq > last->second + 1) lost_ += seq - last->second - 1;
      last->second = seq;
    }
    frame->info.received_ns = monotonicNs();
    ++received_;
    return frame;
  }
}

FrameSubscriber::~FrameSubscriber() = default;

std::optional<Frame> FrameSubscriber::openSealed(const zmq::message_t& topic,
                                                 const zmq::message_t& envelope,
                                                 zmq::message_t& pixels) {
  const std::optional<uint64_t> id = sealedKeyId(envelope);
  if (!id) {
    ++malformed_;  // a plain frame: not taken from a server that should seal
    return std::nullopt;
  }
  if (!key_ || key_->id != *id) {
    // Asked at most once a second: frames under a key the server does not
    // give (a forger's, a refused client's) must not flood the control
    // socket, nor stall this subscriber for a timeout each.
    constexpr auto kAskEvery = std::chrono::seconds(1);
    const auto now = std::chrono::steady_clock::now();
    if (now - key_asked_ < kAskEvery) {
      ++unopened_;
      return std::nullopt;
    }
    askKey();
    if (!key_ || key_->id != *id) {
      ++unopened_;
      return std::nullopt;
    }
  }
  const auto opened = openSealedFrame(topic, envelope, pixels, *key_);
  // The frame is a view on the opened pixels, the tag's bytes after them
  // left unread.
  std::optional<Frame> frame;
  if (opened) frame = parsedFrame(opened->data(), opened->size(), std::move(pixels));
  if (!frame) ++malformed_;
  return frame;
}

}  // namespace picksight::transport
