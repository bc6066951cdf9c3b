// The V4L2 pixel format table's look-ups.
#include "v4l2_formats.hpp"

#include <iterator>
#include <limits>

namespace picksight::video {

const V4l2PixelFormat* findPixelFormat(uint32_t fourcc) {
  for (const auto& f : kV4l2PixelFormats) {
    if (f.fourcc == fourcc) return &f;
  }
  return nullptr;
}

int pixelFormatRank(uint32_t fourcc) {
  for (size_t i = 0; i < std::size(kV4l2PixelFormats); ++i) {
    if (kV4l2PixelFormats[i].fourcc == fourcc) return static_cast<int>(i);
  }
  return std::numeric_limits<int>::max();
}

std::string fourccName(uint32_t fourcc) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    if (c != ' ') s += c;
  }
  return s;
}

}  // namespace picksight::video
