// Pins the stream driver: MJPEG over HTTP (as smartphone IP-camera apps
// serve it) from a server the test runs on loopback, frames with the right
// content, unavailable when the server stops, resuming when it restarts; a
// video file, which loops; the pipeline delay and "a frame after the
// request" judged by the frame's estimated exposure.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/videoio.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/common/clock.hpp"
#include "picksight/sources/source.hpp"
#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/pixel_format.hpp"
#include "stream/stream_source.hpp"

using namespace std::chrono_literals;
using namespace picksight::video;
using picksight::Result;
namespace fs = std::filesystem;

namespace {

// A minimal MJPEG-over-HTTP camera: every client gets
// multipart/x-mixed-replace with a JPEG part every 40 ms. The left half of
// the picture is BGR (level, 100, 200), the right half (50, 200, 50).
class MjpegHttpServer {
 public:
  ~MjpegHttpServer() { stop(); }

  // Binds 127.0.0.1:port (0 = a free one) and serves; returns the port.
  uint16_t start(uint16_t port = 0) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(listen_fd_ >= 0);
    const int one = 1;
    ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(port);
    REQUIRE(::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0);
    REQUIRE(::listen(listen_fd_, 8) == 0);
    socklen_t len = sizeof(addr);
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    stop_ = false;
    acceptor_ = std::thread([this] { acceptLoop(); });
    return port_;
  }

  // Closes the listening socket and every connection, like an app that quits.
  void stop() {
    stop_ = true;
    if (acceptor_.joinable()) acceptor_.join();
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    for (auto& t : clients_) t.join();
    clients_.clear();
  }

  void setLevel(int level) { level_ = level; }
  uint16_t port() const { return port_; }

 private:
  void acceptLoop() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const int fd = ::accept(listen_fd_, nullptr, nullptr);
      if (fd >= 0) clients_.emplace_back([this, fd] { serve(fd); });
    }
  }

  void serve(int fd) {
    // The request: read until the blank line (or give up).
    std::string request;
    char buf[1024];
    while (request.find("\r\n\r\n") == std::string::npos && !stop_) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
      if (n <= 0) break;
      request.append(buf, static_cast<size_t>(n));
    }
    const std::string head =
        "HTTP/1.0 200 OK\r\nContent-Type: multipart/x-mixed-replace; boundary=frame\r\n"
        "Cache-Control: no-cache\r\nConnection: close\r\n\r\n";
    bool ok = sendAll(fd, head);
    while (ok && !stop_) {
      cv::Mat image(240, 320, CV_8UC3, cv::Scalar(50, 200, 50));
      image(cv::Rect(0, 0, 160, 240)).setTo(cv::Scalar(level_.load(), 100, 200));
      std::vector<uint8_t> jpeg;
      picksight::codecs::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
      const std::string part =
          "--frame\r\nContent-Type: image/jpeg\r\nContent-Length: " + std::to_string(jpeg.size()) +
          "\r\n\r\n";
      ok = sendAll(fd, part) && sendAll(fd, std::string(jpeg.begin(), jpeg.end())) &&
           sendAll(fd, "\r\n");
      std::this_thread::sleep_for(40ms);
    }
    ::close(fd);
  }

  static bool sendAll(int fd, const std::string& data) {
    size_t sent = 0;
    while (sent < data.size()) {
      const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) return false;
      sent += static_cast<size_t>(n);
    }
    return true;
  }

  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> level_{120};
  std::thread acceptor_;
  std::vector<std::thread> clients_;  // acceptor thread only, joined in stop()
};

// The next frame, waiting out timeouts (generous: the test never times the source).
Result<SourceFrame> nextFrame(Source& source, std::chrono::seconds limit = 20s) {
  const auto end = std::chrono::steady_clock::now() + limit;
  for (;;) {
    auto frame = source.grab(500ms);
    if (frame || frame.error().code != SourceErrc::kTimeout ||
        std::chrono::steady_clock::now() > end)
      return frame;
  }
}

cv::Scalar meanOf(const SourceFrame& frame, cv::Rect area) {
  auto bgr = toOutputFormat(frame.image, frame.layout, OutputFormat::kBgr8);
  REQUIRE(bgr);
  return cv::mean((*bgr)(area));
}

bool near(const cv::Scalar& a, const cv::Scalar& b, double tolerance = 6) {
  for (int i = 0; i < 3; ++i) {
    if (std::abs(a[i] - b[i]) > tolerance) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("stream: MJPEG over HTTP arrives with its content, is lost and resumes with the server",
          "[video_server][stream]") {
  MjpegHttpServer server;
  const uint16_t port = server.start();
  auto made = makeSource("stream:http://127.0.0.1:" + std::to_string(port) + "/video");
  REQUIRE(made);
  Source& source = **made;
  CHECK(source.streams());
  REQUIRE(source.open());
  CHECK(source.info().sensor_width == 320);
  CHECK(source.info().sensor_height == 240);

  for (int i = 0; i < 3; ++i) {
    auto frame = nextFrame(source);
    if (!frame) FAIL(frame.error().message);
    CHECK(frame->image.size() == cv::Size(320, 240));
    CHECK(near(meanOf(*frame, cv::Rect(10, 10, 100, 200)), cv::Scalar(120, 100, 200)));
    CHECK(near(meanOf(*frame, cv::Rect(200, 10, 100, 200)), cv::Scalar(50, 200, 50)));
  }
  // New content shows up (the source keeps the newest frame, so it is soon).
  server.setLevel(30);
  bool changed = false;
  for (int i = 0; i < 200 && !changed; ++i) {
    auto frame = nextFrame(source);
    REQUIRE(frame);
    changed = near(meanOf(*frame, cv::Rect(10, 10, 100, 200)), cv::Scalar(30, 100, 200));
  }
  CHECK(changed);

  // The server goes away: the source says unavailable (after any frames in flight).
  server.stop();
  Result<SourceFrame> lost = nextFrame(source);
  for (int i = 0; i < 200 && lost; ++i) lost = nextFrame(source);
  REQUIRE_FALSE(lost);
  CHECK(lost.error().code == SourceErrc::kUnavailable);
  source.close();
  auto refused = source.open();
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == SourceErrc::kUnavailable);

  // Back on the same port: the reopen the camera does with back-off works.
  server.setLevel(200);
  server.start(port);
  Result<void> reopened = source.open();
  for (int i = 0; i < 20 && !reopened; ++i) {
    std::this_thread::sleep_for(250ms);
    reopened = source.open();
  }
  REQUIRE(reopened);
  auto again = nextFrame(source);
  if (!again) FAIL(again.error().message);
  CHECK(near(meanOf(*again, cv::Rect(10, 10, 100, 200)), cv::Scalar(200, 100, 200)));
  source.close();
}

TEST_CASE("stream: a video file plays every frame in order and loops", "[video_server][stream]") {
  char pattern[] = "/tmp/picksight-stream-XXXXXX";
  REQUIRE(mkdtemp(pattern) != nullptr);
  const fs::path dir(pattern);
  const std::string path = (dir / "clip.avi").string();
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, cv::Size(64, 48));
    REQUIRE(writer.isOpened());
    for (int i = 0; i < 5; ++i)
      writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(20 + 40 * i)));
  }
  auto made = makeSource("stream:" + path);
  REQUIRE(made);
  Source& source = **made;
  CHECK_FALSE(source.streams());  // paced by the camera, not by the file
  REQUIRE(source.open());
  for (int k = 0; k < 12; ++k) {
    auto frame = nextFrame(source);
    if (!frame) FAIL(frame.error().message);
    INFO("frame " << k);
    CHECK(std::abs(meanOf(*frame, cv::Rect(0, 0, 64, 48))[0] - (20 + 40 * (k % 5))) <= 4);
    CHECK(frame->compressed);  // what a stream carries went through a lossy codec
  }
  source.close();
  fs::remove_all(dir);

  auto missing = makeSource("stream:/nonexistent/clip.avi");
  REQUIRE(missing);
  auto opened = (*missing)->open();
  REQUIRE_FALSE(opened);
  CHECK(opened.error().code == SourceErrc::kUnavailable);
  CHECK_THAT(opened.error().message, Catch::Contains("/nonexistent/clip.avi"));
}

TEST_CASE("stream: source options name what is wrong", "[video_server][stream]") {
  auto parsed = parseStreamOptions("rtsp://cam/stream1|latency_ms=250");
  REQUIRE(parsed);
  CHECK(parsed->url == "rtsp://cam/stream1");
  CHECK(parsed->latency == 250ms);
  CHECK(parseStreamOptions("http://phone:8080/video")->latency == 0ms);
  for (const char* bad :
       {"rtsp://cam|latency_ms=-1", "rtsp://cam|latency_ms=10001", "rtsp://cam|latency_ms=abc",
        "rtsp://cam|transport=udp", "|latency_ms=1"}) {
    INFO(bad);
    auto refused = makeSource(std::string("stream:") + bad);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == SourceErrc::kBadConfig);
  }
}

TEST_CASE("stream: buffering is measured against the stream's clock only when it is one",
          "[video_server][stream]") {
  constexpr uint64_t kMs = 1000000;
  constexpr uint64_t kDecode = 3 * kMs;
  StreamDelay delay;
  // Presentation times that follow arrival (40 ms apart): one frame held
  // 50 ms longer than the others on its way shows that much delay.
  for (int i = 0; i < 20; ++i) {
    const uint64_t in = (1000 + 40 * static_cast<uint64_t>(i)) * kMs;
    CHECK(delay.add(in, in + kDecode, 40.0 * i) == std::chrono::nanoseconds(kDecode));
  }
  const uint64_t late = (1000 + 40 * 20 + 50) * kMs;
  CHECK(delay.add(late, late + kDecode, 40.0 * 20) == std::chrono::nanoseconds(kDecode + 50 * kMs));
  // A nominal 25 fps count while frames come every 100 ms (an MJPEG-over-HTTP
  // server): not a clock, only the decode time is known.
  StreamDelay nominal;
  for (int i = 0; i < 30; ++i) {
    const uint64_t in = (5000 + 100 * static_cast<uint64_t>(i)) * kMs;
    CHECK(nominal.add(in, in + kDecode, 40.0 * i) == std::chrono::nanoseconds(kDecode));
  }
  // No presentation time at all.
  StreamDelay none;
  CHECK(none.add(10 * kMs, 10 * kMs + kDecode, -1) == std::chrono::nanoseconds(kDecode));
}

namespace {
class NoSink : public FrameSink {
 public:
  void publish(picksight::Frame) override {}
};
}  // namespace

TEST_CASE("stream: a snap or a trigger never gets a frame exposed before the request",
          "[video_server][stream]") {
  MjpegHttpServer server;
  const uint16_t port = server.start();
  // A phone's 2 s of latency: frames arriving within 2 s of a request were
  // exposed before it, by estimate, whatever the machine's load.
  const std::string uri =
      "stream:http://127.0.0.1:" + std::to_string(port) + "/video|latency_ms=2000";
  auto made = makeSource(uri);
  REQUIRE(made);
  CHECK((*made)->reportsAge());
  CameraConfig config;
  config.name = "phone";
  config.uri = uri;
  NoSink sink;
  Camera camera(config, std::move(*made), sink);
  camera.start();
  REQUIRE(camera.waitForFrame(1, 30s));

  const auto served = [&camera] {
    const uint64_t requested = picksight::realtimeNs();
    auto ticket = camera.trigger();
    REQUIRE(ticket);
    auto frame = camera.waitForFrame(ticket->sequence, 60s);
    REQUIRE(frame);
    // host_timestamp_ns is the estimated exposure (arrival minus the delay).
    CHECK(frame->info.host_timestamp_ns >= requested);
  };
  for (int i = 0; i < 2; ++i) served();
  REQUIRE(camera.setMode(AcquisitionMode::kTrigger, 0));
  served();
  // The frames left out were counted (the first frame after each request
  // arrived well within the 2 s).
  CHECK(camera.status().frames_before_request > 0);
  camera.stop();
}
