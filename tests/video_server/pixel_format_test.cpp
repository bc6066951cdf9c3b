// Pins format standardization pixel by pixel: mono bit depths, the GenICam to
// OpenCV Bayer naming (on hand-made mosaics), RGB/BGR order, YUV 4:2:2 and
// MJPEG decoding, and broken buffers as error values.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/video_server/mjpeg_frame.hpp"
#include "picksight/video_server/pixel_format.hpp"

using picksight::video::OutputFormat;
using picksight::video::PixelLayout;
using picksight::video::toOutputFormat;

namespace {

cv::Mat convertOk(const cv::Mat& raw, PixelLayout layout, OutputFormat format) {
  auto out = toOutputFormat(raw, layout, format);
  if (!out) FAIL(out.error().message);
  REQUIRE(out->type() == (format == OutputFormat::kMono8 ? CV_8UC1 : CV_8UC3));
  REQUIRE(out->size() == (layout == PixelLayout::kMJPEG ? out->size() : raw.size()));
  return *out;
}

// Maximum absolute difference between every pixel of `image` and `value`.
double maxDiff(const cv::Mat& image, const cv::Scalar& value) {
  cv::Mat diff;
  cv::absdiff(image, value, diff);
  return cv::norm(diff, cv::NORM_INF);
}

// A mosaic whose 2x2 cell, read left to right and top to bottom from (0,0),
// is `cell` ("RGGB" = first row R G, second row G B, GenICam BayerRG8), with
// every red site `r`, green `g` and blue `b`.
cv::Mat mosaic(const std::string& cell, int size, uint8_t r, uint8_t g, uint8_t b) {
  cv::Mat m(size, size, CV_8UC1);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const char c = cell[static_cast<size_t>((y % 2) * 2 + x % 2)];
      m.at<uint8_t>(y, x) = c == 'R' ? r : c == 'G' ? g : b;
    }
  }
  return m;
}

}  // namespace

TEST_CASE("Mono10/12/16 scale full scale to 255, with rounding", "[video_server][formats]") {
  cv::Mat mono12 = (cv::Mat_<uint16_t>(1, 4) << 0, 2048, 4095, 65535);
  cv::Mat out = convertOk(mono12, PixelLayout::kMono12, OutputFormat::kMono8);
  CHECK(out.at<uint8_t>(0, 0) == 0);
  CHECK(out.at<uint8_t>(0, 1) == 128);
  CHECK(out.at<uint8_t>(0, 2) == 255);
  CHECK(out.at<uint8_t>(0, 3) == 255);  // stray high bits saturate, never wrap

  cv::Mat mono10 = (cv::Mat_<uint16_t>(1, 3) << 1023, 512, 4);
  out = convertOk(mono10, PixelLayout::kMono10, OutputFormat::kMono8);
  CHECK(out.at<uint8_t>(0, 0) == 255);
  CHECK(out.at<uint8_t>(0, 1) == 128);
  CHECK(out.at<uint8_t>(0, 2) == 1);

  cv::Mat mono16 = (cv::Mat_<uint16_t>(1, 2) << 65535, 257 * 100);
  out = convertOk(mono16, PixelLayout::kMono16, OutputFormat::kBgr8);
  CHECK(out.at<cv::Vec3b>(0, 0) == cv::Vec3b(255, 255, 255));
  CHECK(out.at<cv::Vec3b>(0, 1) == cv::Vec3b(100, 100, 100));
}

TEST_CASE("Mono8 passes through to mono8 and replicates to bgr8", "[video_server][formats]") {
  cv::Mat mono = (cv::Mat_<uint8_t>(1, 2) << 7, 200);
  CHECK(convertOk(mono, PixelLayout::kMono8, OutputFormat::kMono8).at<uint8_t>(0, 1) == 200);
  CHECK(convertOk(mono, PixelLayout::kMono8, OutputFormat::kBgr8).at<cv::Vec3b>(0, 0) ==
        cv::Vec3b(7, 7, 7));
}

TEST_CASE("BayerRG8 hand-made 4x4 mosaic maps to OpenCV's BG code", "[video_server][formats]") {
  // GenICam BayerRG8: the first row starts R, G. Red 200, green 100, blue 50.
  const cv::Mat raw = (cv::Mat_<uint8_t>(4, 4) <<  //
                           200,
                       100, 200, 100,       //
                       100, 50, 100, 50,    //
                       200, 100, 200, 100,  //
                       100, 50, 100, 50);
  const cv::Mat bgr = convertOk(raw, PixelLayout::kBayerRG8, OutputFormat::kBgr8);
  // A flat colour demosaics to itself everywhere, borders included.
  CHECK(maxDiff(bgr, cv::Scalar(50, 100, 200)) <= 1);
  const cv::Mat grey = convertOk(raw, PixelLayout::kBayerRG8, OutputFormat::kMono8);
  // 0.299 R + 0.587 G + 0.114 B
  CHECK(maxDiff(grey, cv::Scalar(0.299 * 200 + 0.587 * 100 + 0.114 * 50)) <= 1);
}

TEST_CASE("every Bayer layout demosaics a flat colour to that colour", "[video_server][formats]") {
  const std::vector<std::pair<std::string, PixelLayout>> layouts = {
      {"RGGB", PixelLayout::kBayerRG8},
      {"GRBG", PixelLayout::kBayerGR8},
      {"BGGR", PixelLayout::kBayerBG8},
      {"GBRG", PixelLayout::kBayerGB8},
  };
  for (const auto& [cell, layout] : layouts) {
    INFO(cell);
    // Flat red: only the red sites lit.
    const cv::Mat red = mosaic(cell, 8, 255, 0, 0);
    CHECK(maxDiff(convertOk(red, layout, OutputFormat::kBgr8), cv::Scalar(0, 0, 255)) <= 1);
    CHECK(maxDiff(convertOk(red, layout, OutputFormat::kMono8), cv::Scalar(76)) <= 1);
    // Three distinct levels catch a swap of R and B or of the G phase.
    const cv::Mat mixed = mosaic(cell, 8, 30, 140, 220);
    CHECK(maxDiff(convertOk(mixed, layout, OutputFormat::kBgr8), cv::Scalar(220, 140, 30)) <= 1);
  }
}

TEST_CASE("RGB8 swaps to BGR, BGR8 passes through, both to grey", "[video_server][formats]") {
  cv::Mat rgb(2, 2, CV_8UC3, cv::Scalar(255, 0, 0));  // red, in R,G,B order
  CHECK(maxDiff(convertOk(rgb, PixelLayout::kRGB8, OutputFormat::kBgr8), cv::Scalar(0, 0, 255)) ==
        0);
  CHECK(maxDiff(convertOk(rgb, PixelLayout::kRGB8, OutputFormat::kMono8), cv::Scalar(76)) <= 1);
  cv::Mat bgr(2, 2, CV_8UC3, cv::Scalar(255, 0, 0));  // blue, in B,G,R order
  CHECK(maxDiff(convertOk(bgr, PixelLayout::kBGR8, OutputFormat::kBgr8), cv::Scalar(255, 0, 0)) ==
        0);
  CHECK(maxDiff(convertOk(bgr, PixelLayout::kBGR8, OutputFormat::kMono8), cv::Scalar(29)) <= 1);
}

TEST_CASE("YUYV and UYVY give the BT.601 colours and Y as grey", "[video_server][formats]") {
  // Studio-range BT.601 codes of 100% red, green and blue, and mid grey.
  struct Colour {
    uint8_t y, u, v;
    cv::Scalar bgr;
  };
  const std::vector<Colour> colours = {
      {81, 90, 240, cv::Scalar(0, 0, 255)},
      {145, 54, 34, cv::Scalar(0, 255, 0)},
      {41, 240, 110, cv::Scalar(255, 0, 0)},
      {126, 128, 128, cv::Scalar(128, 128, 128)},
  };
  for (const auto& c : colours) {
    INFO("Y " << int(c.y) << " U " << int(c.u) << " V " << int(c.v));
    cv::Mat yuyv(2, 4, CV_8UC2);
    cv::Mat uyvy(2, 4, CV_8UC2);
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 4; ++x) {
        const uint8_t chroma = x % 2 == 0 ? c.u : c.v;
        yuyv.at<cv::Vec2b>(y, x) = cv::Vec2b(c.y, chroma);
        uyvy.at<cv::Vec2b>(y, x) = cv::Vec2b(chroma, c.y);
      }
    }
    CHECK(maxDiff(convertOk(yuyv, PixelLayout::kYUYV, OutputFormat::kBgr8), c.bgr) <= 3);
    CHECK(maxDiff(convertOk(uyvy, PixelLayout::kUYVY, OutputFormat::kBgr8), c.bgr) <= 3);
    // Grey is Y itself, exactly.
    CHECK(maxDiff(convertOk(yuyv, PixelLayout::kYUYV, OutputFormat::kMono8), cv::Scalar(c.y)) == 0);
    CHECK(maxDiff(convertOk(uyvy, PixelLayout::kUYVY, OutputFormat::kMono8), cv::Scalar(c.y)) == 0);
  }
}

TEST_CASE("MJPEG decodes to the encoded image", "[video_server][formats]") {
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar(30, 160, 220));
  cv::rectangle(image, cv::Rect(16, 16, 16, 16), cv::Scalar(200, 20, 40), cv::FILLED);
  std::vector<uint8_t> jpeg;
  REQUIRE(picksight::codecs::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const cv::Mat raw(1, static_cast<int>(jpeg.size()), CV_8UC1, jpeg.data());

  const cv::Mat bgr = convertOk(raw, PixelLayout::kMJPEG, OutputFormat::kBgr8);
  REQUIRE(bgr.size() == image.size());
  CHECK(maxDiff(bgr(cv::Rect(2, 2, 8, 8)), cv::Scalar(30, 160, 220)) <= 6);
  CHECK(maxDiff(bgr(cv::Rect(20, 20, 8, 8)), cv::Scalar(200, 20, 40)) <= 6);
  const cv::Mat grey = convertOk(raw, PixelLayout::kMJPEG, OutputFormat::kMono8);
  CHECK(maxDiff(grey(cv::Rect(2, 2, 8, 8)), cv::Scalar(0.114 * 30 + 0.587 * 160 + 0.299 * 220)) <=
        6);

  // Zero padding after the end marker, as some webcams send, is accepted.
  std::vector<uint8_t> padded = jpeg;
  padded.resize(jpeg.size() + 64, 0);
  const cv::Mat padded_raw(1, static_cast<int>(padded.size()), CV_8UC1, padded.data());
  CHECK(toOutputFormat(padded_raw, PixelLayout::kMJPEG, OutputFormat::kMono8));
}

namespace {
// The JPEG without its DHT segments, as a UVC webcam sends MJPEG.
std::vector<uint8_t> withoutHuffmanTables(const std::vector<uint8_t>& jpeg) {
  std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + 2);
  size_t pos = 2;
  while (pos + 4 <= jpeg.size() && jpeg[pos + 1] != 0xDA) {
    const size_t length = (size_t{jpeg[pos + 2]} << 8) | jpeg[pos + 3];
    if (jpeg[pos + 1] != 0xC4) {
      out.insert(out.end(), jpeg.begin() + static_cast<long>(pos),
                 jpeg.begin() + static_cast<long>(pos + 2 + length));
    }
    pos += 2 + length;
  }
  out.insert(out.end(), jpeg.begin() + static_cast<long>(pos), jpeg.end());
  return out;
}

size_t countMarker(const std::vector<uint8_t>& bytes, uint8_t marker) {
  size_t n = 0;
  for (size_t i = 0; i + 1 < bytes.size(); ++i) n += bytes[i] == 0xFF && bytes[i + 1] == marker;
  return n;
}
}  // namespace

TEST_CASE("MJPEG frames without Huffman tables or with bytes after the end decode exactly",
          "[video_server][formats]") {
  cv::Mat image(40, 56, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(255));
  std::vector<uint8_t> jpeg;
  // Not optimized: the encoder's tables are the standard ones, as in MJPEG.
  REQUIRE(picksight::codecs::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80}));
  const cv::Mat whole(1, static_cast<int>(jpeg.size()), CV_8UC1, jpeg.data());
  const cv::Mat expected_bgr = convertOk(whole, PixelLayout::kMJPEG, OutputFormat::kBgr8);
  const cv::Mat expected_grey = convertOk(whole, PixelLayout::kMJPEG, OutputFormat::kMono8);

  std::vector<uint8_t> bare = withoutHuffmanTables(jpeg);
  REQUIRE(countMarker(jpeg, 0xC4) >= 1);
  REQUIRE(countMarker(bare, 0xC4) == 0);
  // Padding a phone app's HTTP server leaves: a CRLF, a stray boundary, zeros.
  const std::string tail = "\r\n--boundary\r\n";
  std::vector<uint8_t> padded = jpeg;
  padded.insert(padded.end(), tail.begin(), tail.end());
  padded.resize(padded.size() + 7, 0);
  std::vector<uint8_t> both = bare;
  both.insert(both.end(), tail.begin(), tail.end());

  for (std::vector<uint8_t>* bytes : {&bare, &padded, &both}) {
    const cv::Mat raw(1, static_cast<int>(bytes->size()), CV_8UC1, bytes->data());
    const cv::Mat bgr = convertOk(raw, PixelLayout::kMJPEG, OutputFormat::kBgr8);
    const cv::Mat grey = convertOk(raw, PixelLayout::kMJPEG, OutputFormat::kMono8);
    REQUIRE(bgr.size() == image.size());
    CHECK(cv::norm(bgr, expected_bgr, cv::NORM_INF) == 0);
    CHECK(cv::norm(grey, expected_grey, cv::NORM_INF) == 0);
  }
  // The completed frame: the tables in front of the scan, the tail gone.
  auto completed = picksight::video::completeMjpegFrame(
      cv::Mat(1, static_cast<int>(both.size()), CV_8UC1, both.data()));
  REQUIRE(completed);
  const std::vector<uint8_t> fixed(completed->ptr<uint8_t>(),
                                   completed->ptr<uint8_t>() + completed->total());
  CHECK(countMarker(fixed, 0xC4) == 1);
  CHECK(fixed[fixed.size() - 2] == 0xFF);
  CHECK(fixed.back() == 0xD9);
}

TEST_CASE("corrupt and truncated MJPEG frames are errors, not crashes", "[video_server][formats]") {
  cv::Mat image(64, 64, CV_8UC1, cv::Scalar(90));
  std::vector<uint8_t> jpeg;
  REQUIRE(picksight::codecs::imencode(".jpg", image, jpeg));
  std::vector<uint8_t> truncated(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2));
  std::vector<uint8_t> garbage(500, 0x5A);
  garbage[0] = 0xFF;
  garbage[1] = 0xD8;
  garbage[498] = 0xFF;
  garbage[499] = 0xD9;  // right markers, nonsense inside
  std::vector<uint8_t> tiny = {0xFF};
  for (std::vector<uint8_t>* bytes : {&truncated, &garbage, &tiny}) {
    const cv::Mat raw(1, static_cast<int>(bytes->size()), CV_8UC1, bytes->data());
    for (auto format : {OutputFormat::kMono8, OutputFormat::kBgr8}) {
      auto out = toOutputFormat(raw, PixelLayout::kMJPEG, format);
      REQUIRE_FALSE(out);
      CHECK(out.error().code == picksight::video::SourceErrc::kBadValue);
      CHECK_THAT(out.error().message, Catch::Contains("MJPEG"));
    }
  }
}

TEST_CASE("a buffer that does not match its layout is an error naming it",
          "[video_server][formats]") {
  const cv::Mat odd_yuyv(2, 3, CV_8UC2, cv::Scalar(0));
  auto out = toOutputFormat(odd_yuyv, PixelLayout::kYUYV, OutputFormat::kBgr8);
  REQUIRE_FALSE(out);
  CHECK_THAT(out.error().message, Catch::Contains("YUYV"));
  const cv::Mat eight_bit(2, 2, CV_8UC1, cv::Scalar(0));
  out = toOutputFormat(eight_bit, PixelLayout::kMono12, OutputFormat::kMono8);
  REQUIRE_FALSE(out);
  CHECK_THAT(out.error().message, Catch::Contains("Mono12"));
  out = toOutputFormat(cv::Mat(), PixelLayout::kBGR8, OutputFormat::kMono8);
  CHECK_FALSE(out);
}

TEST_CASE("packed Mono10p, Mono12p, Mono10Packed and Mono12Packed unpack exactly",
          "[video_server][formats]") {
  // Values whose 8-bit result is exact (0, a third, two thirds, full scale),
  // packed by hand as the camera sends them.
  struct Case {
    PixelLayout layout;
    std::vector<uint8_t> row;   // the packed bytes of one row
    std::vector<int> expected;  // 8-bit grey of each pixel
  };
  // Mono10p: 0, 1023, 341, 682 -> 0x000, 0x3FF, 0x155, 0x2AA, bits LSB first:
  //   b0 = 0x00, b1 = 0xFC (p1 low 6 bits << 2), b2 = 0x5F (p1 high 4 | p2 low 4 << 4),
  //   b3 = 0x95 (p2 high 6 | p3 low 2 << 6), b4 = 0xAA (p3 high 8).
  // Mono12p: 4095, 1365 -> b0 = 0xFF, b1 = 0x5F, b2 = 0x55.
  // Mono10Packed: 1023, 341 -> b0 = 0xFF, b1 = 0x13 (0b11 | 0b01 << 4), b2 = 0x55.
  // Mono12Packed: 4095, 2730 -> b0 = 0xFF, b1 = 0xAF, b2 = 0xAA.
  const std::vector<Case> cases = {
      {PixelLayout::kMono10p, {0x00, 0xFC, 0x5F, 0x95, 0xAA}, {0, 255, 85, 170}},
      {PixelLayout::kMono12p, {0xFF, 0x5F, 0x55}, {255, 85}},
      {PixelLayout::kMono10Packed, {0xFF, 0x13, 0x55}, {255, 85}},
      {PixelLayout::kMono12Packed, {0xFF, 0xAF, 0xAA}, {255, 170}},
  };
  for (const Case& c : cases) {
    INFO(picksight::video::pixelLayoutName(c.layout));
    // Two rows: the second is the first repeated, so rows are unpacked one by one.
    cv::Mat raw(2, static_cast<int>(c.row.size()), CV_8UC1);
    for (int y = 0; y < 2; ++y) std::copy(c.row.begin(), c.row.end(), raw.ptr<uint8_t>(y));
    auto grey = toOutputFormat(raw, c.layout, OutputFormat::kMono8);
    REQUIRE(grey);
    REQUIRE(grey->size() == cv::Size(static_cast<int>(c.expected.size()), 2));
    for (int y = 0; y < 2; ++y) {
      for (size_t x = 0; x < c.expected.size(); ++x) {
        CHECK(grey->at<uint8_t>(y, static_cast<int>(x)) == c.expected[x]);
      }
    }
    auto bgr = toOutputFormat(raw, c.layout, OutputFormat::kBgr8);
    REQUIRE(bgr);
    CHECK(bgr->at<cv::Vec3b>(1, 0) == cv::Vec3b::all(static_cast<uint8_t>(c.expected[0])));
  }
  // A row that is not whole groups is a mismatch, naming the layout.
  auto odd = toOutputFormat(cv::Mat(1, 4, CV_8UC1, cv::Scalar(0)), PixelLayout::kMono10p,
                            OutputFormat::kMono8);
  REQUIRE_FALSE(odd);
  CHECK_THAT(odd.error().message, Catch::Contains("Mono10p"));
}

TEST_CASE("Bayer 10, 12 and 16 bit mosaics demosaic like their 8-bit pattern",
          "[video_server][formats]") {
  struct Case {
    PixelLayout layout;
    double max;
  };
  for (const Case& c : {Case{PixelLayout::kBayerRG10, 1023}, Case{PixelLayout::kBayerRG12, 4095},
                        Case{PixelLayout::kBayerRG16, 65535}}) {
    INFO(picksight::video::pixelLayoutName(c.layout));
    // Red full scale, green a third, blue zero: exactly 255, 85, 0 in 8 bits.
    const cv::Mat eight = mosaic("RGGB", 8, 3, 1, 0);
    cv::Mat wide;
    eight.convertTo(wide, CV_16U, c.max / 3);
    const cv::Mat bgr = convertOk(wide, c.layout, OutputFormat::kBgr8);
    // Away from the border, where demosaicing sees whole cells.
    CHECK(maxDiff(bgr(cv::Rect(2, 2, 4, 4)), cv::Scalar(0, 85, 255)) == 0);
    // The same as the 8-bit layout of the same pattern.
    cv::Mat eight_scaled;
    eight.convertTo(eight_scaled, CV_8U, 85);
    const cv::Mat reference = convertOk(eight_scaled, PixelLayout::kBayerRG8, OutputFormat::kBgr8);
    CHECK(cv::norm(bgr, reference, cv::NORM_INF) == 0);
  }
  auto narrow = toOutputFormat(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), PixelLayout::kBayerGB12,
                               OutputFormat::kBgr8);
  REQUIRE_FALSE(narrow);
  CHECK_THAT(narrow.error().message, Catch::Contains("BayerGB12"));
}
