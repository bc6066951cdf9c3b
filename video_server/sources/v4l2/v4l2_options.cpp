// Parses "v4l2:" source strings; numbers are read whatever the host locale.
#include "v4l2_options.hpp"

#include <algorithm>
#include <cctype>

#include "picksight/common/text.hpp"
#include "picksight/sources/source.hpp"
#include "v4l2_formats.hpp"

namespace picksight::video {

Result<V4l2Options> parseV4l2Options(const std::string& text) {
  V4l2Options o;
  const size_t q = text.find('?');
  o.path = text.substr(0, q);
  if (o.path.empty())
    return makeError(SourceErrc::kBadConfig, "v4l2: needs a device, as in v4l2:/dev/video0");
  std::string query = q == std::string::npos ? "" : text.substr(q + 1);
  size_t pos = 0;
  while (pos < query.size()) {
    const size_t amp = std::min(query.find('&', pos), query.size());
    const std::string pair = query.substr(pos, amp - pos);
    pos = amp + 1;
    if (pair.empty()) continue;
    const size_t eq = pair.find('=');
    const std::string key = pair.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : pair.substr(eq + 1);
    if (key == "width" || key == "height" || key == "buffers" || key == "skip") {
      // The bounds of each count.
      const long long lo = key == "buffers" ? 2 : key == "skip" ? 0 : 1;
      const long long hi = key == "buffers" ? 32 : key == "skip" ? 100 : 16384;
      const auto n = parseInt(value);
      if (!n || *n < lo || *n > hi) {
        return makeError(SourceErrc::kBadConfig, "v4l2: " + key + " must be " + std::to_string(lo) +
                                                     ".." + std::to_string(hi) + ", got '" + value +
                                                     "'");
      }
      int& field = key == "width"     ? o.width
                   : key == "height"  ? o.height
                   : key == "buffers" ? o.buffers
                                      : o.skip;
      field = static_cast<int>(*n);
    } else if (key == "fps") {
      o.fps = parseDouble(value).value_or(0);
      if (!(o.fps > 0 && o.fps <= 1000)) {
        return makeError(SourceErrc::kBadConfig,
                         "v4l2: fps must be in (0, 1000], got '" + value + "'");
      }
    } else if (key == "format") {
      std::string lower;
      for (char c : value) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (lower == "mjpg") lower = "mjpeg";
      if (lower == "gray" || lower == "mono8") lower = "grey";
      std::string known;
      for (const auto& f : kV4l2PixelFormats) {
        if (lower == f.option) o.fourcc = f.fourcc;
        known += std::string(known.empty() ? "" : ", ") + f.option;
      }
      if (o.fourcc == 0) {
        return makeError(SourceErrc::kBadConfig,
                         "v4l2: unknown format '" + value + "' (known: " + known + ")");
      }
    } else {
      return makeError(
          SourceErrc::kBadConfig,
          "v4l2: unknown option '" + key + "' (known: width, height, format, fps, buffers, skip)");
    }
  }
  if ((o.width == 0) != (o.height == 0)) {
    return makeError(SourceErrc::kBadConfig, "v4l2: width and height go together");
  }
  return o;
}

}  // namespace picksight::video
