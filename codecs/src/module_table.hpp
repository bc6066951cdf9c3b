// The table of functions the codecs module hands to the facade: one C symbol
// (kModuleEntry) returns it, so nothing else of the module is looked up by
// name. Both sides are built from this header in the same build.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/codecs/codecs.hpp"

namespace picksight::codecs {

struct ModuleTable {
  // Raised whenever a member is added, removed or changes type, so that a
  // module left from another build is refused rather than called wrongly.
  int version;
  cv::Mat (*imread)(const std::string& path, int flags);
  bool (*imwrite)(const std::string& path, cv::InputArray image, const std::vector<int>& params);
  cv::Mat (*imdecode)(cv::InputArray bytes, int flags);
  bool (*imencode)(const std::string& ext, cv::InputArray image, std::vector<uchar>& bytes,
                   const std::vector<int>& params);
  bool (*haveImageWriter)(const std::string& path);
  VideoStream* (*newVideoStream)();
};

inline constexpr int kModuleVersion = 2;
inline constexpr const char* kModuleEntry = "picksight_codecs_table";

}  // namespace picksight::codecs
