// CameraFeed's JPEGs against a real video server: made by the encoder thread
// only when a viewer asks, once per frame for every viewer.
#include <chrono>
#include <cstdint>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "cell_fixture.hpp"
#include "picksight.pb.h"
#include "picksight/transport/control_client.hpp"
#include "picksight/web/camera_feed.hpp"

namespace {
using namespace std::chrono_literals;
using picksight::e2e::VideoServerProcess;
using picksight::web::CameraFeed;

// Triggers cam0 until `feed` has received one more frame (the first
// triggers may come before its subscription is connected); that frame's
// generation.
uint64_t triggerFrame(zmq::context_t& context, const VideoServerProcess& server, CameraFeed& feed) {
  picksight::transport::ControlClient client(context, server.control, 5000ms);
  picksight::proto::ControlRequest trigger;
  trigger.mutable_trigger()->set_camera("cam0");
  const uint64_t before = feed.generation();
  bool received = false;
  for (int attempt = 0; attempt < 50 && !received; ++attempt) {
    REQUIRE(client.call(trigger));
    received = feed.waitNewer(before, 1s) != before;
  }
  REQUIRE(received);
  return feed.generation();
}

}  // namespace

TEST_CASE("a frame's JPEG is made when asked and once for every viewer", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=320,height=240,parts=2", "--mode", "trigger"});
  zmq::context_t context;
  CameraFeed feed(context, server.frames, "cam0");
  CHECK(feed.jpeg(0, 100ms) == nullptr);  // no frame yet
  const uint64_t first = triggerFrame(context, server, feed);
  CHECK(feed.encodedFrames() == 0);  // nobody asked
  const auto jpeg = feed.jpeg(first, 10s);
  REQUIRE(jpeg != nullptr);
  CHECK(jpeg->generation == first);
  CHECK(jpeg->sequence == feed.latest()->info.sequence);
  CHECK(jpeg->bytes.substr(0, 2) == "\xFF\xD8");  // a JPEG file
  CHECK(feed.jpeg(first, 10s) == jpeg);           // the same for the next viewer
  CHECK(feed.jpeg() == jpeg);
  CHECK(feed.encodedFrames() == 1);

  const uint64_t second = triggerFrame(context, server, feed);
  const auto next = feed.jpeg(second, 10s);
  REQUIRE(next != nullptr);
  CHECK(next->generation == second);
  CHECK(next->sequence > jpeg->sequence);
  CHECK(feed.encodedFrames() == 2);
}
