// Pins the Aravis source against the fake GigE camera: describe, typed
// features and their errors, free-run and triggered frames, ROI, Mono8 and
// Bayer layouts with the fake camera's known pattern, and loss of the device.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <thread>

#include "fake_gv_camera.hpp"
#include "picksight/sources/source.hpp"

using namespace picksight;
using namespace picksight::video;
using namespace std::chrono_literals;
using picksight::test::FakeGvCamera;
using picksight::test::isDiagonalRamp;

namespace {
std::unique_ptr<Source> openFake() {
  auto source = makeSource(std::string("aravis:") + FakeGvCamera::kDeviceId);
  REQUIRE(source);
  auto opened = (*source)->open();
  INFO((opened ? std::string() : opened.error().message));
  REQUIRE(opened);
  return std::move(*source);
}

// The next complete frame; incomplete ones (a lost packet) are skipped.
// Generous: timing never decides a test.
std::optional<SourceFrame> nextFrame(Source& source, std::chrono::seconds within = 10s) {
  const auto deadline = std::chrono::steady_clock::now() + within;
  std::string last_error;
  while (std::chrono::steady_clock::now() < deadline) {
    auto frame = source.grab(200ms);
    if (frame) return std::move(*frame);
    if (frame.error().code == SourceErrc::kUnavailable) FAIL(frame.error().message);
    last_error = frame.error().message;
  }
  WARN("no frame: " << last_error);
  return std::nullopt;
}

Feature mustGet(Source& source, const std::string& name) {
  auto f = source.feature(name);
  INFO(name << ": " << (f ? std::string() : f.error().message));
  REQUIRE(f);
  return *f;
}

void mustSet(Source& source, const std::string& name, const std::string& value) {
  auto set = source.setFeature(name, value);
  INFO(name << " = " << value << ": " << (set ? std::string() : set.error().message));
  REQUIRE(set);
}
}  // namespace

TEST_CASE("aravis source describes the fake camera", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  const SourceInfo info = source->info();
  CHECK(info.vendor == "Aravis");
  CHECK(info.model == "Fake");
  CHECK(info.serial == "GV01");
  CHECK(info.sensor_width == 2048);
  CHECK(info.sensor_height == 2048);
  CHECK(std::count(info.formats.begin(), info.formats.end(), "Mono8") == 1);
  CHECK(std::count(info.formats.begin(), info.formats.end(), "BayerRG8") == 1);
  CHECK(source->streams());
  source->close();

  // An empty id opens the first camera found: the only one here.
  auto first = makeSource("aravis:");
  REQUIRE(first);
  REQUIRE((*first)->open());
  CHECK((*first)->info().serial == "GV01");
  (*first)->close();

  // The serial alone, as on the camera's label.
  auto by_serial = makeSource("aravis:GV01");
  REQUIRE(by_serial);
  auto opened = (*by_serial)->open();
  INFO((opened ? std::string() : opened.error().message));
  REQUIRE(opened);
  CHECK((*by_serial)->info().model == "Fake");
}

TEST_CASE("aravis source reports an absent camera as unavailable, naming it", "[aravis]") {
  auto source = makeSource("aravis:No-Such-Camera-42");
  REQUIRE(source);
  auto opened = (*source)->open();
  REQUIRE_FALSE(opened);
  CHECK(opened.error().code == SourceErrc::kUnavailable);
  CHECK_THAT(opened.error().message, Catch::Contains("No-Such-Camera-42"));
}

TEST_CASE("aravis source reads and writes GenICam features by type", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();

  const Feature exposure = mustGet(*source, "ExposureTimeAbs");
  CHECK(exposure.type == FeatureType::kFloat);
  CHECK(exposure.has_range);
  CHECK(exposure.min == Approx(10));
  CHECK(exposure.max == Approx(1e7));
  mustSet(*source, "ExposureTimeAbs", "20000");
  CHECK(mustGet(*source, "ExposureTimeAbs").value == "20000");

  const Feature gain = mustGet(*source, "GainRaw");
  CHECK(gain.type == FeatureType::kInteger);
  CHECK(gain.has_range);
  CHECK(gain.min == 0);
  CHECK(gain.max == 10);
  mustSet(*source, "GainRaw", "3");
  CHECK(mustGet(*source, "GainRaw").value == "3");

  const Feature format = mustGet(*source, "PixelFormat");
  CHECK(format.type == FeatureType::kEnumeration);
  CHECK(format.value == "Mono8");
  CHECK(std::count(format.choices.begin(), format.choices.end(), "BayerGR8") == 1);
  mustSet(*source, "PixelFormat", "BayerGR8");
  CHECK(mustGet(*source, "PixelFormat").value == "BayerGR8");

  CHECK(mustGet(*source, "TriggerSoftware").type == FeatureType::kCommand);
  const Feature vendor = mustGet(*source, "DeviceVendorName");
  CHECK(vendor.type == FeatureType::kString);
  CHECK(vendor.value == "Aravis");
  CHECK_FALSE(vendor.writable);

  SECTION("out of range names the feature and the range, and changes nothing") {
    auto refused = source->setFeature("GainRaw", "20");
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == SourceErrc::kBadValue);
    CHECK_THAT(refused.error().message, Catch::Contains("GainRaw") && Catch::Contains("[0, 10]"));
    CHECK(mustGet(*source, "GainRaw").value == "3");
    refused = source->setFeature("ExposureTimeAbs", "5");
    REQUIRE_FALSE(refused);
    CHECK_THAT(refused.error().message,
               Catch::Contains("ExposureTimeAbs") && Catch::Contains("[10, 10000000]"));
  }
  SECTION("a value of the wrong type or not among the choices is refused") {
    auto refused = source->setFeature("GainRaw", "lots");
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == SourceErrc::kBadValue);
    refused = source->setFeature("PixelFormat", "Mono99");
    REQUIRE_FALSE(refused);
    CHECK_THAT(refused.error().message, Catch::Contains("Mono99") && Catch::Contains("Mono8"));
    refused = source->setFeature("DeviceVendorName", "Acme");
    REQUIRE_FALSE(refused);
    CHECK_THAT(refused.error().message, Catch::Contains("read-only"));
  }
  SECTION("an unknown feature is named") {
    auto unknown = source->feature("Gain");  // the fake camera only has GainRaw
    REQUIRE_FALSE(unknown);
    CHECK(unknown.error().code == SourceErrc::kUnknownFeature);
    CHECK_THAT(unknown.error().message, Catch::Contains("'Gain'"));
    auto set = source->setFeature("NoSuchFeature", "1");
    REQUIRE_FALSE(set);
    CHECK(set.error().code == SourceErrc::kUnknownFeature);
  }
  SECTION("the feature list carries types, ranges and current values") {
    const auto all = source->features();
    auto find = [&](const std::string& name) {
      return std::find_if(all.begin(), all.end(), [&](const Feature& f) { return f.name == name; });
    };
    REQUIRE(find("Width") != all.end());
    CHECK(find("Width")->type == FeatureType::kInteger);
    CHECK(find("Width")->max == 2048);
    // Listed: what the camera's categories hold (GainRaw is outside them,
    // reachable by name only).
    REQUIRE(find("ExposureTimeAbs") != all.end());
    CHECK(find("ExposureTimeAbs")->value == "20000");
    REQUIRE(find("TriggerMode") != all.end());
    CHECK(find("TriggerMode")->type == FeatureType::kEnumeration);
  }
}

TEST_CASE("aravis source streams Mono8 frames with the fake camera's ramp", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  uint64_t last_timestamp = 0;
  for (int i = 0; i < 10; ++i) {
    auto frame = nextFrame(*source);
    REQUIRE(frame);
    CHECK(frame->layout == PixelLayout::kMono8);
    CHECK(frame->image.cols == 512);  // the fake camera's default region
    CHECK(frame->image.rows == 512);
    CHECK(isDiagonalRamp(frame->image));
    CHECK(frame->device_timestamp_ns > last_timestamp);
    last_timestamp = frame->device_timestamp_ns;
  }
}

TEST_CASE("aravis source follows a region of interest set through features", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  REQUIRE(nextFrame(*source));
  // While acquiring: the source stops, resizes its buffers and restarts.
  mustSet(*source, "Width", "256");
  mustSet(*source, "Height", "128");
  mustSet(*source, "OffsetX", "64");
  CHECK(mustGet(*source, "OffsetX").value == "64");
  std::optional<SourceFrame> frame;
  for (int i = 0; i < 20 && !(frame && frame->image.cols == 256); ++i) frame = nextFrame(*source);
  REQUIRE(frame);
  CHECK(frame->image.cols == 256);
  CHECK(frame->image.rows == 128);
  CHECK(isDiagonalRamp(frame->image));
  // Small frames too: a few packets each, easy to lose in a small socket buffer.
  mustSet(*source, "Width", "64");
  mustSet(*source, "Height", "16");
  int small = 0;
  for (int i = 0; i < 10; ++i) {
    auto f = nextFrame(*source);
    REQUIRE(f);
    small += f->image.cols == 64 && f->image.rows == 16 && isDiagonalRamp(f->image);
  }
  CHECK(small == 10);
}

TEST_CASE("aravis source delivers Bayer and Mono16 frames with their layout", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  const std::vector<std::pair<std::string, PixelLayout>> formats = {
      {"BayerRG8", PixelLayout::kBayerRG8}, {"BayerGR8", PixelLayout::kBayerGR8},
      {"BayerGB8", PixelLayout::kBayerGB8}, {"BayerBG8", PixelLayout::kBayerBG8},
      {"Mono16", PixelLayout::kMono16},     {"Mono8", PixelLayout::kMono8}};
  for (const auto& [name, layout] : formats) {
    INFO(name);
    mustSet(*source, "PixelFormat", name);
    std::optional<SourceFrame> frame;
    for (int i = 0; i < 20 && !(frame && frame->layout == layout); ++i) frame = nextFrame(*source);
    REQUIRE(frame);
    CHECK(frame->layout == layout);
    CHECK(frame->image.cols == 512);
    CHECK(frame->image.rows == 512);
    if (layout == PixelLayout::kMono16) {
      CHECK(frame->image.type() == CV_16UC1);
    } else {
      CHECK(frame->image.type() == CV_8UC1);
    }
    double lo = 0;
    double hi = 0;
    cv::minMaxLoc(frame->image, &lo, &hi);
    CHECK(hi > lo);  // a picture, not an empty buffer
    if (layout != PixelLayout::kMono8 && layout != PixelLayout::kMono16) {
      // A colour mosaic, not the mono ramp relabelled.
      CHECK_FALSE(isDiagonalRamp(frame->image));
    }
  }
}

TEST_CASE("aravis source in trigger mode delivers exactly the triggered frames", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kTrigger, 10, true, true, {}}));
  CHECK(mustGet(*source, "TriggerMode").value == "On");
  CHECK(mustGet(*source, "TriggerSource").value == "Software");
  // No trigger, no frame (the fake camera would stream at 25 fps otherwise).
  for (int i = 0; i < 5; ++i) {
    auto none = source->grab(200ms);
    REQUIRE_FALSE(none);
    CHECK(none.error().code == SourceErrc::kTimeout);
  }
  for (int i = 0; i < 3; ++i) {
    // As the Camera does: a triggered frame that arrives incomplete (a
    // loaded host) is asked for again.
    std::optional<SourceFrame> frame;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    bool ask = true;
    while (!frame && std::chrono::steady_clock::now() < deadline) {
      if (ask) REQUIRE(source->softwareTrigger());
      auto grabbed = source->grab(200ms);
      if (grabbed) frame = std::move(*grabbed);
      ask = !grabbed && grabbed.error().code == SourceErrc::kBadValue;
    }
    REQUIRE(frame);
    CHECK(isDiagonalRamp(frame->image));
    auto extra = source->grab(500ms);
    CHECK_FALSE(extra);
  }
  // Back to free-run: frames without triggers.
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  CHECK(mustGet(*source, "TriggerMode").value == "Off");
  REQUIRE(nextFrame(*source));
  REQUIRE(nextFrame(*source));
}

TEST_CASE("aravis source reports a killed camera as unavailable and reopens it", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  REQUIRE(nextFrame(*source));
  fake.kill();
  bool unavailable = false;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!unavailable && std::chrono::steady_clock::now() < deadline) {
    auto frame = source->grab(200ms);
    unavailable = !frame && frame.error().code == SourceErrc::kUnavailable;
  }
  REQUIRE(unavailable);
  source->close();
  CHECK_FALSE(source->open());

  fake.start();
  REQUIRE(source->open());
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  auto frame = nextFrame(*source);
  REQUIRE(frame);
  CHECK(isDiagonalRamp(frame->image));
}

TEST_CASE("aravis source keeps the configured frame rate unless fps is asked", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  // As a camera's `features:` set it, with no `fps:`.
  mustSet(*source, "AcquisitionFrameRate", "7.5");
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 10, false, false, {}}));
  CHECK(std::stod(mustGet(*source, "AcquisitionFrameRate").value) == Approx(7.5));
  REQUIRE(nextFrame(*source));
  // Asked: set.
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, false, true, {}}));
  CHECK(std::stod(mustGet(*source, "AcquisitionFrameRate").value) == Approx(20));
}

TEST_CASE("aravis source keeps a configured hardware trigger unless free-run is asked",
          "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  const Feature trigger_source = mustGet(*source, "TriggerSource");
  const auto line = std::find_if(trigger_source.choices.begin(), trigger_source.choices.end(),
                                 [](const std::string& c) { return c.rfind("Line", 0) == 0; });
  INFO("TriggerSource choices: " << trigger_source.choices.size());
  REQUIRE(line != trigger_source.choices.end());
  const std::string input = *line;
  mustSet(*source, "TriggerMode", "On");
  mustSet(*source, "TriggerSource", input);
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 10, false, false, {}}));
  CHECK(mustGet(*source, "TriggerMode").value == "On");
  CHECK(mustGet(*source, "TriggerSource").value == input);
  // Free-run asked explicitly (the configuration's `mode:`, a request): off.
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 10, true, false, {}}));
  CHECK(mustGet(*source, "TriggerMode").value == "Off");
  REQUIRE(nextFrame(*source));
}

TEST_CASE("aravis source in hardware trigger mode waits for its line and names a refused input",
          "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  CHECK(source->hardwareTrigger());
  // The fake camera has an input Line0 (never pulsed) and no Line1.
  TriggerInput missing;
  missing.line = "Line1";
  auto refused =
      source->configureAcquisition({AcquisitionMode::kHardwareTrigger, 10, true, false, missing});
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == SourceErrc::kNotSupported);
  CHECK_THAT(refused.error().message, Catch::Contains("TriggerSource") &&
                                          Catch::Contains("Line1") && Catch::Contains("Line0"));
  // The error is an answer, not a loop: grab says it too.
  auto grabbed = source->grab(50ms);
  REQUIRE_FALSE(grabbed);
  CHECK_THAT(grabbed.error().message, Catch::Contains("TriggerSource"));

  TriggerInput line0;
  line0.line = "Line0";
  line0.activation = "RisingEdge";
  REQUIRE(
      source->configureAcquisition({AcquisitionMode::kHardwareTrigger, 10, true, false, line0}));
  CHECK(mustGet(*source, "TriggerSelector").value == "FrameStart");
  CHECK(mustGet(*source, "TriggerMode").value == "On");
  CHECK(mustGet(*source, "TriggerSource").value == "Line0");
  CHECK(mustGet(*source, "TriggerActivation").value == "RisingEdge");
  // No pulse, no frame; the camera is still there (timeouts, not unavailable).
  for (int i = 0; i < 3; ++i) {
    auto none = source->grab(200ms);
    REQUIRE_FALSE(none);
    CHECK(none.error().code == SourceErrc::kTimeout);
  }
  // Back to free-run: frames again.
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  CHECK(mustGet(*source, "TriggerMode").value == "Off");
  REQUIRE(nextFrame(*source));
}

TEST_CASE("aravis source reports the stream's own counters", "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  if (std::getenv("PICKSIGHT_TEST_NETNS") != nullptr &&
      std::system("command -v iptables >/dev/null 2>&1") == 0) {
    // Alone in a network namespace: drop a few stream packets (GVSP; the
    // control channel, UDP 3956, untouched) and see the driver count them.
    REQUIRE(std::system("iptables -A INPUT -p udp ! --sport 3956 ! --dport 3956 "
                        "-m statistic --mode random --probability 0.02 -j DROP") == 0);
    REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (source->driverCounters().missing_packets == 0 &&
           std::chrono::steady_clock::now() < deadline) {
      (void)source->grab(200ms);
    }
    CHECK(source->driverCounters().missing_packets > 0);
    REQUIRE(std::system("iptables -F INPUT") == 0);
  } else {
    WARN("not in a network namespace of its own, or no iptables: no packets dropped");
  }
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 20, true, true, {}}));
  for (int i = 0; i < 3; ++i) REQUIRE(nextFrame(*source));
  // Loopback loses nothing as a rule; the counters exist and survive a
  // remade stream (the payload changes with the width).
  const DriverCounters before = source->driverCounters();
  mustSet(*source, "Width", "256");
  REQUIRE(nextFrame(*source));
  const DriverCounters after = source->driverCounters();
  CHECK(after.incomplete_buffers >= before.incomplete_buffers);
  CHECK(after.missing_packets >= before.missing_packets);
  CHECK(after.underruns >= before.underruns);
  source->close();
  CHECK(source->driverCounters().missing_packets == after.missing_packets);
}

TEST_CASE("aravis source in free-run hands over the newest frame, not the oldest queued",
          "[aravis]") {
  FakeGvCamera fake;
  auto source = openFake();
  REQUIRE(source->configureAcquisition({AcquisitionMode::kFreeRun, 25, true, true, {}}));
  auto first = nextFrame(*source);
  REQUIRE(first);
  // A consumer that falls behind: frames queue up meanwhile, and the next
  // grab passes over all but the newest.
  uint64_t last_timestamp = first->device_timestamp_ns;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (source->driverCounters().skipped_stale == 0 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(200ms);  // the slow consumer, not a wait for a condition
    auto frame = nextFrame(*source);
    REQUIRE(frame);
    CHECK(frame->device_timestamp_ns > last_timestamp);
    last_timestamp = frame->device_timestamp_ns;
  }
  CHECK(source->driverCounters().skipped_stale >= 1);
}
