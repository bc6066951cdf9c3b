// Pins a camera's acquisition: one frame per trigger with the ticket's
// sequence, none without, increasing sequences in free-run, tickets after
// every published frame, output settings applied from the next frame,
// retries of a source that is not there yet, and frames that keep coming
// while a long feature listing runs.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"
#include "temp_dir.hpp"

#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/video_errors.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using picksight::Frame;
using picksight::video::AcquisitionMode;
using picksight::video::Camera;
using picksight::video::CameraConfig;
using picksight::video::OutputSettings;

namespace {

// Generous: only a broken camera takes this long.
constexpr auto kTimeout = 10s;
const std::string kSource = "synthetic:width=160,height=120,parts=2,size=30,seed=3";

// Collects published frames; tests wait on it.
class CollectingSink : public picksight::video::FrameSink {
 public:
  void publish(Frame frame) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      frames_.push_back(std::move(frame));
    }
    changed_.notify_all();
  }

  std::vector<Frame> frames() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_;
  }
  size_t count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_.size();
  }
  // Waits until `done(frames)` holds; false on timeout.
  bool waitUntil(const std::function<bool(const std::vector<Frame>&)>& done,
                 std::chrono::milliseconds timeout = kTimeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return done(frames_); });
  }
  bool waitForCount(size_t n) {
    return waitUntil([n](const std::vector<Frame>& f) { return f.size() >= n; });
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Frame> frames_;
};

CameraConfig config(AcquisitionMode mode, double fps = 10, const std::string& uri = kSource) {
  CameraConfig c;
  c.name = "cam1";
  c.uri = uri;
  c.mode = mode;
  c.fps = fps;
  return c;
}

std::unique_ptr<Camera> makeCamera(const CameraConfig& c, CollectingSink& sink) {
  auto source = picksight::video::makeSource(c.uri);
  REQUIRE(source);
  return std::make_unique<Camera>(c, std::move(*source), sink);
}

bool waitForStatus(const Camera& camera,
                   const std::function<bool(const picksight::video::CameraStatus&)>& done) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (!done(camera.status())) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

bool waitForState(const Camera& camera, const std::string& state) {
  return waitForStatus(camera, [&](const auto& s) { return s.state == state; });
}

using picksight::test::TempDir;

// A streaming camera of 8 x 8 pixels; what it delivers is the subclass's.
class TinyStreamingSource : public picksight::video::Source {
 public:
  void close() override {}
  picksight::video::SourceInfo info() const override {
    picksight::video::SourceInfo i;
    i.sensor_width = 8;
    i.sensor_height = 8;
    return i;
  }
  bool streams() const override { return true; }
};

// A streaming camera that delivers `good` frames after each open, then only
// bad frames (`bad`) or nothing: a stream that stops reaching the host.
class StallingSource : public TinyStreamingSource {
 public:
  struct Counters {
    std::atomic<int> opens{0};
    std::atomic<int> grabs{0};
    std::atomic<bool> hardware_configured{false};
  };
  StallingSource(int good, bool bad, std::shared_ptr<Counters> counters)
      : good_(good), bad_(bad), counters_(std::move(counters)) {}
  // A camera with a trigger input, as Aravis cameras have.
  bool hardwareTrigger() const override { return true; }
  picksight::Result<void> configureAcquisition(
      const picksight::video::AcquisitionRequest& request) override {
    counters_->hardware_configured =
        request.mode == AcquisitionMode::kHardwareTrigger && request.input.line == "Line2";
    return {};
  }
  picksight::video::DriverCounters driverCounters() const override {
    picksight::video::DriverCounters d;
    d.missing_packets = static_cast<uint64_t>(counters_->grabs.load());
    return d;
  }
  picksight::Result<void> open() override {
    ++counters_->opens;
    delivered_ = 0;
    return {};
  }
  picksight::Result<picksight::video::SourceFrame> grab(
      std::chrono::milliseconds timeout) override {
    using picksight::video::SourceErrc;
    ++counters_->grabs;
    if (delivered_ < good_) {
      ++delivered_;
      picksight::video::SourceFrame f;
      f.image = cv::Mat(8, 8, CV_8UC1, cv::Scalar(delivered_));
      return f;
    }
    // A device's grab blocks until its timeout; a short one keeps the test quick.
    std::this_thread::sleep_for(std::min<std::chrono::milliseconds>(timeout, 10ms));
    if (bad_) return picksight::makeError(SourceErrc::kBadValue, "frame 7 incomplete");
    return picksight::makeError(SourceErrc::kTimeout, "no frame");
  }

 private:
  const int good_;
  const bool bad_;
  const std::shared_ptr<Counters> counters_;
  int delivered_ = 0;
};

uint64_t maxSequence(const std::vector<Frame>& frames) {
  uint64_t m = 0;
  for (const auto& f : frames) m = std::max(m, f.info.sequence);
  return m;
}

}  // namespace

TEST_CASE("Camera in trigger mode publishes nothing without a trigger", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kTrigger), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "streaming"));
  // Absence, not speed: a camera that acquired on its own would have done so.
  std::this_thread::sleep_for(300ms);
  CHECK(sink.count() == 0);
  CHECK(camera->status().frames_acquired == 0);
}

TEST_CASE("Camera trigger tickets are consecutive and each gives exactly one frame",
          "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kTrigger), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "streaming"));

  std::vector<uint64_t> tickets;
  for (int i = 0; i < 5; ++i) {
    const auto t = camera->trigger();
    REQUIRE(t);
    CHECK(t->triggered);
    tickets.push_back(t->sequence);
  }
  for (size_t i = 1; i < tickets.size(); ++i) CHECK(tickets[i] == tickets[i - 1] + 1);

  REQUIRE(sink.waitForCount(tickets.size()));
  std::this_thread::sleep_for(300ms);  // no extra frame may follow
  const auto frames = sink.frames();
  REQUIRE(frames.size() == tickets.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].info.sequence == tickets[i]);
    CHECK(frames[i].info.triggered);
    CHECK(frames[i].info.camera == "cam1");
    CHECK(frames[i].image.size() == cv::Size(160, 120));
    CHECK(frames[i].truth.size() == 2);
    CHECK(frames[i].info.host_timestamp_ns > 0);
  }

  // A later trigger continues the numbering.
  const auto next = camera->trigger();
  REQUIRE(next);
  CHECK(next->sequence == tickets.back() + 1);
  REQUIRE(sink.waitForCount(tickets.size() + 1));
  CHECK(sink.frames().back().info.sequence == next->sequence);
  // The status is updated beside the hand-over to the sink, not before it.
  REQUIRE(waitForStatus(*camera, [&](const picksight::video::CameraStatus& s) {
    return s.frames_acquired >= tickets.size() + 1;
  }));
  CHECK(camera->status().frames_acquired == tickets.size() + 1);
  CHECK(camera->status().last_sequence == next->sequence);
}

TEST_CASE("Camera in free-run publishes increasing sequences untriggered", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 50), sink);
  camera->start();
  REQUIRE(sink.waitForCount(5));
  camera->stop();
  const auto frames = sink.frames();
  for (size_t i = 1; i < frames.size(); ++i)
    CHECK(frames[i].info.sequence > frames[i - 1].info.sequence);
  for (const auto& f : frames) CHECK_FALSE(f.info.triggered);
  CHECK(camera->status().state == "stopped");
}

TEST_CASE("Camera free-run trigger ticket follows every published frame", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 50), sink);
  camera->start();
  REQUIRE(sink.waitForCount(3));
  for (int i = 0; i < 3; ++i) {
    const uint64_t published = maxSequence(sink.frames());
    const auto ticket = camera->trigger();
    REQUIRE(ticket);
    CHECK_FALSE(ticket->triggered);
    CHECK(ticket->sequence > published);
    // ... and a frame with that sequence does come.
    CHECK(sink.waitUntil(
        [&](const std::vector<Frame>& f) { return maxSequence(f) >= ticket->sequence; }));
  }
}

TEST_CASE("Camera setOutput applies a ROI from the next frame", "[video_server]") {
  CollectingSink sink;
  // Noise-free: every frame holds the same scene, pixel for pixel.
  auto camera = makeCamera(config(AcquisitionMode::kTrigger, 10, kSource + ",noise=0"), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "streaming"));
  REQUIRE(camera->trigger());
  REQUIRE(sink.waitForCount(1));
  CHECK(sink.frames()[0].image.size() == cv::Size(160, 120));
  CHECK(cv::Point2d(sink.frames()[0].mapping.roi_x, sink.frames()[0].mapping.roi_y) ==
        cv::Point2d(0, 0));

  OutputSettings roi;
  roi.roi = cv::Rect(10, 20, 64, 48);
  REQUIRE(camera->setOutput(roi));
  CHECK(camera->output().roi == roi.roi);
  REQUIRE(camera->trigger());
  REQUIRE(sink.waitForCount(2));
  const auto cropped = sink.frames()[1];
  CHECK(cropped.image.size() == cv::Size(64, 48));
  CHECK(cv::Point2d(cropped.mapping.roi_x, cropped.mapping.roi_y) == cv::Point2d(10, 20));
  const cv::Mat sensor = sink.frames()[0].image;
  const cv::Mat region = sensor(roi.roi);
  CHECK(cv::countNonZero(cropped.image != region) == 0);

  OutputSettings scaled = roi;
  scaled.scale = 0.5;
  scaled.format = picksight::video::OutputFormat::kBgr8;
  REQUIRE(camera->setOutput(scaled));
  REQUIRE(camera->trigger());
  REQUIRE(sink.waitForCount(3));
  const auto small = sink.frames()[2];
  CHECK(small.image.size() == cv::Size(32, 24));
  CHECK(small.image.type() == CV_8UC3);
  CHECK(small.mapping.scale_x == 0.5);
  // The pixels are the region halved, in colour.
  cv::Mat expected;
  cv::resize(region, expected, cv::Size(32, 24), 0, 0, cv::INTER_AREA);
  cv::cvtColor(expected, expected, cv::COLOR_GRAY2BGR);
  CHECK(cv::norm(small.image, expected, cv::NORM_INF) <= 1);
  // Ground truth stays in sensor pixels.
  REQUIRE(small.truth.size() == 2);
  REQUIRE(sink.frames()[0].truth.size() == 2);
  for (size_t i = 0; i < 2; ++i) {
    CHECK(small.truth[i].x == sink.frames()[0].truth[i].x);
    CHECK(small.truth[i].y == sink.frames()[0].truth[i].y);
  }
}

TEST_CASE("Camera setOutput rejects a ROI beyond the sensor once open", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kTrigger), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "streaming"));
  OutputSettings beyond;
  beyond.roi = cv::Rect(100, 100, 100, 100);
  auto r = camera->setOutput(beyond);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("160x120"));
  CHECK(camera->output().roi.empty());
  CHECK(camera->status().info.sensor_width == 160);
}

TEST_CASE("Camera setMode switches between free-run and trigger", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 50), sink);
  camera->start();
  REQUIRE(sink.waitForCount(2));

  REQUIRE(camera->setMode(AcquisitionMode::kTrigger, 0));
  CHECK(camera->status().mode == AcquisitionMode::kTrigger);
  CHECK(camera->status().fps_setting == 50);  // fps 0 leaves it unchanged
  // A frame whose grab had begun may still arrive; after that, silence.
  std::this_thread::sleep_for(300ms);
  const size_t settled = sink.count();
  std::this_thread::sleep_for(300ms);
  CHECK(sink.count() == settled);

  const auto ticket = camera->trigger();
  REQUIRE(ticket);
  CHECK(ticket->triggered);
  REQUIRE(sink.waitForCount(settled + 1));
  CHECK(sink.frames().back().info.sequence == ticket->sequence);
  CHECK(sink.frames().back().info.triggered);

  REQUIRE(camera->setMode(AcquisitionMode::kFreeRun, 40));
  CHECK(camera->status().fps_setting == 40);
  REQUIRE(sink.waitForCount(settled + 4));
  CHECK_FALSE(sink.frames().back().info.triggered);

  CHECK_FALSE(camera->setMode(AcquisitionMode::kFreeRun, -1));
  CHECK_FALSE(camera->setMode(AcquisitionMode::kFreeRun, 5000));
  CHECK_FALSE(camera->setMode(AcquisitionMode::kFreeRun, std::nan("")));
  CHECK_FALSE(camera->setMode(AcquisitionMode::kFreeRun, HUGE_VAL));
  CHECK(camera->status().fps_setting == 40);
}

TEST_CASE("Camera retries a source that is missing and streams once it appears", "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");

  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 20, "file:" + path), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "reconnecting"));
  CHECK_THAT(camera->status().last_error, Catch::Contains(path));
  CHECK(sink.count() == 0);

  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(99))));
  CHECK(sink.waitForCount(1));
  CHECK(camera->status().state == "streaming");
  camera->stop();
  const auto frames = sink.frames();
  REQUIRE_FALSE(frames.empty());
  CHECK(frames[0].image.size() == cv::Size(40, 30));
  CHECK(frames[0].image.at<uint8_t>(0, 0) == 99);
}

TEST_CASE("Camera of a file that goes away fails after the grace period until it returns",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(99))));
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 20, "file:" + path), sink);
  camera->start();
  REQUIRE(sink.waitForCount(1));

  // Gone: a moment of the last image, then the camera says it fails.
  fs::remove(path);
  REQUIRE(waitForState(*camera, "reconnecting"));
  const auto failing = camera->status();
  CHECK_THAT(failing.last_error, Catch::Contains(path));
  CHECK(failing.acquisition_errors >= 1);
  // Garbage in its place: still failing, now saying why.
  std::ofstream(path) << "not an image";
  CHECK(waitForStatus(*camera, [](const auto& s) {
    return s.state == "reconnecting" &&
           s.last_error.find("not a readable image") != std::string::npos;
  }));
  // Back: streams the new image.
  const size_t before = sink.count();
  const std::string tmp = dir.file("scene.tmp.png");
  REQUIRE(picksight::codecs::imwrite(tmp, cv::Mat(30, 40, CV_8UC1, cv::Scalar(7))));
  fs::rename(tmp, path);
  REQUIRE(sink.waitForCount(before + 1));
  CHECK(waitForState(*camera, "streaming"));
  CHECK(sink.frames().back().image.at<uint8_t>(0, 0) == 7);
  CHECK(camera->status().last_error.empty());
}

TEST_CASE("Camera in an outage refuses triggers at once and never bursts afterwards",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kTrigger, 10, "file:" + path), sink);
  camera->start();
  REQUIRE(waitForState(*camera, "reconnecting"));
  for (int i = 0; i < 20; ++i) {
    const auto refused = camera->trigger();
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == picksight::video::SourceErrc::kUnavailable);
    CHECK_THAT(refused.error().message, Catch::Contains("cam1") && Catch::Contains(path));
  }
  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(99))));
  REQUIRE(waitForState(*camera, "streaming"));
  // Absence, not speed: the refused triggers would have been served by now.
  std::this_thread::sleep_for(300ms);
  CHECK(sink.count() == 0);
  CHECK(camera->status().frames_acquired == 0);
  // A trigger now is served, once.
  const auto ticket = camera->trigger();
  REQUIRE(ticket);
  REQUIRE(sink.waitForCount(1));
  CHECK(sink.frames()[0].info.sequence == ticket->sequence);

  camera->setOpen(false);
  REQUIRE(waitForState(*camera, "closed"));
  const auto closed = camera->trigger();
  REQUIRE_FALSE(closed);
  CHECK(closed.error().code == picksight::video::VideoErrc::kCameraClosed);
}

TEST_CASE("Camera that stops delivering frames is reported and reopened until frames return",
          "[video_server]") {
  auto counters = std::make_shared<StallingSource::Counters>();
  CollectingSink sink;
  CameraConfig c = config(AcquisitionMode::kFreeRun);
  c.no_frame_timeout = 300ms;
  Camera camera(c, std::make_unique<StallingSource>(3, false, counters), sink);
  camera.start();
  REQUIRE(sink.waitForCount(3));
  // Silence: said, counted, and the device reopened, which delivers again.
  REQUIRE(waitForStatus(camera, [](const auto& s) {
    return s.state == "reconnecting" && s.last_error.find("no good frame for 0.3 s") == 0;
  }));
  CHECK(camera.status().acquisition_errors >= 1);
  REQUIRE(sink.waitForCount(4));
  CHECK(counters->opens >= 2);
  CHECK(waitForStatus(camera, [](const auto& s) { return s.reconnects >= 1; }));
  camera.stop();
}

TEST_CASE("Camera delivering only bad frames is reported and reopened with back-off",
          "[video_server]") {
  auto counters = std::make_shared<StallingSource::Counters>();
  CollectingSink sink;
  CameraConfig c = config(AcquisitionMode::kFreeRun);
  c.no_frame_timeout = 200ms;
  Camera camera(c, std::make_unique<StallingSource>(0, true, counters), sink);
  camera.start();
  // The stall names the last bad frame, and the reason stays while the
  // reopened device still delivers nothing good.
  REQUIRE(waitForStatus(camera, [&](const auto& s) {
    return counters->opens >= 3 && s.state == "reconnecting" &&
           s.last_error.find("no good frame") == 0 &&
           s.last_error.find("frame 7 incomplete") != std::string::npos;
  }));
  CHECK(camera.status().acquisition_errors >= 3);
  CHECK(camera.status().frames_acquired == 0);
  camera.stop();
}

TEST_CASE("Camera waiting for a hardware trigger is not silent and never reopened",
          "[video_server]") {
  auto counters = std::make_shared<StallingSource::Counters>();
  CollectingSink sink;
  CameraConfig c = config(AcquisitionMode::kHardwareTrigger);
  c.mode_asked = true;
  c.hardware.input.line = "Line2";
  c.no_frame_timeout = 100ms;
  Camera camera(c, std::make_unique<StallingSource>(1, false, counters), sink);
  camera.start();
  REQUIRE(sink.waitForCount(1));
  CHECK(counters->hardware_configured);
  // A free-run camera would have been reopened several times over by the
  // time the source was asked this often (10 ms per grab: 6 timeouts' worth).
  REQUIRE(waitForStatus(camera, [&](const auto&) { return counters->grabs >= 60; }));
  const auto status = camera.status();
  CHECK(counters->opens == 1);
  CHECK(status.state == "streaming");
  CHECK(status.last_error.empty());
  CHECK(status.reconnects == 0);
  CHECK(status.acquisition_errors == 0);
  CHECK(status.mode == AcquisitionMode::kHardwareTrigger);
  CHECK(status.hardware.input.line == "Line2");
  // The driver's counters reach the status.
  CHECK(status.driver.missing_packets >= 1);
  // A request in this mode waits for the next frame the line brings.
  const auto ticket = camera.trigger();
  REQUIRE(ticket);
  CHECK_FALSE(ticket->triggered);
  CHECK(ticket->sequence == 2);
  camera.stop();
}

TEST_CASE("Camera without a trigger input refuses the hardware trigger mode", "[video_server]") {
  CollectingSink sink;
  auto camera = makeCamera(config(AcquisitionMode::kFreeRun, 20), sink);
  camera->start();
  const auto refused = camera->setMode(AcquisitionMode::kHardwareTrigger, 0);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == picksight::video::SourceErrc::kNotSupported);
  CHECK(refused.error().message.find("no hardware trigger input") != std::string::npos);
  CHECK(camera->status().mode == AcquisitionMode::kFreeRun);
  camera->stop();
}

namespace {
// A streaming camera at 20 fps whose feature reads are slow (5 ms each, a
// register round trip over a busy link), with 200 features of which every
// fourth is not available (left out of the list).
class SlowFeaturesSource : public TinyStreamingSource {
 public:
  static constexpr int kFeatures = 200;
  picksight::Result<void> open() override { return {}; }
  picksight::Result<picksight::video::SourceFrame> grab(
      std::chrono::milliseconds timeout) override {
    // The device's own pace: a frame every 50 ms.
    const auto now = std::chrono::steady_clock::now();
    if (due_ == std::chrono::steady_clock::time_point{}) due_ = now;
    if (due_ > now + timeout) {
      std::this_thread::sleep_for(timeout);
      return picksight::makeError(picksight::video::SourceErrc::kTimeout, "no frame");
    }
    std::this_thread::sleep_until(due_);
    due_ = std::max(due_ + 50ms, std::chrono::steady_clock::now());
    picksight::video::SourceFrame f;
    f.image = cv::Mat(8, 8, CV_8UC1, cv::Scalar(1));
    return f;
  }
  std::vector<std::string> featureNames() override {
    std::vector<std::string> names;
    for (int i = 0; i < kFeatures; ++i) names.push_back("F" + std::to_string(i));
    return names;
  }
  std::optional<picksight::video::Feature> listedFeature(const std::string& name) override {
    std::this_thread::sleep_for(5ms);
    if (std::stoi(name.substr(1)) % 4 == 3) return std::nullopt;
    picksight::video::Feature f;
    f.name = name;
    return f;
  }

 private:
  std::chrono::steady_clock::time_point due_{};
};
}  // namespace

TEST_CASE("Camera keeps delivering frames while a long feature listing runs", "[video_server]") {
  CollectingSink sink;
  Camera camera(config(AcquisitionMode::kFreeRun, 20, "slow features"),
                std::make_unique<SlowFeaturesSource>(), sink);
  camera.start();
  REQUIRE(sink.waitForCount(1));
  const size_t before = sink.count();
  std::atomic<bool> listed{false};
  auto listing = std::async(std::launch::async, [&] {
    auto features = camera.features();
    listed = true;
    return features;
  });
  // The list takes dozens of slices of at most half a frame period, with a
  // grab after each: ten frames come long before it is complete. Read in one
  // pass, it would hold the acquisition thread and no frame would come.
  CHECK(sink.waitForCount(before + 10));
  CHECK_FALSE(listed.load());
  auto features = listing.get();
  REQUIRE(features);
  CHECK(features->size() == SlowFeaturesSource::kFeatures / 4 * 3);
  CHECK(features->front().name == "F0");
  CHECK(features->back().name == "F198");
  camera.stop();
}
