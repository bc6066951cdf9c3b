// Completes MJPEG frames: standard Huffman tables inserted where a frame has
// none, bytes after the end-of-image marker cut off.
#include "picksight/video_server/mjpeg_frame.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "picksight/sources/source.hpp"

namespace picksight::video {
namespace {

constexpr uint8_t kMarker = 0xFF;
constexpr uint8_t kSoi = 0xD8;
constexpr uint8_t kEoi = 0xD9;
constexpr uint8_t kSos = 0xDA;
constexpr uint8_t kDht = 0xC4;

// The typical Huffman tables of ITU-T T.81 Annex K.3 (tables K.3 to K.6) as
// one DHT segment: four tables, each its class/id byte, 16 code counts, then
// the symbols. These are the tables Motion JPEG assumes when a frame has none.
const std::vector<uint8_t>& standardHuffmanSegment() {
  static const std::vector<uint8_t> kSegment = [] {
    struct Table {
      uint8_t class_id;
      std::array<uint8_t, 16> counts;
      std::vector<uint8_t> symbols;
    };
    const std::vector<uint8_t> dc_symbols = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    const std::vector<Table> tables = {
        {0x00, {0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0}, dc_symbols},
        {0x10,
         {0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 0x7d},
         {0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61,
          0x07, 0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52,
          0xd1, 0xf0, 0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0a, 0x16, 0x17, 0x18, 0x19, 0x1a, 0x25,
          0x26, 0x27, 0x28, 0x29, 0x2a, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45,
          0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64,
          0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83,
          0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99,
          0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6,
          0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3,
          0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8,
          0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa}},
        {0x01, {0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0}, dc_symbols},
        {0x11,
         {0, 2, 1, 2, 4, 4, 3, 4, 7, 5, 4, 4, 0, 1, 2, 0x77},
         {0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61,
          0x71, 0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33,
          0x52, 0xf0, 0x15, 0x62, 0x72, 0xd1, 0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1, 0x17, 0x18,
          0x19, 0x1a, 0x26, 0x27, 0x28, 0x29, 0x2a, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44,
          0x45, 0x46, 0x47, 0x48, 0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63,
          0x64, 0x65, 0x66, 0x67, 0x68, 0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a,
          0x82, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97,
          0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4,
          0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca,
          0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7,
          0xe8, 0xe9, 0xea, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8, 0xf9, 0xfa}},
    };
    std::vector<uint8_t> body;
    for (const Table& t : tables) {
      body.push_back(t.class_id);
      body.insert(body.end(), t.counts.begin(), t.counts.end());
      body.insert(body.end(), t.symbols.begin(), t.symbols.end());
    }
    const size_t length = body.size() + 2;  // the length field counts itself
    std::vector<uint8_t> segment(2 + length);
    segment[0] = kMarker;
    segment[1] = kDht;
    segment[2] = static_cast<uint8_t>(length >> 8);
    segment[3] = static_cast<uint8_t>(length & 0xFF);
    std::copy(body.begin(), body.end(), segment.begin() + 4);
    return segment;
  }();
  return kSegment;
}

Error corrupt(size_t size, const std::string& why) {
  return makeError(SourceErrc::kBadValue,
                   "corrupt MJPEG frame (" + std::to_string(size) + " bytes): " + why);
}

struct Layout {
  size_t sos = 0;  // offset of the start-of-scan marker
  bool has_tables = false;
};

// Walks the header segments up to the first scan.
std::optional<Layout> headerLayout(const uint8_t* bytes, size_t n) {
  Layout layout;
  size_t pos = 2;
  while (pos + 1 < n) {
    if (bytes[pos] != kMarker) return std::nullopt;
    const uint8_t marker = bytes[pos + 1];
    if (marker == kMarker) {  // fill byte before a marker
      ++pos;
      continue;
    }
    if (marker == kSos) {
      layout.sos = pos;
      return layout;
    }
    layout.has_tables = layout.has_tables || marker == kDht;
    if (pos + 3 >= n) return std::nullopt;
    const size_t length = (size_t{bytes[pos + 2]} << 8) | bytes[pos + 3];
    if (length < 2) return std::nullopt;
    pos += 2 + length;
  }
  return std::nullopt;
}

}  // namespace

Result<cv::Mat> completeMjpegFrame(const cv::Mat& raw) {
  if (raw.type() != CV_8UC1 || !raw.isContinuous() || raw.empty()) {
    return makeError(SourceErrc::kBadValue, "MJPEG frame is not one continuous row of bytes (" +
                                                std::to_string(raw.cols) + "x" +
                                                std::to_string(raw.rows) + ")");
  }
  const auto* bytes = raw.ptr<uint8_t>();
  const size_t n = raw.total();
  if (n < 4 || bytes[0] != kMarker || bytes[1] != kSoi) return corrupt(n, "no JPEG start marker");
  const std::optional<Layout> layout = headerLayout(bytes, n);
  if (!layout) return corrupt(n, "no scan after the header");
  // Entropy-coded data stuffs every 0xFF with a 0x00, so the last FF D9 after
  // the scan starts is the end of the image (a thumbnail's end comes before
  // it). A libjpeg decoder fills a frame cut short with grey and succeeds:
  // only this check catches a frame truncated by a USB or network hiccup.
  size_t end = n;
  while (end >= layout->sos + 4 && !(bytes[end - 2] == kMarker && bytes[end - 1] == kEoi)) --end;
  if (end < layout->sos + 4) return corrupt(n, "no JPEG end marker");
  if (layout->has_tables) return raw.colRange(0, static_cast<int>(end));
  const std::vector<uint8_t>& tables = standardHuffmanSegment();
  cv::Mat out(1, static_cast<int>(end + tables.size()), CV_8UC1);
  auto* o = out.ptr<uint8_t>();
  std::copy(bytes, bytes + layout->sos, o);
  std::copy(tables.begin(), tables.end(), o + layout->sos);
  std::copy(bytes + layout->sos, bytes + end, o + layout->sos + tables.size());
  return out;
}

}  // namespace picksight::video
