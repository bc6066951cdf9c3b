// Where the time of one LOCATE goes, step by step: the camera's steps timed
// in process on the same source, then the trigger path against a real video
// server (control round trip, camera wake, render, frame to the feed thread,
// hand-over to the request thread, vision pass), then the LOCATE round trip
// over TCP against the real vision app. Medians, by nearest rank.
//
// Stamps of one triggered frame: t0 (request, here), the trigger reply
// (here), the synthetic source's device timestamp (CLOCK_MONOTONIC when its
// grab started, on the same machine: the render is the synthetic camera's
// exposure, on the trigger path as a real exposure is), its host timestamp
// (CLOCK_REALTIME when the grab ended, turned monotonic here), received_ns
// (the feed thread decoded it), the request thread woken, the vision pass
// done.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "opencv_baseline.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/link/frame_feed.hpp"
#include "picksight/sources/source.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/video_server/frame_pipeline.hpp"
#include "picksight/video_server/pixel_format.hpp"

namespace {
using namespace std::chrono_literals;
using picksight::monotonicNs;

double msBetween(uint64_t from_ns, uint64_t to_ns) {
  return (static_cast<double>(to_ns) - static_cast<double>(from_ns)) / 1e6;
}

double median(const std::vector<double>& ms) { return picksight::bench::nearestRank(ms, 50); }

void row(const char* what, const std::vector<double>& ms) {
  std::printf("  %-58s %8.3f %8.3f\n", what, median(ms), picksight::bench::nearestRank(ms, 90));
}

// The camera's own steps, in process, on frames of the same synthetic source.
struct CameraSteps {
  std::vector<double> render, grab, standardize, header_encode, header_decode, bare_transfer;
};

CameraSteps timeCameraSteps(const std::string& uri, const picksight::bench::LocateArgs& args) {
  const int runs = args.requests;
  CameraSteps t;
  // The render itself: the synthetic camera's exposure.
  picksight::synthetic::SceneOptions scene;
  scene.width = args.width;
  scene.height = args.height;
  scene.parts = args.parts;
  scene.seed = 5;
  const picksight::synthetic::SceneRenderer renderer(scene);
  cv::Mat rendered;
  for (int i = 0; i < runs; ++i) {
    const uint64_t a = monotonicNs();
    renderer.renderInto(static_cast<uint64_t>(i), rendered);
    t.render.push_back(msBetween(a, monotonicNs()));
  }
  auto source = picksight::video::makeSource(uri);
  if (!source || !(*source)->open()) return t;
  // Bare ZeroMQ PUB/SUB of the same bytes over loopback TCP: the transfer's physics.
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub);
  zmq::socket_t sub(context, zmq::socket_type::sub);
  pub.bind("tcp://127.0.0.1:*");
  sub.set(zmq::sockopt::subscribe, "");
  sub.connect(pub.get(zmq::sockopt::last_endpoint));
  std::this_thread::sleep_for(200ms);  // the subscription travels to the publisher
  for (int i = 0; i < runs; ++i) {
    uint64_t a = monotonicNs();
    auto grabbed = (*source)->grab(1000ms);
    uint64_t b = monotonicNs();
    if (!grabbed) continue;
    t.grab.push_back(msBetween(a, b));
    auto out = picksight::video::applyOutputSettings(*grabbed, {});
    a = monotonicNs();
    t.standardize.push_back(msBetween(b, a));
    if (!out) continue;
    picksight::Frame frame;
    frame.image = out->image;
    frame.info.camera = "cam0";
    frame.truth = grabbed->truth;
    b = monotonicNs();
    const std::string header = picksight::transport::frameHeaderOf(frame).SerializeAsString();
    a = monotonicNs();
    t.header_encode.push_back(msBetween(b, a));
    picksight::proto::FrameHeader parsed;
    parsed.ParseFromString(header);
    // The pixels lent, not copied, as ZeroMQ hands over a received message.
    auto decoded = picksight::transport::decodeFrame(
        parsed, zmq::message_t(
                    frame.image.data, frame.image.total() * frame.image.elemSize(),
                    [](void*, void*) {}, nullptr));
    b = monotonicNs();
    t.header_decode.push_back(msBetween(a, b));
    auto held = std::make_shared<cv::Mat>(frame.image);
    zmq::message_t pixels(
        held->data, held->total(), [](void*, void* hint) { delete static_cast<cv::Mat*>(hint); },
        new cv::Mat(*held));
    a = monotonicNs();
    pub.send(pixels, zmq::send_flags::none);
    zmq::message_t got;
    if (sub.recv(got)) t.bare_transfer.push_back(msBetween(a, monotonicNs()));
  }
  return t;
}

struct PathSamples {
  std::vector<double> trigger_rtt, to_frame, to_render_start, server_render, render_end_to_received,
      hand_over, pass, total;
};
}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  const auto args = picksight::bench::parseLocateArgs(argc, argv, {200, 1920, 1080, 20});
  const std::string dir = picksight::bench::binDir();
  const std::string params = "width=" + std::to_string(args.width) +
                             ",height=" + std::to_string(args.height) +
                             ",parts=" + std::to_string(args.parts) + ",seed=5";
  const CameraSteps steps = timeCameraSteps("synthetic:" + params, args);
  if (steps.grab.empty()) {
    std::cerr << "bench: the synthetic source did not open\n";
    return 1;
  }

  picksight::tool_support::Subprocess server(
      {dir + "/picksight-video-server", "--source", "cam0=synthetic:" + params, "--frames",
       "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*", "--mode", "trigger"});
  const auto frames = server.waitForLine("frames ", 10s);
  const auto control_endpoint = server.waitForLine("control ", 10s);
  if (!frames || !control_endpoint) return 1;

  // The vision app's trigger path, with stamps: the same calls as
  // picksight::link::VideoServerCamera::freshFrame, then its vision pass.
  PathSamples s;
  int failures = 0;
  {
    zmq::context_t context;
    picksight::link::FrameFeed feed(context, *frames, "cam0");
    picksight::transport::ControlClient control(context, *control_endpoint, 2000ms);
    feed.start();
    picksight::proto::ControlRequest trigger;
    trigger.mutable_trigger()->set_camera("cam0");
    // Both clocks read together: the host timestamp is CLOCK_REALTIME.
    const uint64_t realtime_ahead = picksight::realtimeNs() - monotonicNs();
    for (int i = 0; i < args.requests + 10; ++i) {
      const uint64_t t0 = monotonicNs();
      auto reply = control.call(trigger);
      const uint64_t t1 = monotonicNs();
      auto frame = reply ? feed.waitFor(reply->trigger().sequence(), t0, 2000ms) : nullptr;
      const uint64_t t2 = monotonicNs();
      if (!frame) {
        ++failures;
        continue;
      }
      const auto outcome = picksight::cell::locateInFrame(*frame, {}, nullptr, -1);
      const uint64_t t3 = monotonicNs();
      if (i < 10 || outcome.parts.empty()) continue;  // warm-up
      const uint64_t render_start = frame->info.device_timestamp_ns;
      const uint64_t grabbed = frame->info.host_timestamp_ns - realtime_ahead;
      s.trigger_rtt.push_back(msBetween(t0, t1));
      s.to_frame.push_back(msBetween(t0, t2));
      s.to_render_start.push_back(msBetween(t0, render_start));
      s.server_render.push_back(msBetween(render_start, grabbed));
      s.render_end_to_received.push_back(msBetween(grabbed, frame->info.received_ns));
      s.hand_over.push_back(msBetween(frame->info.received_ns, t2));
      s.pass.push_back(msBetween(t2, t3));
      s.total.push_back(msBetween(t0, t3));
    }
    feed.stop();
  }

  // The same LOCATE through the vision app, over TCP (the only subscriber now).
  std::vector<double> locate;
  const std::string data_dir = picksight::bench::makeDataDir();
  if (data_dir.empty()) return 1;
  {
    picksight::bench::VideoServerRun endpoints;
    endpoints.frames = *frames;
    endpoints.control = *control_endpoint;
    auto vision = picksight::bench::startVision(endpoints, data_dir);
    if (!vision) return 1;
    std::this_thread::sleep_for(300ms);
    picksight::tool_support::LineClient* robot = &vision->robot;
    for (int i = 0; i < args.requests + 10; ++i) {
      const uint64_t t0 = monotonicNs();
      auto r = robot->request("LOCATE 1", 10s);
      if (!r || r->rfind("OK", 0) != 0) {
        ++failures;
        continue;
      }
      if (i >= 10) locate.push_back(msBetween(t0, monotonicNs()));
    }
    robot->close();
    vision->process->terminate();
  }
  server.terminate();
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);

  std::printf("Trigger path of one LOCATE: %dx%d, %d parts, %zu triggered frames (%d failed)\n",
              args.width, args.height, args.parts, s.total.size(), failures);
  std::printf("  %-58s %8s %8s\n", "ms", "median", "p90");
  std::printf(" camera steps in process (same source, same frames):\n");
  row("render of one synthetic frame (clean scene + noise)", steps.render);
  row("standardize + output settings", steps.standardize);
  row("frame header encode (20 truth parts)", steps.header_encode);
  row("frame header parse + decode", steps.header_decode);
  row("bare ZeroMQ PUB/SUB of the pixels, loopback TCP", steps.bare_transfer);
  std::printf(" trigger path against the video server (stamps of each frame):\n");
  row("trigger request round trip (control socket)", s.trigger_rtt);
  row("trigger sent -> render starts (device timestamp)", s.to_render_start);
  row("grab in the server (device to host timestamp)", s.server_render);
  row("render ends -> frame decoded on the feed thread", s.render_end_to_received);
  row("frame decoded -> request thread woken", s.hand_over);
  row("trigger sent -> request thread has the frame", s.to_frame);
  row("vision pass (locateInFrame)", s.pass);
  row("trigger sent -> parts located", s.total);
  std::printf(" through the vision app:\n");
  row("LOCATE round trip over TCP", locate);
  std::printf("  (TCP request + reply and protocol: the LOCATE round trip minus the path above)\n");
  return failures == 0 ? 0 : 1;
}
