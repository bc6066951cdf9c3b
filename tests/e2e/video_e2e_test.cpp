// Video server end to end: frames to several subscribers, ROI and resize at
// run time through picksight-cam, software trigger.
#include <catch2/catch.hpp>

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include "picksight/codecs/codecs.hpp"

#include "cell_fixture.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::transport;
using namespace std::chrono_literals;

namespace {
CommandResult cam(const VideoServerProcess& server, std::vector<std::string> args) {
  std::vector<std::string> argv = {binPath("picksight-cam"), "--control", server.control};
  argv.insert(argv.end(), args.begin(), args.end());
  return run(argv);
}
// The value of `key` in picksight-cam's "key: value" lines (values aligned
// with spaces), or "" when there is no such line.
std::string infoValue(const std::string& out, const std::string& key) {
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    const size_t value = line.find_first_not_of(' ', key.size() + 1);
    return value == std::string::npos ? "" : line.substr(value);
  }
  return "";
}
}  // namespace

TEST_CASE("ROI and resize change both the pixels and the header", "[e2e][video]") {
  // Noise-free, so two frames of the scene are identical pixel for pixel.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=800,height=600,parts=5,noise=0", "--fps", "20"});
  zmq::context_t context;
  FrameSubscriber sub(context, server.frames, "cam0", 4);
  auto full = receiveUntil(sub, [](const Frame& f) { return f.info.width == 800; });
  REQUIRE(full);
  CHECK(full->mapping.roi_x == 0);
  CHECK(full->mapping.scale_x == 1.0);
  const cv::Mat sensor = full->image.clone();

  REQUIRE(cam(server, {"roi", "cam0", "100", "50", "400", "300"}).exit_code == 0);
  auto cropped = receiveUntil(sub, [](const Frame& f) { return f.info.width == 400; });
  REQUIRE(cropped);
  CHECK(cropped->info.height == 300);
  CHECK(cropped->mapping.roi_x == 100);
  CHECK(cropped->mapping.roi_y == 50);
  CHECK(cropped->mapping.scale_x == 1.0);
  CHECK(cv::countNonZero(cropped->image != sensor(cv::Rect(100, 50, 400, 300))) == 0);

  REQUIRE(cam(server, {"size", "cam0", "200", "150"}).exit_code == 0);
  auto resized = receiveUntil(sub, [](const Frame& f) { return f.info.width == 200; });
  REQUIRE(resized);
  CHECK(resized->info.height == 150);
  CHECK(resized->mapping.roi_x == 100);
  CHECK(resized->mapping.scale_x == Approx(0.5));
  CHECK(resized->mapping.scale_y == Approx(0.5));
  cv::Mat expected;
  cv::resize(sensor(cv::Rect(100, 50, 400, 300)), expected, cv::Size(200, 150), 0, 0,
             cv::INTER_AREA);
  CHECK(cv::norm(resized->image, expected, cv::NORM_INF) <= 1);

  // Out of range is refused with the reason, and changes nothing.
  const auto refused = cam(server, {"roi", "cam0", "700", "0", "400", "300"});
  CHECK(refused.exit_code == 1);
  auto still = receiveUntil(sub, [](const Frame&) { return true; });
  REQUIRE(still);
  CHECK(still->info.width == 200);
}

TEST_CASE("two subscribers receive the same sequence numbers", "[e2e][video]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=4", "--fps", "25"});
  zmq::context_t context;
  FrameSubscriber a(context, server.frames, "cam0", 16);
  FrameSubscriber b(context, server.frames, "cam0", 16);
  // Both are connected once both have seen a frame; from the next sequence on
  // they must see the very same ones.
  auto first_a = a.receive(5s);
  auto first_b = b.receive(5s);
  REQUIRE(first_a);
  REQUIRE(first_b);
  const uint64_t start = std::max(first_a->info.sequence, first_b->info.sequence) + 1;
  auto collect = [&](FrameSubscriber& s) {
    std::vector<uint64_t> seqs;
    while (seqs.size() < 20) {
      auto f = s.receive(5s);
      if (!f) break;
      if (f->info.sequence >= start) seqs.push_back(f->info.sequence);
    }
    return seqs;
  };
  const auto seqs_a = collect(a);
  const auto seqs_b = collect(b);
  REQUIRE(seqs_a.size() == 20);
  CHECK(seqs_a == seqs_b);
  for (size_t i = 1; i < seqs_a.size(); ++i) CHECK(seqs_a[i] == seqs_a[i - 1] + 1);
}

TEST_CASE("a software trigger's frame carries the sequence its reply named", "[e2e][video]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--mode", "trigger"});
  zmq::context_t context;
  FrameSubscriber sub(context, server.frames, "cam0", 4);
  // No trigger, no frame: every frame the subscriber sees has the sequence
  // number of the trigger that asked for it, with no frame in between.
  uint64_t last = waitForSubscription(server, sub);
  for (int i = 0; i < 3; ++i) {
    const uint64_t before = realtimeNs();
    const auto reply = cam(server, {"--json", "trigger", "cam0"});
    REQUIRE(reply.exit_code == 0);
    const size_t at = reply.out.find("\"sequence\":");
    REQUIRE(at != std::string::npos);
    const auto seq =
        parseInt(reply.out.substr(at + 11, reply.out.find_first_of(",}", at) - at - 11));
    REQUIRE(seq);
    CHECK(static_cast<uint64_t>(*seq) == last + 1);
    auto frame = sub.receive(5s);
    REQUIRE(frame);
    CHECK(static_cast<long long>(frame->info.sequence) == *seq);
    last = frame->info.sequence;
    CHECK(frame->info.triggered);
    CHECK(frame->info.host_timestamp_ns > before);
  }
}

TEST_CASE("picksight-cam reports cameras and refuses unknown ones", "[e2e][video]") {
  VideoServerProcess server({"--source", "top=synthetic:width=640,height=480", "--source",
                             "side=synthetic:width=320,height=240,seed=2"});
  const auto list = cam(server, {"list"});
  CHECK(list.exit_code == 0);
  CHECK(list.out.find("top") != std::string::npos);
  CHECK(list.out.find("side") != std::string::npos);
  const auto info = cam(server, {"info", "side"});
  CHECK(info.exit_code == 0);
  INFO(info.out);
  // The camera asked for, not the other one: its name, source and sizes.
  CHECK(infoValue(info.out, "camera") == "side");
  CHECK(infoValue(info.out, "source") == "synthetic:width=320,height=240,seed=2");
  CHECK(infoValue(info.out, "sensor") == "320x240");
  CHECK(infoValue(info.out, "output") == "320x240");
  CHECK(cam(server, {"info", "front"}).exit_code == 1);
  CHECK(cam(server, {"roi", "top", "x", "0", "10", "10"}).exit_code == 2);
  CHECK(cam(server, {"stats"}).exit_code == 0);
}

TEST_CASE("bad video server options fail at start with the option named", "[e2e][video]") {
  auto r = run({binPath("picksight-video-server"), "--fps", "fast"});
  CHECK(r.exit_code == 2);
  r = run({binPath("picksight-video-server"), "--source", "cam0=synthetic:parts=lots"});
  CHECK(r.exit_code == 1);
  r = run({binPath("picksight-video-server"), "--source", "cam0=webcam:0"});
  CHECK(r.exit_code == 1);
}

TEST_CASE("a stalled subscriber loses frames on its own side only", "[e2e][video]") {
  // Full-HD frames fill a stalled reader's queues within a second.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=1920,height=1080,parts=4", "--fps", "15"});
  zmq::context_t context;
  FrameSubscriber stalled(context, server.frames, "cam0", 2);
  // A deep queue: on a loaded machine the reader may pause, but must not lose.
  FrameSubscriber reader(context, server.frames, "cam0", 64);
  REQUIRE(stalled.receive(5s));
  REQUIRE(reader.receive(5s));
  // The stalled subscriber now reads nothing while the other one reads 90
  // frames (6 s): its own queues overflow, the reader must not see a gap.
  const uint64_t lost_before = reader.framesLost();
  int received = 0;
  while (received < 90) {
    auto f = reader.receive(5s);
    REQUIRE(f);
    ++received;
  }
  CHECK(reader.framesLost() == lost_before);
  // The stalled one resumes and finds its own loss, and frames still come.
  // Up to about 30 frames can be waiting for it: ZeroMQ's queues, and
  // loopback TCP buffers that grow to 32 MB on the receiving side
  // (net.ipv4.tcp_rmem here: 16 full-HD frames); it failed twice reading
  // 30. The stall's 90 frames cannot all wait.
  uint64_t stalled_lost = 0;
  for (int i = 0; i < 90 && stalled_lost == 0; ++i) {
    REQUIRE(stalled.receive(5s));
    stalled_lost = stalled.framesLost();
  }
  CHECK(stalled_lost > 0);
  const auto stats = cam(server, {"--json", "stats"});
  CHECK(stats.exit_code == 0);
  CHECK(stats.out.find("\"subscribers\":2") != std::string::npos);
}

TEST_CASE("snap saves the next frame and close releases the camera until open resumes it",
          "[e2e][video]") {
  // Noise-free and static: every frame holds the very same pixels.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3,noise=0", "--fps", "20"});
  picksight::test::TempDir dir;
  const std::string file = dir.file("frame.png");
  zmq::context_t context;
  FrameSubscriber sub(context, server.frames, "cam0", 4);
  const auto published = sub.receive(5s);
  REQUIRE(published);
  REQUIRE(cam(server, {"snap", "cam0", file}).exit_code == 0);
  const cv::Mat saved = picksight::codecs::imread(file, cv::IMREAD_UNCHANGED);
  REQUIRE_FALSE(saved.empty());
  REQUIRE(saved.size() == cv::Size(640, 480));
  REQUIRE(saved.type() == CV_8UC1);
  CHECK(cv::countNonZero(saved != published->image) == 0);

  REQUIRE(cam(server, {"close", "cam0"}).exit_code == 0);
  const uint64_t closed_ns = realtimeNs();
  CHECK(cam(server, {"list"}).out.find("closed") != std::string::npos);
  CHECK(cam(server, {"snap", "cam0", file}).exit_code == 1);
  const uint64_t opening_ns = realtimeNs();
  REQUIRE(cam(server, {"open", "cam0"}).exit_code == 0);
  // Frames already on their way may still arrive; none was taken while the
  // camera was closed, and frames come again after open. How many were on
  // their way depends on how long the commands above took (socket buffers
  // hold dozens at 20 fps): read until a deadline, not a count.
  std::optional<Frame> resumed;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!resumed && std::chrono::steady_clock::now() < deadline) {
    auto f = sub.receive(5s);
    REQUIRE(f);
    const uint64_t taken = f->info.host_timestamp_ns;
    INFO("frame " << f->info.sequence << " taken at " << taken);
    CHECK_FALSE((taken > closed_ns && taken < opening_ns));
    if (taken > opening_ns) resumed = std::move(f);
  }
  REQUIRE(resumed);
  CHECK(cv::countNonZero(resumed->image != published->image) == 0);
  CHECK(cam(server, {"list"}).out.find("streaming") != std::string::npos);
}

TEST_CASE("a file camera follows its image replaced by one of another size", "[e2e][video]") {
  picksight::test::TempDir dir;
  const std::string path = dir.file("scene.png");
  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(480, 640, CV_8UC1, cv::Scalar(90))));
  VideoServerProcess server({"--source", "cam0=file:" + path, "--mode", "trigger"});
  const std::string snap = dir.file("snap.png");
  REQUIRE(cam(server, {"snap", "cam0", snap}).exit_code == 0);
  REQUIRE(picksight::codecs::imread(snap, cv::IMREAD_UNCHANGED).size() == cv::Size(640, 480));
  CHECK(infoValue(cam(server, {"info", "cam0"}).out, "sensor") == "640x480");

  // Replaced as a person saving another photograph would (renamed over it).
  for (const cv::Size size : {cv::Size(800, 600), cv::Size(320, 200)}) {
    const std::string next = dir.file("next.png");
    REQUIRE(picksight::codecs::imwrite(next, cv::Mat(size, CV_8UC1, cv::Scalar(120))));
    std::filesystem::rename(next, path);
    REQUIRE(cam(server, {"snap", "cam0", snap}).exit_code == 0);
    CHECK(picksight::codecs::imread(snap, cv::IMREAD_UNCHANGED).size() == size);
    // What clients map ROIs and parts through: the new size, no restart.
    const std::string info = cam(server, {"info", "cam0"}).out;
    INFO(info);
    const std::string wh = std::to_string(size.width) + "x" + std::to_string(size.height);
    CHECK(infoValue(info, "sensor") == wh);
    CHECK(infoValue(info, "roi") ==
          "x=0 y=0 width=" + std::to_string(size.width) + " height=" + std::to_string(size.height));
  }
}
