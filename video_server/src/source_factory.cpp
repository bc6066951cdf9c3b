// The one place that knows every driver: builds a source from its string.
#include "../sources/file/file_source.hpp"
#include "../sources/synthetic/synthetic_source.hpp"
#include "picksight/video_server/source.hpp"

namespace picksight::video {

Result<std::unique_ptr<Source>> makeSource(const std::string& uri) {
  const size_t colon = uri.find(':');
  if (colon == std::string::npos) {
    return makeError(kSourceBadConfig,
                     "source '" + uri + "' has no scheme (synthetic:, file:<path>)");
  }
  const std::string scheme = uri.substr(0, colon);
  const std::string rest = uri.substr(colon + 1);
  if (scheme == "synthetic") {
    auto options = parseSyntheticOptions(rest);
    if (!options) return options.error();
    return std::unique_ptr<Source>(std::make_unique<SyntheticSource>(std::move(*options)));
  }
  if (scheme == "file") {
    if (rest.empty()) return makeError(kSourceBadConfig, "file: needs a path, as in file:/data/part.png");
    return std::unique_ptr<Source>(std::make_unique<FileSource>(rest));
  }
  return makeError(kSourceBadConfig,
                   "unknown source scheme '" + scheme + "' in '" + uri + "' (known: synthetic:, file:)");
}

}  // namespace picksight::video
