// Pins the V4L2 driver against a simulated webcam: format and size choice,
// mmap streaming with the buffer count the driver grants, frames with the
// device's pixels, EINTR/EAGAIN and error-flagged frames, controls as typed
// features, frame rate, software trigger, and a device that disappears
// (reported unavailable, so the Camera reconnects) with everything released.
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include "picksight/common/clock.hpp"
#include "picksight/sources/source.hpp"
#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/pixel_format.hpp"
#include "simulated_v4l2_device.hpp"
#include "v4l2/v4l2_source.hpp"

using namespace std::chrono_literals;
using namespace picksight::video;
using picksight::video::testing::SimulatedV4l2Device;

namespace {

// A source on a fresh simulated device; `sim` borrows the device the source owns.
struct Rig {
  // Unless `options` say otherwise, no frames skipped after STREAMON, so
  // that tests can name frames by their number from the first.
  explicit Rig(std::string options = "") {
    if (options.find("skip=") == std::string::npos)
      options += options.empty() ? "?skip=0" : "&skip=0";
    auto parsed = parseV4l2Options(std::string(SimulatedV4l2Device::kPath) + options);
    REQUIRE(parsed);
    auto device = std::make_unique<SimulatedV4l2Device>();
    sim = device.get();
    source = std::make_unique<V4l2Source>(*parsed, std::move(device));
  }
  SimulatedV4l2Device* sim = nullptr;
  std::unique_ptr<V4l2Source> source;
};

SourceFrame grabOk(Source& source) {
  auto frame = source.grab(2s);
  if (!frame) FAIL(frame.error().message);
  return std::move(*frame);
}

// The frame's grey level: every pixel must have it (within `tolerance`).
int uniformLevel(const SourceFrame& frame, int tolerance = 0) {
  auto grey = toOutputFormat(frame.image, frame.layout, OutputFormat::kMono8);
  REQUIRE(grey);
  double lo = 0, hi = 0;
  cv::minMaxLoc(*grey, &lo, &hi);
  CHECK(hi - lo <= tolerance);
  return static_cast<int>(cv::mean(*grey)[0] + 0.5);
}

Feature findFeature(const std::vector<Feature>& features, const std::string& name) {
  for (const auto& f : features) {
    if (f.name == name) return f;
  }
  FAIL("no feature " << name);
  return {};
}

class CollectingSink : public FrameSink {
 public:
  void publish(picksight::Frame frame) override {
    std::lock_guard<std::mutex> lock(mutex_);
    frames_.push_back(frame.info.sequence);
    compressed_ = compressed_ || frame.info.compressed;
  }
  // Whether any frame published was marked compressed.
  bool anyCompressed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return compressed_;
  }
  size_t count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_.size();
  }

 private:
  mutable std::mutex mutex_;
  std::vector<uint64_t> frames_;
  bool compressed_ = false;
};

template <typename Pred>
bool eventually(Pred pred, std::chrono::milliseconds limit = 10s) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return pred();
}

}  // namespace

TEST_CASE("v4l2 options: keys, values and errors that name them", "[video_server][v4l2]") {
  auto o = parseV4l2Options("/dev/video2?width=1280&height=720&format=MJPG&fps=30&buffers=6");
  REQUIRE(o);
  CHECK(o->path == "/dev/video2");
  CHECK(o->width == 1280);
  CHECK(o->height == 720);
  CHECK(o->fourcc == V4L2_PIX_FMT_MJPEG);
  CHECK(o->fps == 30);
  CHECK(o->buffers == 6);
  CHECK(parseV4l2Options("/dev/video0")->fourcc == 0);
  CHECK(parseV4l2Options("/dev/video0")->skip == 3);
  CHECK(parseV4l2Options("/dev/video0?skip=0")->skip == 0);
  CHECK_THAT(parseV4l2Options("/dev/video0?skip=101").error().message,
             Catch::Contains("skip") && Catch::Contains("0..100"));

  CHECK_THAT(parseV4l2Options("/dev/video0?width=640").error().message,
             Catch::Contains("together"));
  CHECK_THAT(parseV4l2Options("/dev/video0?format=h264").error().message, Catch::Contains("h264"));
  CHECK_THAT(parseV4l2Options("/dev/video0?exposure=3").error().message,
             Catch::Contains("exposure"));
  CHECK_THAT(parseV4l2Options("/dev/video0?fps=fast").error().message, Catch::Contains("fps"));
  CHECK_THAT(parseV4l2Options("?width=1").error().message, Catch::Contains("device"));
  // Through the factory, the same errors.
  auto bad = makeSource("v4l2:/dev/video0?buffers=1");
  REQUIRE_FALSE(bad);
  CHECK(bad.error().code == SourceErrc::kBadConfig);
  CHECK_THAT(bad.error().message, Catch::Contains("buffers"));
  CHECK(makeSource("v4l2:/dev/video0?width=640&height=480"));
}

TEST_CASE("v4l2 streams YUYV at the requested size with the device's pixels",
          "[video_server][v4l2]") {
  Rig rig("?width=640&height=480");
  rig.sim->setGrantedBuffers(3);  // asked for 4: the driver decides
  REQUIRE(rig.source->open());
  const auto st = rig.sim->state();
  CHECK(st.pixelformat == V4L2_PIX_FMT_YUYV);
  CHECK(st.buffers == 3);
  CHECK(st.mapped == 3);
  CHECK(st.streaming);
  const SourceInfo info = rig.source->info();
  CHECK(info.sensor_width == 640);
  CHECK(info.sensor_height == 480);
  CHECK(info.model == "Simulated Webcam");
  CHECK(info.formats == std::vector<std::string>{"YUYV", "MJPG"});

  // More frames than buffers: each must have been queued back.
  for (uint64_t n = 0; n < 10; ++n) {
    const SourceFrame frame = grabOk(*rig.source);
    CHECK(frame.layout == PixelLayout::kYUYV);
    CHECK(frame.image.size() == cv::Size(640, 480));
    CHECK(frame.device_timestamp_ns > 0);
    CHECK(uniformLevel(frame) == SimulatedV4l2Device::level(n));
  }
  // Colour from U = V = 128 is grey.
  const SourceFrame frame = grabOk(*rig.source);
  auto bgr = toOutputFormat(frame.image, frame.layout, OutputFormat::kBgr8);
  REQUIRE(bgr);
  const cv::Vec3b px = bgr->at<cv::Vec3b>(10, 10);
  CHECK(std::abs(px[0] - px[2]) <= 1);
}

TEST_CASE("v4l2 prefers MJPEG where only it reaches the rate, and honours format=",
          "[video_server][v4l2]") {
  {
    Rig rig("?width=1280&height=720&fps=30");  // YUYV runs 10 fps at 720p on this webcam
    REQUIRE(rig.source->open());
    CHECK(rig.sim->state().pixelformat == V4L2_PIX_FMT_MJPEG);
    CHECK(rig.sim->state().fps == 30);
    const SourceFrame frame = grabOk(*rig.source);
    CHECK(frame.layout == PixelLayout::kMJPEG);
    CHECK(frame.image.rows == 1);
    auto grey = toOutputFormat(frame.image, frame.layout, OutputFormat::kMono8);
    REQUIRE(grey);
    CHECK(grey->size() == cv::Size(1280, 720));
    CHECK(std::abs(uniformLevel(frame, 4) - SimulatedV4l2Device::level(0)) <= 2);
  }
  {
    Rig rig("?width=1280&height=720");  // no rate asked: exact YUYV wins
    REQUIRE(rig.source->open());
    CHECK(rig.sim->state().pixelformat == V4L2_PIX_FMT_YUYV);
  }
  {
    Rig rig("?format=mjpeg");
    REQUIRE(rig.source->open());
    CHECK(rig.sim->state().pixelformat == V4L2_PIX_FMT_MJPEG);
    CHECK(rig.source->info().sensor_width == 640);  // the device's current size
  }
  {
    Rig rig("?width=800&height=600");  // not offered: the nearest
    REQUIRE(rig.source->open());
    CHECK(rig.source->info().sensor_width == 640);
  }
  {
    Rig rig("?format=uyvy");
    auto opened = rig.source->open();
    REQUIRE_FALSE(opened);
    CHECK(opened.error().code == SourceErrc::kBadConfig);
    CHECK_THAT(opened.error().message, Catch::Contains("UYVY") && Catch::Contains("YUYV, MJPG"));
    CHECK(rig.sim->state().open_fds == 0);  // a failed open releases the device
  }
}

TEST_CASE("v4l2 retries EINTR and spurious wakeups, drops error-flagged frames",
          "[video_server][v4l2]") {
  Rig rig;
  rig.sim->injectIoctlEintr(3);  // inside open(): QUERYCAP, G_FMT, ENUM_FMT
  REQUIRE(rig.source->open());
  rig.sim->injectPollEintr(2);
  rig.sim->injectDqbufEagain(2);
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(0));
  rig.sim->injectIoctlEintr(2);  // DQBUF and QBUF
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(1));
  rig.sim->injectErrorFrames(2);
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(4));
  CHECK(rig.source->droppedFrames() == 2);
  CHECK(rig.source->driverCounters().incomplete_buffers == 2);
  CHECK(rig.source->driverCounters().sequence_gaps == 0);
  rig.sim->setPaused(true);
  auto none = rig.source->grab(50ms);
  REQUIRE_FALSE(none);
  CHECK(none.error().code == SourceErrc::kTimeout);
}

TEST_CASE("v4l2 close stops streaming, unmaps and closes", "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  grabOk(*rig.source);
  rig.source->close();
  auto st = rig.sim->state();
  CHECK_FALSE(st.streaming);
  CHECK(st.mapped == 0);
  CHECK(st.buffers == 0);
  CHECK(st.open_fds == 0);
  // And opens again: the simulated device, like a webcam, allows one client.
  REQUIRE(rig.source->open());
  grabOk(*rig.source);
  rig.source.reset();  // the destructor closes too
}

TEST_CASE("v4l2 device that disappears is unavailable and everything is released",
          "[video_server][v4l2]") {
  for (bool poll_fails : {false, true}) {
    INFO("poll fails: " << poll_fails);
    Rig rig;
    REQUIRE(rig.source->open());
    grabOk(*rig.source);
    rig.sim->unplug(poll_fails);
    auto lost = rig.source->grab(2s);
    REQUIRE_FALSE(lost);
    CHECK(lost.error().code == SourceErrc::kUnavailable);
    CHECK_THAT(lost.error().message, Catch::Contains("/dev/video0"));
    rig.source->close();
    CHECK(rig.sim->state().mapped == 0);
    CHECK(rig.sim->state().open_fds == 0);
    auto reopened = rig.source->open();
    REQUIRE_FALSE(reopened);
    CHECK(reopened.error().code == SourceErrc::kUnavailable);
    rig.sim->replug();
    REQUIRE(rig.source->open());
    grabOk(*rig.source);
  }
}

TEST_CASE("v4l2 camera reconnects after the device comes back", "[video_server][v4l2]") {
  Rig rig;
  SimulatedV4l2Device* sim = rig.sim;
  CollectingSink sink;
  CameraConfig config;
  config.name = "webcam";
  config.uri = "v4l2:/dev/video0";
  Camera camera(config, std::move(rig.source), sink);
  camera.start();
  REQUIRE(eventually([&] { return sink.count() >= 3; }));
  sim->unplug(false);
  REQUIRE(eventually([&] { return camera.status().state == "reconnecting"; }));
  sim->replug();
  REQUIRE(eventually(
      [&] { return camera.status().reconnects >= 1 && camera.status().state == "streaming"; }));
  const size_t before = sink.count();
  CHECK(eventually([&] { return sink.count() >= before + 3; }));
  camera.stop();
  CHECK(sim->state().open_fds == 0);
}

TEST_CASE("v4l2 camera marks an MJPEG webcam's frames compressed, a YUYV one's not",
          "[video_server][v4l2]") {
  for (const std::string format : {"mjpeg", "yuyv"}) {
    INFO(format);
    Rig rig("?format=" + format);
    CollectingSink sink;
    CameraConfig config;
    config.name = "webcam";
    config.uri = "v4l2:/dev/video0?format=" + format;
    Camera camera(config, std::move(rig.source), sink);
    camera.start();
    REQUIRE(eventually([&] { return sink.count() >= 2; }));
    camera.stop();
    CHECK(sink.anyCompressed() == (format == "mjpeg"));
  }
}

TEST_CASE("v4l2 controls are typed features named from their labels", "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  const auto features = rig.source->features();
  std::vector<std::string> names;
  for (const auto& f : features) names.push_back(f.name);
  // Class markers, disabled and 64-bit controls are not features.
  CHECK(names == std::vector<std::string>{"brightness", "contrast", "white_balance_automatic",
                                          "gain", "auto_exposure", "exposure_time_absolute"});
  const Feature gain = findFeature(features, "gain");
  CHECK(gain.type == FeatureType::kInteger);
  CHECK(gain.value == "32");
  CHECK(gain.has_range);
  CHECK(gain.min == 0);
  CHECK(gain.max == 255);
  CHECK(findFeature(features, "contrast").increment == 10);
  CHECK(findFeature(features, "white_balance_automatic").type == FeatureType::kBoolean);
  CHECK(findFeature(features, "white_balance_automatic").value == "true");
  const Feature ae = findFeature(features, "auto_exposure");
  CHECK(ae.type == FeatureType::kEnumeration);
  CHECK(ae.choices == std::vector<std::string>{"Manual Mode", "Aperture Priority Mode"});
  CHECK(ae.value == "Aperture Priority Mode");
  CHECK_THAT(findFeature(features, "exposure_time_absolute").description,
             Catch::Contains("inactive"));

  // Values are checked by type and range; errors name the control and the range.
  REQUIRE(rig.source->setFeature("gain", "100"));
  CHECK(rig.sim->controlValue(V4L2_CID_GAIN) == 100);
  CHECK(rig.source->feature("gain")->value == "100");
  auto out_of_range = rig.source->setFeature("gain", "300");
  REQUIRE_FALSE(out_of_range);
  CHECK(out_of_range.error().code == SourceErrc::kBadValue);
  CHECK_THAT(out_of_range.error().message, Catch::Contains("gain") && Catch::Contains("[0, 255]"));
  CHECK(rig.sim->controlValue(V4L2_CID_GAIN) == 100);
  CHECK_THAT(rig.source->setFeature("brightness", "bright").error().message,
             Catch::Contains("brightness"));
  CHECK_THAT(rig.source->setFeature("contrast", "55").error().message,
             Catch::Contains("multiple of 10"));
  REQUIRE(rig.source->setFeature("brightness", "-20"));
  CHECK(rig.sim->controlValue(V4L2_CID_BRIGHTNESS) == -20);
  REQUIRE(rig.source->setFeature("white_balance_automatic", "false"));
  CHECK(rig.sim->controlValue(V4L2_CID_AUTO_WHITE_BALANCE) == 0);
  CHECK_FALSE(rig.source->setFeature("white_balance_automatic", "maybe"));

  auto unknown = rig.source->setFeature("zoom", "2");
  REQUIRE_FALSE(unknown);
  CHECK(unknown.error().code == SourceErrc::kUnknownFeature);
  CHECK_THAT(unknown.error().message, Catch::Contains("zoom"));
  CHECK(rig.source->feature("zoom").error().code == SourceErrc::kUnknownFeature);

  auto no_choice = rig.source->setFeature("auto_exposure", "Shutter Priority Mode");
  REQUIRE_FALSE(no_choice);
  CHECK_THAT(no_choice.error().message, Catch::Contains("Manual Mode, Aperture Priority Mode"));
  REQUIRE(rig.source->setFeature("auto_exposure", "manual mode"));
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_AUTO) == 1);
  REQUIRE(rig.source->setFeature("exposure_time_absolute", "500"));
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_ABSOLUTE) == 500);
  CHECK(rig.source->feature("exposure_time_absolute")->unit == "100us");
  CHECK_THAT(rig.source->setFeature("exposure_time_absolute", "1").error().message,
             Catch::Contains("[3, 2047]"));
  // Frames still flow after all that.
  grabOk(*rig.source);
}

TEST_CASE("v4l2 frame rate: the URI's until the camera's changes at run time",
          "[video_server][v4l2]") {
  Rig rig("?fps=15");
  REQUIRE(rig.source->open());
  CHECK(rig.sim->state().fps == 15);
  // The camera passes its configured default first: the URI's rate holds.
  REQUIRE(rig.source->configureAcquisition({AcquisitionMode::kFreeRun, 10, true, true, {}}));
  CHECK(rig.sim->state().fps == 15);
  const int streamons = rig.sim->state().streamons;
  // A change at run time: applied, restarting the stream (S_PARM is refused while streaming).
  REQUIRE(rig.source->configureAcquisition({AcquisitionMode::kFreeRun, 30, true, true, {}}));
  CHECK(rig.sim->state().fps == 30);
  CHECK(rig.sim->state().streamons == streamons + 1);
  CHECK(rig.sim->state().streaming);
  grabOk(*rig.source);
  // And survives a reconnect.
  rig.source->close();
  REQUIRE(rig.source->open());
  CHECK(rig.sim->state().fps == 30);
}

TEST_CASE("v4l2 software trigger returns a frame captured after it", "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  REQUIRE(rig.source->configureAcquisition({AcquisitionMode::kTrigger, 10, true, true, {}}));
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(0));
  rig.sim->captureNow(2);            // frames 1 and 2 wait in the driver, older than the trigger
  std::this_thread::sleep_for(2ms);  // so the trigger's timestamp is after theirs
  const uint64_t asked = picksight::monotonicNs();
  REQUIRE(rig.source->softwareTrigger());
  // The frame is stamped at least one frame interval (at the device's rate)
  // after the trigger: exposed wholly after it.
  const uint64_t interval = static_cast<uint64_t>(1e9 / rig.sim->state().fps);
  const SourceFrame after = grabOk(*rig.source);
  CHECK(after.device_timestamp_ns >= asked + interval);
  CHECK(rig.source->droppedFrames() == 0);  // frames older than a trigger are not faults
  // Asked again (the camera does after a grab timed out): the first trigger stands.
  const uint64_t again = picksight::monotonicNs();
  REQUIRE(rig.source->softwareTrigger());
  rig.sim->captureNow(1);
  REQUIRE(rig.source->softwareTrigger());
  CHECK(grabOk(*rig.source).device_timestamp_ns >= again + interval);
}

TEST_CASE("v4l2 counts frames missing from the driver's sequence numbers", "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  grabOk(*rig.source);
  CHECK(rig.source->driverCounters().sequence_gaps == 0);
  // Frames the driver numbered but never handed over (no free buffer).
  rig.sim->injectLostFrames(3);
  // Every frame is checked, so the gap shows whichever buffer carries it.
  for (int i = 0; i < 6; ++i) grabOk(*rig.source);
  CHECK(rig.source->driverCounters().sequence_gaps == 3);
  CHECK(rig.source->driverCounters().incomplete_buffers == 0);
  CHECK(rig.source->hardwareTrigger() == false);
  auto hardware = rig.source->configureAcquisition(
      {AcquisitionMode::kHardwareTrigger, 10, true, false, TriggerInput{}});
  REQUIRE_FALSE(hardware);
  CHECK(hardware.error().code == SourceErrc::kNotSupported);
  CHECK(hardware.error().message.find("hardware trigger") != std::string::npos);
}

TEST_CASE("v4l2 controls answer to the old and the new kernel names", "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  // The simulated camera has the new labels; a configuration from an older
  // kernel says exposure_auto and exposure_absolute.
  REQUIRE(rig.source->setFeature("exposure_auto", "Manual Mode"));
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_AUTO) == 1);
  REQUIRE(rig.source->setFeature("exposure_absolute", "300"));
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_ABSOLUTE) == 300);
  const auto old_name = rig.source->feature("exposure_absolute");
  REQUIRE(old_name);
  CHECK(old_name->name == "exposure_time_absolute");  // answered under the current name
  CHECK(old_name->value == "300");
  REQUIRE(rig.source->setFeature("white_balance_temperature_auto", "false"));
  CHECK(rig.sim->controlValue(V4L2_CID_AUTO_WHITE_BALANCE) == 0);
  // A name of neither kernel stays unknown.
  CHECK(rig.source->feature("exposure_automatic").error().code == SourceErrc::kUnknownFeature);
}

TEST_CASE("v4l2 exposure written under auto exposure switches it to manual and says so",
          "[video_server][v4l2]") {
  Rig rig;
  REQUIRE(rig.source->open());
  REQUIRE(rig.sim->controlValue(V4L2_CID_EXPOSURE_AUTO) == 3);  // aperture priority
  REQUIRE(rig.source->setFeature("exposure_time_absolute", "500"));
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_AUTO) == 1);
  CHECK(rig.sim->controlValue(V4L2_CID_EXPOSURE_ABSOLUTE) == 500);
  const auto exposure = rig.source->feature("exposure_time_absolute");
  REQUIRE(exposure);
  CHECK(exposure->value == "500");
  CHECK_THAT(exposure->description, Catch::Contains("switched to manual"));
  CHECK(rig.source->feature("auto_exposure")->value == "Manual Mode");
  // A value out of range still fails and names the range.
  CHECK_THAT(rig.source->setFeature("exposure_time_absolute", "1").error().message,
             Catch::Contains("[3, 2047]"));
}

TEST_CASE("v4l2 identity: the device's serial number, else the port said as such",
          "[video_server][v4l2]") {
  {
    Rig rig;
    REQUIRE(rig.source->open());
    // No serial (a cheap webcam): the port string is not passed off as one.
    CHECK(rig.source->info().serial == "none (port usb-sim-1)");
  }
  Rig rig;
  rig.sim->setSerial("SN-4711");
  REQUIRE(rig.source->open());
  CHECK(rig.source->info().serial == "SN-4711");
}

TEST_CASE("v4l2 drops the first frames after every start of streaming", "[video_server][v4l2]") {
  Rig rig("?skip=3");
  REQUIRE(rig.source->open());
  // Frames 0 to 2 come before auto exposure settles.
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(3));
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(4));
  CHECK(rig.source->droppedFrames() == 0);  // not faults
  rig.source->close();
  REQUIRE(rig.source->open());
  const uint64_t produced = rig.sim->state().frames;
  CHECK(uniformLevel(grabOk(*rig.source)) == SimulatedV4l2Device::level(produced + 3));
}
