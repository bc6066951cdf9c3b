// Pins the output transform of published frames: ROI crop, resize with a
// sub-pixel exact mapping back to sensor pixels, pixel format conversion,
// never aliasing the source's buffer, and the validation errors.
#include <cstdint>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "picksight/sources/source.hpp"
#include "picksight/video_server/frame_pipeline.hpp"

using Catch::Detail::Approx;
using picksight::video::applyOutputSettings;
using picksight::video::OutputFormat;
using picksight::video::OutputSettings;
using picksight::video::validateOutputSettings;

namespace {

// BGR image whose blue channel is x, green is y and red a constant: every
// pixel says where it came from.
cv::Mat positionImage(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(x), static_cast<uint8_t>(y), 77);
    }
  }
  return image;
}

// Mono image with value (x + 3 y) mod 256.
cv::Mat monoGradient(int width, int height) {
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      image.at<uint8_t>(y, x) = static_cast<uint8_t>((x + 3 * y) % 256);
  }
  return image;
}

bool aliases(const cv::Mat& out, const cv::Mat& in) {
  return out.data < in.dataend && in.datastart < out.data + out.total() * out.elemSize();
}

// Intensity-weighted centroid of an image with a black background, mapped
// back to sensor pixels with the convention of picksight.proto.
cv::Point2d sensorCentroid(const picksight::video::OutputFrame& out) {
  const cv::Moments m = cv::moments(out.image, false);
  const double u = m.m10 / m.m00;
  const double v = m.m01 / m.m00;
  return {out.roi_offset.x + (u + 0.5) / out.scale_x - 0.5,
          out.roi_offset.y + (v + 0.5) / out.scale_y - 0.5};
}

}  // namespace

TEST_CASE("applyOutputSettings crops the ROI with the pixels at their sensor positions",
          "[video_server]") {
  const cv::Mat sensor = positionImage(64, 48);
  OutputSettings s;
  s.roi = cv::Rect(10, 5, 20, 15);
  s.format = OutputFormat::kBgr8;
  const auto out = applyOutputSettings(sensor, s);
  REQUIRE(out.image.type() == CV_8UC3);
  REQUIRE(out.image.size() == cv::Size(20, 15));
  CHECK(out.roi_offset == cv::Point(10, 5));
  CHECK(out.scale_x == 1.0);
  CHECK(out.scale_y == 1.0);
  CHECK(out.image.isContinuous());
  int wrong = 0;
  for (int v = 0; v < out.image.rows; ++v) {
    for (int u = 0; u < out.image.cols; ++u) {
      if (out.image.at<cv::Vec3b>(v, u) !=
          cv::Vec3b(static_cast<uint8_t>(10 + u), static_cast<uint8_t>(5 + v), 77)) {
        ++wrong;
      }
    }
  }
  CHECK(wrong == 0);
}

TEST_CASE("a crop of a buffer the pipeline owns is still published as one continuous block",
          "[video_server]") {
  // A converted frame is the pipeline's own and may be published without a
  // copy, but a crop of it is a view with the full row stride: the
  // publisher sends rows x width bytes from its start, so it must be copied.
  const cv::Mat sensor = monoGradient(64, 48);
  OutputSettings s;
  s.roi = cv::Rect(10, 5, 20, 15);
  const auto out = applyOutputSettings(sensor, s, /*sensor_is_private=*/true);
  REQUIRE(out.image.size() == cv::Size(20, 15));
  CHECK(out.image.isContinuous());
  CHECK(cv::norm(out.image, sensor(s.roi), cv::NORM_INF) == 0);
}

TEST_CASE("applyOutputSettings with default settings is the whole sensor, mono", "[video_server]") {
  const cv::Mat sensor = monoGradient(40, 30);
  const auto out = applyOutputSettings(sensor, OutputSettings{});
  REQUIRE(out.image.type() == CV_8UC1);
  REQUIRE(out.image.size() == sensor.size());
  CHECK(out.roi_offset == cv::Point(0, 0));
  CHECK(out.scale_x == 1.0);
  CHECK(out.scale_y == 1.0);
  CHECK(cv::norm(out.image, sensor, cv::NORM_INF) == 0);
}

TEST_CASE("applyOutputSettings clamps a ROI to a sensor that shrank", "[video_server]") {
  const cv::Mat sensor = monoGradient(80, 60);
  OutputSettings s;
  s.roi = cv::Rect(50, 40, 100, 100);
  const auto out = applyOutputSettings(sensor, s);
  REQUIRE(out.image.size() == cv::Size(30, 20));
  CHECK(out.roi_offset == cv::Point(50, 40));
  CHECK(out.image.at<uint8_t>(0, 0) == sensor.at<uint8_t>(40, 50));
  CHECK(out.image.at<uint8_t>(19, 29) == sensor.at<uint8_t>(59, 79));
}

TEST_CASE("applyOutputSettings resize reports scale_x and scale_y", "[video_server]") {
  const cv::Mat sensor = monoGradient(200, 100);
  SECTION("uniform scale") {
    OutputSettings s;
    s.scale = 0.5;
    const auto out = applyOutputSettings(sensor, s);
    CHECK(out.image.size() == cv::Size(100, 50));
    CHECK(out.scale_x == 0.5);
    CHECK(out.scale_y == 0.5);
  }
  SECTION("target size with different factors, after a ROI") {
    OutputSettings s;
    s.roi = cv::Rect(20, 10, 160, 80);
    s.size = cv::Size(40, 40);
    const auto out = applyOutputSettings(sensor, s);
    CHECK(out.image.size() == cv::Size(40, 40));
    CHECK(out.roi_offset == cv::Point(20, 10));
    CHECK(out.scale_x == 0.25);
    CHECK(out.scale_y == 0.5);
  }
  SECTION("enlarging") {
    OutputSettings s;
    s.roi = cv::Rect(0, 0, 50, 40);
    s.scale = 2;
    const auto out = applyOutputSettings(sensor, s);
    CHECK(out.image.size() == cv::Size(100, 80));
    CHECK(out.scale_x == 2.0);
    CHECK(out.scale_y == 2.0);
  }
  SECTION("scale 1 and the ROI size itself are no resize") {
    OutputSettings s;
    s.roi = cv::Rect(3, 4, 50, 40);
    s.scale = 1;
    auto out = applyOutputSettings(sensor, s);
    CHECK(out.image.size() == cv::Size(50, 40));
    CHECK(out.image.at<uint8_t>(0, 0) == sensor.at<uint8_t>(4, 3));
    s.scale = 0;
    s.size = cv::Size(50, 40);
    out = applyOutputSettings(sensor, s);
    CHECK(out.image.size() == cv::Size(50, 40));
    CHECK(out.scale_x == 1.0);
  }
}

TEST_CASE("a resized frame maps back to sensor pixels within 0.05 px", "[video_server]") {
  // A bright square with its centroid between pixel centres, on black.
  cv::Mat sensor(300, 400, CV_8UC1, cv::Scalar(0));
  sensor(cv::Rect(151, 101, 40, 30)).setTo(200);
  const cv::Point2d truth(151 + 19.5, 101 + 14.5);
  REQUIRE(sensorCentroid(applyOutputSettings(sensor, OutputSettings{})).x == Approx(truth.x));

  struct Case {
    const char* name;
    cv::Rect roi;
    cv::Size size;
    double scale;
  };
  const Case cases[] = {
      {"halve", cv::Rect(100, 60, 200, 150), cv::Size(), 0.5},
      {"third", cv::Rect(99, 61, 201, 150), cv::Size(), 1.0 / 3.0},
      {"non-integer shrink", cv::Rect(100, 60, 200, 150), cv::Size(), 0.6},
      {"anisotropic size", cv::Rect(100, 50, 200, 150), cv::Size(120, 50), 0},
      {"enlarge", cv::Rect(120, 80, 100, 80), cv::Size(), 2.0},
      {"enlarge non-integer", cv::Rect(120, 80, 100, 80), cv::Size(), 1.5},
      {"full sensor, shrink", cv::Rect(), cv::Size(), 0.25},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    OutputSettings s;
    s.roi = c.roi;
    s.size = c.size;
    s.scale = c.scale;
    const auto out = applyOutputSettings(sensor, s);
    const cv::Point2d back = sensorCentroid(out);
    CHECK(back.x == Approx(truth.x).margin(0.05));
    CHECK(back.y == Approx(truth.y).margin(0.05));
  }
}

TEST_CASE("applyOutputSettings converts mono to bgr and bgr to mono", "[video_server]") {
  SECTION("mono to bgr repeats the grey level in every channel") {
    cv::Mat mono(4, 5, CV_8UC1, cv::Scalar(37));
    mono.at<uint8_t>(2, 3) = 200;
    OutputSettings s;
    s.format = OutputFormat::kBgr8;
    const auto out = applyOutputSettings(mono, s);
    REQUIRE(out.image.type() == CV_8UC3);
    CHECK(out.image.at<cv::Vec3b>(2, 3) == cv::Vec3b(200, 200, 200));
    CHECK(out.image.at<cv::Vec3b>(0, 0) == cv::Vec3b(37, 37, 37));
  }
  SECTION("bgr to mono weighs the channels as B, G, R") {
    cv::Mat bgr(1, 4, CV_8UC3);
    bgr.at<cv::Vec3b>(0, 0) = cv::Vec3b(255, 0, 0);  // blue
    bgr.at<cv::Vec3b>(0, 1) = cv::Vec3b(0, 255, 0);  // green
    bgr.at<cv::Vec3b>(0, 2) = cv::Vec3b(0, 0, 255);  // red
    bgr.at<cv::Vec3b>(0, 3) = cv::Vec3b(100, 100, 100);
    const auto out = applyOutputSettings(bgr, OutputSettings{});
    REQUIRE(out.image.type() == CV_8UC1);
    // ITU-R BT.601: Y = 0.114 B + 0.587 G + 0.299 R.
    CHECK(int(out.image.at<uint8_t>(0, 0)) == Approx(29).margin(1));
    CHECK(int(out.image.at<uint8_t>(0, 1)) == Approx(150).margin(1));
    CHECK(int(out.image.at<uint8_t>(0, 2)) == Approx(76).margin(1));
    CHECK(int(out.image.at<uint8_t>(0, 3)) == 100);
  }
}

TEST_CASE("applyOutputSettings never returns the input buffer", "[video_server]") {
  const cv::Mat mono = monoGradient(64, 48);
  const cv::Mat bgr = positionImage(64, 48);
  const cv::Mat big = monoGradient(100, 80);
  const cv::Mat sub_view = big(cv::Rect(10, 10, 64, 48));  // not continuous

  struct Case {
    const char* name;
    const cv::Mat* input;
    OutputSettings settings;
  };
  OutputSettings full_rows;
  full_rows.roi = cv::Rect(0, 8, 64, 20);  // a continuous band of the input
  OutputSettings crop;
  crop.roi = cv::Rect(5, 5, 30, 20);
  OutputSettings bgr_out;
  bgr_out.format = OutputFormat::kBgr8;
  OutputSettings half;
  half.scale = 0.5;
  const Case cases[] = {
      {"mono default", &mono, OutputSettings{}},
      {"mono full-width rows", &mono, full_rows},
      {"mono crop", &mono, crop},
      {"bgr kept bgr", &bgr, bgr_out},
      {"bgr full-width rows kept bgr", &bgr,
       [&] {
         OutputSettings s = full_rows;
         s.format = OutputFormat::kBgr8;
         return s;
       }()},
      {"resize", &mono, half},
      {"view of a larger image", &sub_view, OutputSettings{}},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    cv::Mat input = c.input->clone();
    if (c.input == &sub_view) input = sub_view;
    const auto out = applyOutputSettings(input, c.settings);
    CHECK_FALSE(aliases(out.image, input));
    CHECK(out.image.isContinuous());
    CHECK(out.image.u != input.u);
  }
}

TEST_CASE("applyOutputSettings of a source frame never returns the source's buffer",
          "[video_server]") {
  picksight::video::SourceFrame frame;
  frame.image = monoGradient(64, 48);
  frame.layout = picksight::video::PixelLayout::kMono8;
  OutputSettings full_rows;
  full_rows.roi = cv::Rect(0, 8, 64, 20);
  for (const OutputSettings& s : {OutputSettings{}, full_rows}) {
    auto out = applyOutputSettings(frame, s);
    REQUIRE(out);
    CHECK_FALSE(aliases(out->image, frame.image));
    CHECK(out->image.isContinuous());
    CHECK(out->image.at<uint8_t>(0, 5) == frame.image.at<uint8_t>(s.roi.y, 5));
  }
}

TEST_CASE("validateOutputSettings accepts settings within the sensor", "[video_server]") {
  const cv::Size sensor(640, 480);
  CHECK(validateOutputSettings(OutputSettings{}, sensor));
  OutputSettings s;
  s.roi = cv::Rect(540, 380, 100, 100);  // touches the far corner exactly
  s.size = cv::Size(50, 50);
  CHECK(validateOutputSettings(s, sensor));
  s.size = cv::Size();
  s.scale = 16;
  CHECK(validateOutputSettings(s, sensor));
  // Sensor not known yet (camera not opened): only the form is checked.
  s.roi = cv::Rect(5000, 5000, 100, 100);
  CHECK(validateOutputSettings(s, cv::Size()));
}

TEST_CASE("validateOutputSettings names the sizes of a ROI beyond the sensor", "[video_server]") {
  const cv::Size sensor(640, 480);
  OutputSettings s;
  s.roi = cv::Rect(600, 0, 100, 100);
  auto r = validateOutputSettings(s, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("640x480"));
  CHECK_THAT(r.error().message, Catch::Contains("100x100"));
  s.roi = cv::Rect(0, 400, 640, 81);
  CHECK_FALSE(validateOutputSettings(s, sensor));
}

TEST_CASE("validateOutputSettings rejects a ROI whose end overflows int", "[video_server]") {
  // What a control request with uint32 fields near 2^31 becomes.
  OutputSettings s;
  s.roi = cv::Rect(2000000000, 0, 2000000000, 10);
  CHECK_FALSE(validateOutputSettings(s, cv::Size(640, 480)));
  s.roi = cv::Rect(0, 2000000000, 10, 2000000000);
  CHECK_FALSE(validateOutputSettings(s, cv::Size(640, 480)));
  // Also before the sensor size is known: cv::Rect arithmetic would overflow.
  CHECK_FALSE(validateOutputSettings(s, cv::Size()));
}

TEST_CASE("validateOutputSettings rejects half sizes and negative values", "[video_server]") {
  const cv::Size sensor(640, 480);
  OutputSettings half;
  half.size = cv::Size(320, 0);
  auto r = validateOutputSettings(half, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("size"));
  half.size = cv::Size(0, 240);
  CHECK_FALSE(validateOutputSettings(half, sensor));

  OutputSettings negative_offset;
  negative_offset.roi = cv::Rect(-1, 0, 10, 10);
  r = validateOutputSettings(negative_offset, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("roi"));

  // Only the all-zero ROI means "full sensor"; a ROI with a size of zero or
  // below in one direction is a mistake, not a request for the full sensor.
  for (const cv::Rect roi : {cv::Rect(10, 10, -5, 20), cv::Rect(10, 10, 20, -5),
                             cv::Rect(10, 10, 0, 20), cv::Rect(0, 0, 20, 0)}) {
    INFO("roi " << roi);
    OutputSettings bad_roi;
    bad_roi.roi = roi;
    r = validateOutputSettings(bad_roi, sensor);
    REQUIRE_FALSE(r);
    CHECK_THAT(r.error().message, Catch::Contains("roi"));
    CHECK_FALSE(validateOutputSettings(bad_roi, cv::Size()));
  }

  OutputSettings negative_size;
  negative_size.size = cv::Size(-5, -5);
  CHECK_FALSE(validateOutputSettings(negative_size, sensor));
  OutputSettings huge_size;
  huge_size.size = cv::Size(100000, 10);
  CHECK_FALSE(validateOutputSettings(huge_size, sensor));

  OutputSettings negative_scale;
  negative_scale.scale = -1;
  r = validateOutputSettings(negative_scale, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("scale"));
  OutputSettings huge_scale;
  huge_scale.scale = 17;
  CHECK_FALSE(validateOutputSettings(huge_scale, sensor));
}

TEST_CASE("output sizes are bounded at 16384 a side and 64 Mi pixels in all", "[video_server]") {
  // What one frame may allocate, however the size was asked for: as a size,
  // or as a scale of the sensor (or its ROI).
  const cv::Size sensor(2048, 2048);
  OutputSettings s;
  s.size = cv::Size(16384, 4096);  // 64 Mi exactly
  CHECK(validateOutputSettings(s, sensor));
  s.size = cv::Size(16384, 4097);
  auto r = validateOutputSettings(s, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("pixels in all"));
  s.size = cv::Size(16385, 8);
  CHECK_FALSE(validateOutputSettings(s, sensor));
  OutputSettings scaled;
  scaled.scale = 4;  // 8192 x 8192: 64 Mi
  CHECK(validateOutputSettings(scaled, sensor));
  scaled.scale = 4.01;
  r = validateOutputSettings(scaled, sensor);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("scaled size"));
}
