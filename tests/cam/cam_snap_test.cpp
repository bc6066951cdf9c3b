// picksight-cam snap: the saved file holds the frame's exact pixels, and
// every way a snap can fail is reported.
#include "cam_test_support.hpp"

using namespace picksight::camtest;
namespace proto = picksight::proto;

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
  const cv::Mat read = picksight::codecs::imread(file, cv::IMREAD_UNCHANGED);
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
  CHECK(picksight::codecs::imread(file, cv::IMREAD_UNCHANGED).size() == cv::Size(4, 2));
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
