// The one place that knows every driver: builds a source from its string.
#include "aravis/aravis_source.hpp"
#include "dir/dir_source.hpp"
#include "file/file_source.hpp"
#include "picksight/sources/source.hpp"
#include "stream/stream_source.hpp"
#include "synthetic/synthetic_source.hpp"
#include "v4l2/v4l2_source.hpp"

namespace picksight::video {

const char* errorName(SourceErrc e) {
  switch (e) {
    case SourceErrc::kTimeout:
      return "timeout";
    case SourceErrc::kUnavailable:
      return "unavailable";
    case SourceErrc::kBadConfig:
      return "bad config";
    case SourceErrc::kUnknownFeature:
      return "unknown feature";
    case SourceErrc::kBadValue:
      return "bad value";
    case SourceErrc::kNotSupported:
      return "not supported";
  }
  return "unknown";
}

std::vector<std::string> Source::featureNames() {
  std::vector<std::string> names;
  for (const Feature& f : features()) names.push_back(f.name);
  return names;
}

std::optional<Feature> Source::listedFeature(const std::string& name) {
  auto f = feature(name);
  if (!f) return std::nullopt;
  return *f;
}

Result<std::unique_ptr<Source>> makeSource(const std::string& uri) {
  const size_t colon = uri.find(':');
  if (colon == std::string::npos) {
    return makeError(SourceErrc::kBadConfig,
                     "source '" + uri +
                         "' has no scheme (synthetic:, file:<path>, dir:<path>, "
                         "v4l2:/dev/videoN, stream:<url>)");
  }
  const std::string scheme = uri.substr(0, colon);
  const std::string rest = uri.substr(colon + 1);
  if (scheme == "synthetic") {
    auto options = parseSyntheticOptions(rest);
    if (!options) return options.error();
    return std::unique_ptr<Source>(std::make_unique<SyntheticSource>(std::move(*options)));
  }
  if (scheme == "aravis") {
    // Empty id: the first camera Aravis finds.
    return std::unique_ptr<Source>(std::make_unique<AravisSource>(rest));
  }
  if (scheme == "file") {
    if (rest.empty())
      return makeError(SourceErrc::kBadConfig, "file: needs a path, as in file:/data/part.png");
    return std::unique_ptr<Source>(std::make_unique<FileSource>(rest));
  }
  if (scheme == "v4l2") {
    auto options = parseV4l2Options(rest);
    if (!options) return options.error();
    return std::unique_ptr<Source>(std::make_unique<V4l2Source>(std::move(*options)));
  }
  if (scheme == "stream") {
    auto options = parseStreamOptions(rest);
    if (!options) return options.error();
    return std::unique_ptr<Source>(std::make_unique<StreamSource>(std::move(*options)));
  }
  if (scheme == "dir") {
    if (rest.empty()) {
      return makeError(SourceErrc::kBadConfig, "dir: needs a directory, as in dir:/data/run1");
    }
    return std::unique_ptr<Source>(std::make_unique<DirSource>(rest));
  }
  return makeError(SourceErrc::kBadConfig,
                   "unknown source scheme '" + scheme + "' in '" + uri +
                       "' (known: synthetic:, file:, dir:, v4l2:, stream:, aravis:)");
}

}  // namespace picksight::video
