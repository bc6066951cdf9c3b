// Pins the sensor mapping conversions (the convention of
// proto/picksight.proto) and frames made from still images.
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "picksight/common/frame.hpp"

using picksight::SensorMapping;

namespace {
// A crop at (100, 40) resized to a quarter across and a half down.
const SensorMapping kAnisotropic{100, 40, 0.25, 0.5};
}  // namespace

TEST_CASE("SensorMapping identity leaves coordinates alone", "[common]") {
  const SensorMapping identity;
  CHECK(identity.toSensor({12.5, 7}) == cv::Point2d(12.5, 7));
  CHECK(identity.toFrame({12.5, 7}) == cv::Point2d(12.5, 7));
  CHECK(identity.areaToSensor(42) == 42);
  CHECK(identity.directionToSensor(33) == Approx(33));
}

TEST_CASE("SensorMapping maps pixel centres with the ROI offset and scale", "[common]") {
  // Frame pixel 0 covers sensor pixels 100..103 across: its centre is 101.5.
  const cv::Point2d s = kAnisotropic.toSensor({0, 0});
  CHECK(s.x == Approx(101.5));
  CHECK(s.y == Approx(40.5));
  // The frame's edge (-0.5) is the ROI's edge (-0.5 in sensor pixels).
  CHECK(kAnisotropic.toSensor({-0.5, -0.5}).x == Approx(99.5));
  CHECK(kAnisotropic.toSensor({-0.5, -0.5}).y == Approx(39.5));
}

TEST_CASE("SensorMapping toFrame and sensorToFrame invert toSensor", "[common]") {
  for (const cv::Point2d p : {cv::Point2d(0, 0), cv::Point2d(17.25, 3.5), cv::Point2d(-2, 99)}) {
    const cv::Point2d s = kAnisotropic.toSensor(p);
    const cv::Point2d back = kAnisotropic.toFrame(s);
    CHECK(back.x == Approx(p.x));
    CHECK(back.y == Approx(p.y));
    const cv::Matx23d a = kAnisotropic.sensorToFrame();
    CHECK(a(0, 0) * s.x + a(0, 1) * s.y + a(0, 2) == Approx(p.x));
    CHECK(a(1, 0) * s.x + a(1, 1) * s.y + a(1, 2) == Approx(p.y));
  }
}

TEST_CASE("SensorMapping areas and lengths undo the resize", "[common]") {
  CHECK(kAnisotropic.areaToSensor(10) == Approx(80));
  CHECK(kAnisotropic.areaToFrame(kAnisotropic.areaToSensor(10)) == Approx(10));
  CHECK(kAnisotropic.lengthToSensor(10) == Approx(10 / std::sqrt(0.125)));
}

TEST_CASE("SensorMapping directions turn with an anisotropic resize", "[common]") {
  // Axis directions stay; a diagonal in the frame is steeper on the sensor
  // where the frame was squeezed more across (1 across is 4 sensor pixels,
  // 1 down is 2).
  CHECK(kAnisotropic.directionToSensor(0) == Approx(0));
  CHECK(kAnisotropic.directionToSensor(90) == Approx(90));
  CHECK(kAnisotropic.directionToSensor(180) == Approx(180));
  CHECK(kAnisotropic.directionToSensor(45) == Approx(std::atan2(2.0, 4.0) * 180 / M_PI));
  CHECK(kAnisotropic.directionToSensor(-90) == Approx(270));
}

TEST_CASE("SensorMapping moments of a rectangle match the sensor rectangle", "[common]") {
  // A w x h rectangle: m00 = wh, mu20 = w^3 h / 12, mu02 = w h^3 / 12.
  const auto rect = [](double w, double h) {
    cv::Moments m;
    m.m00 = w * h;
    m.mu20 = w * w * w * h / 12;
    m.mu02 = w * h * h * h / 12;
    m.mu11 = 0;
    return m;
  };
  const cv::Moments sensor = kAnisotropic.momentsToSensor(rect(10, 6));
  const cv::Moments expected = rect(40, 12);
  CHECK(sensor.m00 == Approx(expected.m00));
  CHECK(sensor.mu20 == Approx(expected.mu20));
  CHECK(sensor.mu02 == Approx(expected.mu02));
  cv::Moments sheared;
  sheared.mu11 = 3;
  CHECK(kAnisotropic.momentsToSensor(sheared).mu11 == Approx(3 / (0.25 * 0.25 * 0.5 * 0.5)));
}

TEST_CASE("SensorMapping boxes map their corner and scale their size", "[common]") {
  const cv::Rect box = kAnisotropic.boxToSensor(cv::Rect(2, 4, 10, 5));
  CHECK(box.x == std::lround(kAnisotropic.toSensor({2, 4}).x));
  CHECK(box.y == std::lround(kAnisotropic.toSensor({2, 4}).y));
  CHECK(box.width == 40);
  CHECK(box.height == 10);
}

TEST_CASE("frameFromImage makes a full sensor frame that shares the pixels", "[common]") {
  const cv::Mat image(30, 40, CV_8UC3, cv::Scalar(1, 2, 3));
  const picksight::Frame frame = picksight::frameFromImage(image, "still", 7);
  CHECK(frame.image.data == image.data);
  CHECK(frame.info.camera == "still");
  CHECK(frame.info.sequence == 7);
  CHECK(frame.info.width == 40);
  CHECK(frame.info.height == 30);
  CHECK(frame.info.triggered);
  CHECK(frame.info.host_timestamp_ns > 0);
  CHECK(frame.mapping.toSensor({5, 6}) == cv::Point2d(5, 6));
  CHECK(frame.truth.empty());
  CHECK_FALSE(frame.info.compressed);
}

TEST_CASE("isJpegFile reads a file's first bytes, not its name", "[common]") {
  char pattern[] = "/tmp/picksight-jpeg-XXXXXX";
  REQUIRE(::mkdtemp(pattern) != nullptr);
  const std::string dir = pattern;
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
    return dir + "/" + name;
  };
  // A JPEG begins with its start-of-image marker and another marker.
  CHECK(picksight::isJpegFile(write("a.png", std::string("\xFF\xD8\xFF\xE0rest", 8))));
  CHECK_FALSE(picksight::isJpegFile(write("b.jpg", "\x89PNG\r\n")));
  CHECK_FALSE(picksight::isJpegFile(write("c.jpg", std::string("\xFF\xD8", 2))));  // cut short
  CHECK_FALSE(picksight::isJpegFile(write("d.jpg", std::string("\xFF\x00\xFF", 3))));
  CHECK_FALSE(picksight::isJpegFile(dir + "/missing.jpg"));
  std::filesystem::remove_all(dir);
}
