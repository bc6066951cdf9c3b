// picksight-cam against a real ZeroMQ REP socket: what it sends for each
// command, what it prints for people and scripts, and its exit codes.
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
#include <opencv2/imgcodecs.hpp>
#include <zmq.hpp>
#include "temp_dir.hpp"

#include "cam_cli.hpp"
#include "picksight.pb.h"
#include "reply_printer.hpp"

namespace {

using picksight::cam::runCamCli;
namespace proto = picksight::proto;

// Generous: a loaded CI machine must never turn a passing test into a timeout.
const std::string kTimeoutMs = "10000";

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

Run runCli(zmq::context_t& context, const std::vector<std::string>& args) {
  std::ostringstream out;
  std::ostringstream err;
  const int code = runCamCli(args, out, err, context);
  return {code, out.str(), err.str()};
}

// Runs `args` against `server`, as a user would with --control.
Run runAt(zmq::context_t& context, const FakeServer& server, std::vector<std::string> args) {
  args.insert(args.begin(), {"--control", server.endpoint(), "--timeout", kTimeoutMs});
  return runCli(context, args);
}

proto::ControlReply okReply() {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);
  return reply;
}

// Expects exactly one request, and returns it.
proto::ControlRequest onlyRequest(FakeServer& server) {
  const std::vector<proto::ControlRequest> requests = server.stop();
  INFO("server failure: " << server.failure());
  REQUIRE(server.failure().empty());
  REQUIRE(requests.size() == 1);
  return requests.front();
}

// A port nothing listens on: bound once to get it from the kernel, then freed.
std::string unusedEndpoint(zmq::context_t& context) {
  zmq::socket_t socket(context, zmq::socket_type::rep);
  socket.set(zmq::sockopt::linger, 0);
  socket.bind("tcp://127.0.0.1:*");
  return socket.get(zmq::sockopt::last_endpoint);
}

using picksight::test::TempDir;

// Value of channel `c` of pixel (x, y) in the frames the tests snap: varied
// enough that a swapped channel, row or column shows.
std::uint8_t pixelValue(int x, int y, int c) {
  return static_cast<std::uint8_t>((x * 37 + y * 11 + c * 101 + 5) % 256);
}

// A snap reply whose rows are `stride` bytes apart; the padding after each row
// is 0xEE, so that a writer that ignored the stride would put it in the image.
proto::ControlReply snapReply(int width, int height, int channels, int stride) {
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
cv::Mat expectedImage(int width, int height, int channels) {
  cv::Mat image(height, width, channels == 3 ? CV_8UC3 : CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c)
        image.ptr<std::uint8_t>(y)[x * channels + c] = pixelValue(x, y, c);
    }
  }
  return image;
}

proto::Feature exposureFeature() {
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

proto::Feature triggerModeFeature() {
  proto::Feature f;
  f.set_name("TriggerMode");
  f.set_type(proto::ENUMERATION);
  f.set_value("Off");
  f.add_choices("Off");
  f.add_choices("On");
  f.set_writable(true);
  return f;
}

proto::ControlReply featureReply(const proto::Feature& feature) {
  proto::ControlReply reply = okReply();
  *reply.mutable_feature()->mutable_feature() = feature;
  return reply;
}

proto::ControlReply errorReply(proto::Error::Code code, const std::string& text) {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(code);
  reply.mutable_error()->set_text(text);
  return reply;
}

}  // namespace

TEST_CASE("list prints an aligned table, or JSON", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* cameras = reply.mutable_list_cameras();
  auto* cam0 = cameras->add_cameras();
  cam0->set_name("cam0");
  cam0->set_source("synthetic:");
  cam0->set_state("streaming");
  cam0->set_mode(proto::FREERUN);
  auto* left = cameras->add_cameras();
  left->set_name("conveyor-left");
  left->set_source("aravis:Basler-12345");
  left->set_state("reconnecting");
  left->set_mode(proto::TRIGGER);
  FakeServer server(context, reply);

  SECTION("text") {
    const Run run = runAt(context, server, {"list"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out ==
          "NAME           SOURCE               STATE         MODE\n"
          "cam0           synthetic:           streaming     freerun\n"
          "conveyor-left  aravis:Basler-12345  reconnecting  trigger\n");
  }
  SECTION("JSON, with the option after the command") {
    const Run run = runAt(context, server, {"list", "--json"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"cameras":[{"name":"cam0","source":"synthetic:","state":"streaming",)"
                     R"("mode":"freerun"},{"name":"conveyor-left","source":"aravis:Basler-12345",)"
                     R"("state":"reconnecting","mode":"trigger"}]})"
                     "\n");
  }
  CHECK(onlyRequest(server).request_case() == proto::ControlRequest::kListCameras);
}

TEST_CASE("list of a server without cameras", "[cam]") {
  zmq::context_t context;
  // The list part left out entirely: proto3 cannot tell it from an empty list.
  FakeServer server(context, okReply());
  CHECK(runAt(context, server, {"list"}).out == "no cameras\n");
  CHECK(runAt(context, server, {"--json", "list"}).out == "{\"cameras\":[]}\n");
}

TEST_CASE("info prints key: value lines, or JSON with escaped strings", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* d = reply.mutable_describe_camera();
  d->mutable_summary()->set_name("cam0");
  d->mutable_summary()->set_source("aravis:Basler-12345");
  d->mutable_summary()->set_state("streaming");
  d->mutable_summary()->set_mode(proto::TRIGGER);
  d->set_vendor("Basler");
  d->set_model("acA1920-40gm \"rev\\2\"");
  d->set_serial("12345");
  d->set_sensor_width(1920);
  d->set_sensor_height(1200);
  d->mutable_roi()->set_x(100);
  d->mutable_roi()->set_y(50);
  d->mutable_roi()->set_width(800);
  d->mutable_roi()->set_height(600);
  d->set_output_width(400);
  d->set_output_height(300);
  d->set_pixel_format(proto::MONO8);
  d->set_fps(40.0);
  d->add_source_formats("Mono8");
  d->add_source_formats("Mono12");
  FakeServer server(context, reply);

  SECTION("text") {
    const Run run = runAt(context, server, {"info", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "camera:         cam0\n"
          "source:         aravis:Basler-12345\n"
          "state:          streaming\n"
          "mode:           trigger\n"
          "vendor:         Basler\n"
          "model:          acA1920-40gm \"rev\\2\"\n"
          "serial:         12345\n"
          "sensor:         1920x1200\n"
          "roi:            x=100 y=50 width=800 height=600\n"
          "output:         400x300\n"
          "pixel format:   mono8\n"
          "fps:            40.0\n"
          "source formats: Mono8, Mono12\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "info", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"name":"cam0","source":"aravis:Basler-12345","state":"streaming",)"
                     R"("mode":"trigger","vendor":"Basler","model":"acA1920-40gm \"rev\\2\"",)"
                     R"("serial":"12345","sensor_width":1920,"sensor_height":1200,)"
                     R"("roi":{"x":100,"y":50,"width":800,"height":600},"output_width":400,)"
                     R"("output_height":300,"pixel_format":"mono8","fps":40.0,)"
                     R"("source_formats":["Mono8","Mono12"]})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kDescribeCamera);
  CHECK(request.describe_camera().camera() == "cam0");
}

TEST_CASE("roi sends the rectangle and confirms it", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("text") {
    const Run run = runAt(context, server, {"roi", "cam0", "10", "20", "300", "200"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "cam0: ROI set to x=10 y=20 width=300 height=200\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "roi", "cam0", "10", "20", "300", "200"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"ok":true,"camera":"cam0","roi":{"x":10,"y":20,"width":300,"height":200}})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kSetRoi);
  CHECK(request.set_roi().camera() == "cam0");
  CHECK(request.set_roi().roi().x() == 10);
  CHECK(request.set_roi().roi().y() == 20);
  CHECK(request.set_roi().roi().width() == 300);
  CHECK(request.set_roi().roi().height() == 200);
}

TEST_CASE("size sends a target size or a scale", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("target size") {
    const Run run = runAt(context, server, {"size", "cam0", "640", "480"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: output size set to 640x480\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetSize);
    CHECK(request.set_size().camera() == "cam0");
    CHECK(request.set_size().width() == 640);
    CHECK(request.set_size().height() == 480);
    CHECK(request.set_size().scale() == 0.0);
  }
  SECTION("scale") {
    const Run run = runAt(context, server, {"size", "cam0", "--scale", "0.5"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: output scale set to 0.5\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetSize);
    CHECK(request.set_size().width() == 0);
    CHECK(request.set_size().height() == 0);
    CHECK(request.set_size().scale() == 0.5);
  }
  SECTION("scale, JSON") {
    const Run run = runAt(context, server, {"--json", "size", "cam0", "--scale", "0.25"});
    CHECK(run.code == 0);
    CHECK(run.out == "{\"ok\":true,\"camera\":\"cam0\",\"scale\":0.25}\n");
  }
}

TEST_CASE("mode and format send the enum values", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("free-run with a frame rate") {
    const Run run = runAt(context, server, {"mode", "cam0", "freerun", "15"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: mode set to freerun at 15 fps\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().mode() == proto::FREERUN);
    CHECK(request.set_mode().fps() == 15.0);
  }
  SECTION("trigger, frame rate left unchanged, JSON") {
    const Run run = runAt(context, server, {"--json", "mode", "cam0", "trigger"});
    CHECK(run.code == 0);
    CHECK(run.out == "{\"ok\":true,\"camera\":\"cam0\",\"mode\":\"trigger\"}\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().mode() == proto::TRIGGER);
    CHECK(request.set_mode().fps() == 0.0);
  }
  SECTION("format") {
    const Run run = runAt(context, server, {"format", "cam0", "bgr8"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: pixel format set to bgr8\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetFormat);
    CHECK(request.set_format().camera() == "cam0");
    CHECK(request.set_format().pixel_format() == proto::BGR8);
  }
}

TEST_CASE("trigger prints the sequence number the frame will carry", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  reply.mutable_trigger()->set_sequence(4242);
  SECTION("trigger mode") {
    reply.mutable_trigger()->set_triggered(true);
    FakeServer server(context, reply);
    const Run text = runAt(context, server, {"trigger", "cam0"});
    CHECK(text.code == 0);
    CHECK(text.out == "cam0: triggered, the frame will carry sequence 4242\n");
    const Run json = runAt(context, server, {"--json", "trigger", "cam0"});
    CHECK(json.code == 0);
    CHECK(json.out == "{\"camera\":\"cam0\",\"sequence\":4242,\"triggered\":true}\n");
    const std::vector<proto::ControlRequest> requests = server.stop();
    REQUIRE(requests.size() == 2);
    REQUIRE(requests[0].request_case() == proto::ControlRequest::kTrigger);
    CHECK(requests[0].trigger().camera() == "cam0");
  }
  SECTION("free-run: says the frame is not a dedicated one") {
    reply.mutable_trigger()->set_triggered(false);
    FakeServer server(context, reply);
    const Run run = runAt(context, server, {"trigger", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "cam0: camera is in free-run, the first frame after the request will carry "
          "sequence 4242\n");
  }
}

TEST_CASE("trigger with a reply that lacks the sequence number is an error", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  const Run run = runAt(context, server, {"trigger", "cam0"});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK_THAT(run.err, Catch::Contains("unexpected reply: no trigger sequence number"));
}

TEST_CASE("stats prints an aligned table with right-aligned numbers, or JSON", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  reply.mutable_statistics()->set_subscribers(3);
  auto* s = reply.mutable_statistics()->add_cameras();
  s->set_camera("cam0");
  s->set_frames_acquired(1200);
  s->set_frames_published(1198);
  s->set_frames_dropped(2);
  s->set_acquisition_errors(0);
  s->set_reconnects(1);
  s->set_fps(29.97);
  s->set_last_sequence(1199);
  FakeServer server(context, reply);

  SECTION("all cameras, text") {
    const Run run = runAt(context, server, {"stats"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "CAMERA  ACQUIRED  PUBLISHED  DROPPED  ERRORS  RECONNECTS   FPS  LAST SEQ\n"
          "cam0        1200       1198        2       0           1  30.0      1199\n"
          "subscribers: 3\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kStatistics);
    CHECK(request.statistics().camera().empty());
  }
  SECTION("one camera, JSON") {
    const Run run = runAt(context, server, {"--json", "stats", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"subscribers":3,"cameras":[{"camera":"cam0","frames_acquired":1200,)"
                     R"("frames_published":1198,"frames_dropped":2,"acquisition_errors":0,)"
                     R"("reconnects":1,"fps":29.97,"last_sequence":1199}]})"
                     "\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kStatistics);
    CHECK(request.statistics().camera() == "cam0");
  }
}

TEST_CASE("usage errors exit 2 with a message and contact no server", "[cam]") {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"roi", "cam0", "abc", "20", "300", "200"},
       "roi: X must be a non-negative integer, got 'abc'"},
      {{"roi", "cam0", "10", "-5", "300", "200"},
       "roi: Y must be a non-negative integer, got '-5'"},
      {{"roi", "cam0", "10", "20", "1.5", "200"},
       "roi: W must be a non-negative integer, got '1.5'"},
      {{"roi", "cam0", "10", "20", "300", "99999999999"}, "roi: H is too large, got '99999999999'"},
      {{"roi", "cam0", "10", "20", "300"},
       "roi: missing arguments; usage: picksight-cam roi CAM X Y W H"},
      {{"info"}, "info: missing arguments"},
      {{"info", "cam0", "cam1"}, "info: too many arguments (unexpected 'cam1')"},
      {{"info", ""}, "info: CAM must not be empty"},
      {{"list", "extra"}, "list: too many arguments (unexpected 'extra')"},
      {{"size", "cam0", "640"}, "size: missing arguments"},
      {{"size", "cam0", "640", "x480"}, "size: H must be a non-negative integer, got 'x480'"},
      {{"size", "cam0", "--scale", "0"}, "size: S must be a positive number, got '0'"},
      // A decimal comma is what a German locale would accept.
      {{"size", "cam0", "--scale", "1,5"}, "size: S must be a positive number, got '1,5'"},
      {{"mode", "cam0", "burst"}, "mode: mode must be 'freerun' or 'trigger', got 'burst'"},
      {{"mode", "cam0", "freerun", "fast"}, "mode: FPS must be a positive number, got 'fast'"},
      {{"mode", "cam0", "freerun", "15", "x"}, "mode: too many arguments (unexpected 'x')"},
      {{"format", "cam0", "rgb8"}, "format: format must be 'mono8' or 'bgr8', got 'rgb8'"},
      {{"trigger"}, "trigger: missing arguments; usage: picksight-cam trigger CAM"},
      {{"stats", "cam0", "cam1"}, "stats: too many arguments (unexpected 'cam1')"},
      {{"frobnicate", "cam0"}, "unknown command 'frobnicate'"},
      {{}, "missing command"},
      {{"--verbose", "list"}, "unknown option '--verbose'"},
      {{"--timeout", "soon", "list"}, "--timeout: MS must be a positive integer, got 'soon'"},
      {{"--timeout", "0", "list"}, "--timeout: MS must be a positive integer, got '0'"},
      {{"list", "--control"}, "--control: missing value"},
      {{"features"}, "features: missing arguments; usage: picksight-cam features CAM"},
      {{"features", "cam0", "Gain"}, "features: too many arguments (unexpected 'Gain')"},
      {{"get", "cam0"}, "get: missing arguments; usage: picksight-cam get CAM FEATURE"},
      {{"get", "cam0", ""}, "get: FEATURE must not be empty"},
      {{"set", "cam0", "GainRaw"},
       "set: missing arguments; usage: picksight-cam set CAM FEATURE VALUE"},
      {{"set", "", "GainRaw", "3"}, "set: CAM must not be empty"},
      {{"set", "cam0", "GainRaw", "3", "4"}, "set: too many arguments (unexpected '4')"},
      {{"open"}, "open: missing arguments; usage: picksight-cam open CAM"},
      {{"close", "cam0", "now"}, "close: too many arguments (unexpected 'now')"},
      {{"snap", "cam0"}, "snap: missing arguments; usage: picksight-cam snap CAM FILE"},
      {{"snap", "cam0", ""}, "snap: FILE must not be empty"},
      {{"snap", "cam0", "frame.xyz"}, "snap: no image writer for 'frame.xyz'"},
      {{"snap", "cam0", "frame"}, "snap: no image writer for 'frame'"},
  };
  zmq::context_t context;
  FakeServer server(context, okReply());
  for (const Case& c : cases) {
    std::string joined;
    for (const std::string& arg : c.args) joined += " '" + arg + "'";
    INFO("args:" << joined);
    const Run run = runAt(context, server, c.args);
    CHECK(run.code == 2);
    CHECK(run.out.empty());
    CHECK_THAT(run.err, Catch::StartsWith("picksight-cam: " + c.message));
  }
  // runCamCli waits for a reply to whatever it sends, so anything sent has
  // been received by the time the loop ends.
  CHECK(server.stop().empty());
  CHECK(server.failure().empty());
}

TEST_CASE("a malformed endpoint is a usage error", "[cam]") {
  zmq::context_t context;
  const Run run = runCli(context, {"--control", "not-an-endpoint", "list"});
  CHECK(run.code == 2);
  CHECK_THAT(run.err, Catch::Contains("invalid endpoint 'not-an-endpoint'"));
}

TEST_CASE("--help prints the usage on stdout", "[cam]") {
  zmq::context_t context;
  const Run run = runCli(context, {"list", "--help"});
  CHECK(run.code == 0);
  CHECK(run.err.empty());
  CHECK_THAT(run.out, Catch::StartsWith("usage: picksight-cam [--control ENDPOINT]"));
  CHECK_THAT(run.out, Catch::Contains("size CAM --scale S"));
  CHECK_THAT(run.out, Catch::Contains("features CAM"));
  CHECK_THAT(run.out, Catch::Contains("get CAM FEATURE"));
  CHECK_THAT(run.out, Catch::Contains("set CAM FEATURE VALUE"));
  CHECK_THAT(run.out, Catch::Contains("open CAM"));
  CHECK_THAT(run.out, Catch::Contains("close CAM"));
  CHECK_THAT(run.out, Catch::Contains("snap CAM FILE"));
}

TEST_CASE("a server error exits 1 with the server's text and code", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::UNKNOWN_CAMERA);
  reply.mutable_error()->set_text("unknown camera 'cam9'");
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"roi", "cam9", "0", "0", "64", "64"});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK(run.err ==
        "picksight-cam: roi: unknown camera 'cam9' (server error UNKNOWN_CAMERA, code 2)\n");
  CHECK(onlyRequest(server).set_roi().camera() == "cam9");
}

TEST_CASE("no server: exit 3 naming the endpoint and the timeout", "[cam]") {
  zmq::context_t context;
  const std::string endpoint = unusedEndpoint(context);
  const Run run = runCli(context, {"--control", endpoint, "--timeout", "200", "info", "cam0"});
  CHECK(run.code == 3);
  CHECK(run.out.empty());
  CHECK(run.err == "picksight-cam: no answer from " + endpoint +
                       " within 200 ms: is picksight-video-server running?\n");
}

TEST_CASE("JSON strings are escaped", "[cam]") {
  using picksight::cam::toJson;
  CHECK(toJson("plain") == "\"plain\"");
  CHECK(toJson("a\"b\\c") == "\"a\\\"b\\\\c\"");
  CHECK(toJson("line\nnext\ttab\r") == "\"line\\nnext\\ttab\\r\"");
  CHECK(toJson(std::string("\x01\x1f", 2)) == "\"\\u0001\\u001f\"");
  CHECK(toJson(std::string("nul\0x", 5)) == "\"nul\\u0000x\"");
  CHECK(toJson("caf\xc3\xa9") == "\"caf\xc3\xa9\"");  // UTF-8 passes through
  // Invalid UTF-8 (a camera's vendor string) must not make the output unreadable.
  CHECK(toJson("bad\xff") == "\"bad\xef\xbf\xbd\"");
}

TEST_CASE("toJson keeps key order and writes numbers JSON can read", "[cam]") {
  using picksight::cam::Json;
  Json json = Json::object();
  json["a"] = Json::array({1, 2.5, false, "x"});
  json["empty"] = Json::object();
  json["nan"] = std::numeric_limits<double>::quiet_NaN();
  json["big"] = std::numeric_limits<std::uint64_t>::max();
  json["k\"ey"] = Json::array({Json::object(), Json::object()});
  CHECK(picksight::cam::toJson(json) ==
        R"({"a":[1,2.5,false,"x"],"empty":{},"nan":null,"big":18446744073709551615,)"
        R"("k\"ey":[{},{}]})");
}

TEST_CASE("features prints names, types, values, ranges, units and access", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* list = reply.mutable_list_features();
  *list->add_features() = exposureFeature();
  auto* gain = list->add_features();
  gain->set_name("GainRaw");
  gain->set_type(proto::INTEGER);
  gain->set_value("0");
  gain->set_has_range(true);
  gain->set_max(10);
  gain->set_increment(1);
  gain->set_writable(true);
  *list->add_features() = triggerModeFeature();
  // GenICam float ranges often end at the largest double.
  auto* rate = list->add_features();
  rate->set_name("AcquisitionFrameRate");
  rate->set_type(proto::FLOAT);
  rate->set_value("25.5");
  rate->set_has_range(true);
  rate->set_min(0.1);
  rate->set_max(std::numeric_limits<double>::max());
  rate->set_unit("Hz");
  rate->set_writable(true);
  auto* model = list->add_features();
  model->set_name("DeviceModelName");
  model->set_type(proto::STRING);
  model->set_value("GV01");
  auto* software = list->add_features();
  software->set_name("TriggerSoftware");
  software->set_type(proto::COMMAND);
  software->set_writable(true);
  FakeServer server(context, reply);

  const Run run = runAt(context, server, {"features", "cam0"});
  CHECK(run.code == 0);
  CHECK(run.err.empty());
  CHECK(run.out ==
        "NAME                  TYPE         VALUE  RANGE                         UNIT  WRITABLE\n"
        "ExposureTimeAbs       float        20000  10..1000000                   us    yes\n"
        "GainRaw               integer      0      0..10, step 1                       yes\n"
        "TriggerMode           enumeration  Off    Off|On                              yes\n"
        "AcquisitionFrameRate  float        25.5   0.1..1.7976931348623157e+308  Hz    yes\n"
        "DeviceModelName       string       GV01                                       no\n"
        "TriggerSoftware       command                                                 yes\n");
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kListFeatures);
  CHECK(request.list_features().camera() == "cam0");
}

TEST_CASE("features as JSON: every field of every feature", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  *reply.mutable_list_features()->add_features() = exposureFeature();
  *reply.mutable_list_features()->add_features() = triggerModeFeature();
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"--json", "features", "cam0"});
  CHECK(run.code == 0);
  CHECK(run.out == R"({"camera":"cam0","features":[{"name":"ExposureTimeAbs","type":"float",)"
                   R"("value":"20000","has_range":true,"min":10.0,"max":1000000.0,"increment":0.0,)"
                   R"("choices":[],"unit":"us","description":"Exposure time","writable":true},)"
                   R"({"name":"TriggerMode","type":"enumeration","value":"Off","has_range":false,)"
                   R"("min":0.0,"max":0.0,"increment":0.0,"choices":["Off","On"],"unit":"",)"
                   R"("description":"","writable":true}]})"
                   "\n");
}

TEST_CASE("features of a camera without any", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  CHECK(runAt(context, server, {"features", "cam0"}).out == "cam0: no features\n");
  CHECK(runAt(context, server, {"--json", "features", "cam0"}).out ==
        "{\"camera\":\"cam0\",\"features\":[]}\n");
}

TEST_CASE("get prints the bare value, or the whole feature as JSON", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, featureReply(exposureFeature()));
  SECTION("text") {
    const Run run = runAt(context, server, {"get", "cam0", "ExposureTimeAbs"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "20000\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "get", "cam0", "ExposureTimeAbs"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"name":"ExposureTimeAbs","type":"float","value":"20000",)"
                     R"("has_range":true,"min":10.0,"max":1000000.0,"increment":0.0,"choices":[],)"
                     R"("unit":"us","description":"Exposure time","writable":true})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kGetFeature);
  CHECK(request.get_feature().camera() == "cam0");
  CHECK(request.get_feature().name() == "ExposureTimeAbs");
}

TEST_CASE("set sends the value as typed and prints the value read back", "[cam]") {
  zmq::context_t context;
  SECTION("text, with the unit") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "ExposureTimeAbs = 20000 us\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetFeature);
    CHECK(request.set_feature().camera() == "cam0");
    CHECK(request.set_feature().name() == "ExposureTimeAbs");
    CHECK(request.set_feature().value() == "20000");
  }
  SECTION("a camera that rounded the value: says what was asked") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "19999.5"});
    CHECK(run.code == 0);
    CHECK(run.out == "ExposureTimeAbs = 20000 us (requested 19999.5)\n");
  }
  SECTION("the same number written differently is not a rounding") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000.0"});
    CHECK(run.out == "ExposureTimeAbs = 20000 us\n");
  }
  SECTION("a negative value is a value, not an option") {
    proto::Feature offset;
    offset.set_name("BlackLevel");
    offset.set_type(proto::INTEGER);
    offset.set_value("-5");
    FakeServer server(context, featureReply(offset));
    const Run run = runAt(context, server, {"set", "cam0", "BlackLevel", "-5"});
    CHECK(run.code == 0);
    CHECK(run.out == "BlackLevel = -5\n");
    CHECK(onlyRequest(server).set_feature().value() == "-5");
  }
  SECTION("an empty string value") {
    proto::Feature user;
    user.set_name("DeviceUserID");
    user.set_type(proto::STRING);
    FakeServer server(context, featureReply(user));
    const Run run = runAt(context, server, {"set", "cam0", "DeviceUserID", ""});
    CHECK(run.code == 0);
    CHECK(run.out == "DeviceUserID = \n");
    const proto::ControlRequest request = onlyRequest(server);
    CHECK(request.set_feature().value().empty());
  }
  SECTION("JSON") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000", "--json"});
    CHECK(run.code == 0);
    CHECK_THAT(run.out, Catch::StartsWith(R"({"name":"ExposureTimeAbs","type":"float",)"
                                          R"("value":"20000",)"));
  }
}

TEST_CASE("feature errors exit 1 with the server's text", "[cam]") {
  struct Case {
    std::vector<std::string> args;
    proto::Error::Code code;
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"get", "cam0", "Exposure"},
       proto::Error::UNKNOWN_FEATURE,
       "unknown feature 'Exposure'",
       "picksight-cam: get: unknown feature 'Exposure' (server error UNKNOWN_FEATURE, code 7)\n"},
      {{"set", "cam0", "GainRaw", "99"},
       proto::Error::OUT_OF_RANGE,
       "GainRaw: 99 is out of range 0..10",
       "picksight-cam: set: GainRaw: 99 is out of range 0..10 (server error OUT_OF_RANGE, "
       "code 3)\n"},
      {{"set", "cam0", "GainRaw", "3"},
       proto::Error::CAMERA_UNAVAILABLE,
       "camera 'cam0' is disconnected",
       "picksight-cam: set: camera 'cam0' is disconnected (server error CAMERA_UNAVAILABLE, "
       "code 5)\n"},
      {{"features", "cam0"},
       proto::Error::CAMERA_UNAVAILABLE,
       "camera 'cam0' is disconnected",
       "picksight-cam: features: camera 'cam0' is disconnected (server error CAMERA_UNAVAILABLE, "
       "code 5)\n"},
  };
  zmq::context_t context;
  for (const Case& c : cases) {
    INFO("command: " << c.args[0] << ", error: " << c.text);
    FakeServer server(context, errorReply(c.code, c.text));
    const Run run = runAt(context, server, c.args);
    CHECK(run.code == 1);
    CHECK(run.out.empty());
    CHECK(run.err == c.expected);
  }
}

TEST_CASE("get and set with a reply that lacks the feature are errors", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"get", "cam0", "GainRaw"},
        std::vector<std::string>{"set", "cam0", "GainRaw", "3"}}) {
    INFO("command: " << args[0]);
    const Run run = runAt(context, server, args);
    CHECK(run.code == 1);
    CHECK(run.out.empty());
    CHECK_THAT(run.err, Catch::Contains("unexpected reply: no feature"));
  }
}

TEST_CASE("open and close send the camera and confirm", "[cam]") {
  struct Case {
    std::string command;
    proto::ControlRequest::RequestCase request_case;
    std::string text;
    std::string json;
  };
  const std::vector<Case> cases = {
      {"open", proto::ControlRequest::kOpenStream, "cam0: stream opened\n",
       "{\"ok\":true,\"camera\":\"cam0\",\"open\":true}\n"},
      {"close", proto::ControlRequest::kCloseStream, "cam0: stream closed, device released\n",
       "{\"ok\":true,\"camera\":\"cam0\",\"open\":false}\n"},
  };
  zmq::context_t context;
  for (const Case& c : cases) {
    INFO("command: " << c.command);
    FakeServer server(context, okReply());
    const Run text = runAt(context, server, {c.command, "cam0"});
    CHECK(text.code == 0);
    CHECK(text.out == c.text);
    const Run json = runAt(context, server, {"--json", c.command, "cam0"});
    CHECK(json.code == 0);
    CHECK(json.out == c.json);
    const std::vector<proto::ControlRequest> requests = server.stop();
    REQUIRE(requests.size() == 2);
    REQUIRE(requests[0].request_case() == c.request_case);
    CHECK((c.request_case == proto::ControlRequest::kOpenStream
               ? requests[0].open_stream().camera()
               : requests[0].close_stream().camera()) == "cam0");
  }
}

TEST_CASE("snap saves the frame with its exact pixels, honouring the stride", "[cam]") {
  struct Case {
    const char* name;
    int width, height, channels, stride;
    const char* format;
  };
  // Odd sizes and strides past the row: rows must be cut at the width.
  const Case c = GENERATE(Case{"mono8, packed rows", 5, 3, 1, 5, "mono8"},
                          Case{"mono8, padded rows", 5, 3, 1, 8, "mono8"},
                          Case{"bgr8, packed rows", 4, 3, 3, 12, "bgr8"},
                          Case{"bgr8, padded rows", 4, 3, 3, 17, "bgr8"});
  INFO(c.name);
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("frame.png");
  FakeServer server(context, snapReply(c.width, c.height, c.channels, c.stride));

  const Run run = runAt(context, server, {"snap", "cam0", file});
  CHECK(run.code == 0);
  CHECK(run.err.empty());
  CHECK(run.out == "saved " + std::to_string(c.width) + "x" + std::to_string(c.height) + " " +
                       c.format + " frame #77 to " + file + "\n");
  const cv::Mat read = cv::imread(file, cv::IMREAD_UNCHANGED);
  const cv::Mat expected = expectedImage(c.width, c.height, c.channels);
  REQUIRE(read.type() == expected.type());
  REQUIRE(read.size() == expected.size());
  CHECK(cv::norm(read, expected, cv::NORM_INF) == 0);
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kSnap);
  CHECK(request.snap().camera() == "cam0");
}

TEST_CASE("snap as JSON describes the saved frame", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("frame.png");
  proto::ControlReply reply = snapReply(4, 2, 1, 4);
  reply.mutable_snap()->mutable_header()->set_triggered(true);
  reply.mutable_snap()->mutable_header()->set_host_timestamp_ns(1700000000123456789);
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"--json", "snap", "cam0", file});
  CHECK(run.code == 0);
  CHECK(run.out == R"({"camera":"cam0","file":")" + file +
                       R"(","sequence":77,"width":4,"height":2,"pixel_format":"mono8",)"
                       R"("triggered":true,"device_timestamp_ns":0,)"
                       R"("host_timestamp_ns":1700000000123456789})"
                       "\n");
  CHECK(cv::imread(file, cv::IMREAD_UNCHANGED).size() == cv::Size(4, 2));
}

TEST_CASE("snap refuses a frame whose payload does not match its header", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("frame.png");
  // The last row of a padded frame is padded too: one byte short is short.
  proto::ControlReply reply = snapReply(5, 3, 1, 8);
  reply.mutable_snap()->mutable_pixels()->pop_back();
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"snap", "cam0", file});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK(run.err ==
        "picksight-cam: snap: inconsistent frame: 5x3 mono8 with stride 8 needs 24 bytes of "
        "pixels, got 23 from " +
            server.endpoint() + "\n");
  CHECK_FALSE(std::filesystem::exists(file));
}

TEST_CASE("snap with a stride shorter than a row is refused", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("frame.png");
  proto::ControlReply reply = snapReply(4, 3, 3, 12);
  reply.mutable_snap()->mutable_header()->set_stride(4);  // as if mono8
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"snap", "cam0", file});
  CHECK(run.code == 1);
  CHECK_THAT(run.err, Catch::Contains("inconsistent frame: 4x3 bgr8 with stride 4"));
  CHECK_FALSE(std::filesystem::exists(file));
}

TEST_CASE("snap into a directory that does not exist exits 1 naming the file", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("missing/frame.png");
  FakeServer server(context, snapReply(5, 3, 1, 5));
  const Run run = runAt(context, server, {"snap", "cam0", file});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK_THAT(run.err, Catch::StartsWith("picksight-cam: snap: could not save '" + file + "': "));
  // The server did nothing wrong.
  CHECK_THAT(run.err, !Catch::Contains(server.endpoint()));
}

TEST_CASE("snap: a server error exits 1 and writes nothing", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  const std::string file = dir.file("frame.png");
  FakeServer server(
      context, errorReply(proto::Error::TIMEOUT, "no frame from camera 'cam0' within 3000 ms"));
  const Run run = runAt(context, server, {"snap", "cam0", file});
  CHECK(run.code == 1);
  CHECK(run.err ==
        "picksight-cam: snap: no frame from camera 'cam0' within 3000 ms (server error TIMEOUT, "
        "code 8)\n");
  CHECK_FALSE(std::filesystem::exists(file));
}

TEST_CASE("snap waits longer than --timeout for the server to take the frame", "[cam]") {
  zmq::context_t context;
  TempDir dir;
  // The reply comes after 300 ms; --timeout 50 alone would give up before it.
  FakeServer server(context, snapReply(5, 3, 1, 5), std::chrono::milliseconds(300));
  const std::vector<std::string> options = {"--control", server.endpoint(), "--timeout", "50"};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), options.begin(), options.end());
    return args;
  };
  // The same delay makes any other command time out: the test can fail.
  CHECK(runCli(context, with({"get", "cam0", "GainRaw"})).code == 3);
  const Run run = runCli(context, with({"snap", "cam0", dir.file("frame.png")}));
  CHECK(run.code == 0);
  CHECK(run.err.empty());
}
