// Test support for picksight-cam's tests: a fake control server on a real
// ZeroMQ REP socket, a way to run the CLI as a user would, canned replies.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include <opencv2/core.hpp>
#include <zmq.hpp>
#include "picksight/codecs/codecs.hpp"

#include "cam_cli.hpp"
#include "picksight.pb.h"
#include "reply_printer.hpp"
#include "temp_dir.hpp"

namespace picksight::camtest {

using picksight::cam::runCamCli;

// Generous: a loaded CI machine must never turn a passing test into a timeout.
inline const std::string kTimeoutMs = "10000";

// A control socket served by its own thread (which owns the socket), answering
// every request with the same canned reply and recording what it received.
// `delay` holds each reply back, as the real server does while it waits for a
// frame to snap.
class FakeServer {
 public:
  FakeServer(zmq::context_t& context, proto::ControlReply reply,
             std::chrono::milliseconds delay = std::chrono::milliseconds(0))
      : context_(context), reply_(std::move(reply)), delay_(delay) {
    thread_ = std::thread([this] { serve(); });
    endpoint_ = bound_.get_future().get();
  }
  ~FakeServer() { stop(); }
  FakeServer(const FakeServer&) = delete;
  FakeServer& operator=(const FakeServer&) = delete;

  const std::string& endpoint() const { return endpoint_; }

  // Stops the thread and returns the requests it received, in order. The
  // vector is only read after the join, so it needs no mutex.
  std::vector<proto::ControlRequest> stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return requests_;
  }
  // Valid after stop(): empty unless the server thread failed.
  const std::string& failure() const { return failure_; }

 private:
  void serve() {
    bool bound = false;
    try {
      zmq::socket_t socket(context_, zmq::socket_type::rep);
      socket.set(zmq::sockopt::linger, 0);
      socket.bind("tcp://127.0.0.1:*");
      bound_.set_value(socket.get(zmq::sockopt::last_endpoint));
      bound = true;
      const std::string reply_bytes = reply_.SerializeAsString();
      while (!stop_) {
        zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
        if (zmq::poll(&item, 1, std::chrono::milliseconds(20)) == 0) continue;
        zmq::message_t message;
        if (!socket.recv(message)) continue;
        proto::ControlRequest request;
        if (!request.ParseFromArray(message.data(), static_cast<int>(message.size()))) {
          failure_ += "unparsable request; ";
        }
        requests_.push_back(request);
        std::this_thread::sleep_for(delay_);
        socket.send(zmq::buffer(reply_bytes), zmq::send_flags::none);
      }
    } catch (const std::exception& e) {
      failure_ += e.what();
      if (!bound) bound_.set_value("server failed: " + failure_);
    }
  }

  zmq::context_t& context_;
  const proto::ControlReply reply_;
  const std::chrono::milliseconds delay_;
  std::promise<std::string> bound_;
  std::string endpoint_;
  std::atomic<bool> stop_{false};
  std::vector<proto::ControlRequest> requests_;  // server thread only until stop()
  std::string failure_;                          // server thread only until stop()
  std::thread thread_;
};

struct Run {
  int code;
  std::string out;
  std::string err;
};

inline Run runCli(zmq::context_t& context, const std::vector<std::string>& args) {
  std::ostringstream out;
  std::ostringstream err;
  const int code = runCamCli(args, out, err, context);
  return {code, out.str(), err.str()};
}

// Runs `args` against `server`, as a user would with --control.
inline Run runAt(zmq::context_t& context, const FakeServer& server, std::vector<std::string> args) {
  args.insert(args.begin(), {"--control", server.endpoint(), "--timeout", kTimeoutMs});
  return runCli(context, args);
}

inline proto::ControlReply okReply() {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);
  return reply;
}

// Expects exactly one request, and returns it.
inline proto::ControlRequest onlyRequest(FakeServer& server) {
  const std::vector<proto::ControlRequest> requests = server.stop();
  INFO("server failure: " << server.failure());
  REQUIRE(server.failure().empty());
  REQUIRE(requests.size() == 1);
  return requests.front();
}

// A port nothing listens on: bound once to get it from the kernel, then freed.
inline std::string unusedEndpoint(zmq::context_t& context) {
  zmq::socket_t socket(context, zmq::socket_type::rep);
  socket.set(zmq::sockopt::linger, 0);
  socket.bind("tcp://127.0.0.1:*");
  return socket.get(zmq::sockopt::last_endpoint);
}

using picksight::test::TempDir;

// Value of channel `c` of pixel (x, y) in the frames the tests snap: varied
// enough that a swapped channel, row or column shows.
inline std::uint8_t pixelValue(int x, int y, int c) {
  return static_cast<std::uint8_t>((x * 37 + y * 11 + c * 101 + 5) % 256);
}

// A snap reply whose rows are `stride` bytes apart; the padding after each row
// is 0xEE, so that a writer that ignored the stride would put it in the image.
inline proto::ControlReply snapReply(int width, int height, int channels, int stride) {
  proto::ControlReply reply = okReply();
  auto* h = reply.mutable_snap()->mutable_header();
  h->set_camera("cam0");
  h->set_sequence(77);
  h->set_width(static_cast<std::uint32_t>(width));
  h->set_height(static_cast<std::uint32_t>(height));
  h->set_stride(static_cast<std::uint32_t>(stride));
  h->set_pixel_format(channels == 3 ? proto::BGR8 : proto::MONO8);
  std::string pixels(static_cast<size_t>(stride) * static_cast<size_t>(height), '\xEE');
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        pixels[static_cast<size_t>(y * stride + x * channels + c)] =
            static_cast<char>(pixelValue(x, y, c));
      }
    }
  }
  reply.mutable_snap()->set_pixels(pixels);
  return reply;
}

// The image snapReply() describes, built pixel by pixel.
inline cv::Mat expectedImage(int width, int height, int channels) {
  cv::Mat image(height, width, channels == 3 ? CV_8UC3 : CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c)
        image.ptr<std::uint8_t>(y)[x * channels + c] = pixelValue(x, y, c);
    }
  }
  return image;
}

inline proto::Feature exposureFeature() {
  proto::Feature f;
  f.set_name("ExposureTimeAbs");
  f.set_type(proto::FLOAT);
  f.set_value("20000");
  f.set_has_range(true);
  f.set_min(10);
  f.set_max(1000000);
  f.set_unit("us");
  f.set_description("Exposure time");
  f.set_writable(true);
  return f;
}

inline proto::Feature triggerModeFeature() {
  proto::Feature f;
  f.set_name("TriggerMode");
  f.set_type(proto::ENUMERATION);
  f.set_value("Off");
  f.add_choices("Off");
  f.add_choices("On");
  f.set_writable(true);
  return f;
}

inline proto::ControlReply featureReply(const proto::Feature& feature) {
  proto::ControlReply reply = okReply();
  *reply.mutable_feature()->mutable_feature() = feature;
  return reply;
}

inline proto::ControlReply errorReply(proto::Error::Code code, const std::string& text) {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(code);
  reply.mutable_error()->set_text(text);
  return reply;
}

}  // namespace picksight::camtest
