// The camera source interface: every driver (synthetic, file, and later
// aravis, v4l2, stream, dir) implements it in its own folder under sources/,
// and SourceFactory builds one from its source string.
//
// Threading: a Source is owned by one Camera and called from that camera's
// acquisition thread only, except where a method says otherwise.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"

namespace picksight::video {

// Ground truth of one part in a frame, in sensor pixels (synthetic sources).
struct TruthPart {
  std::string type;
  double x = 0;
  double y = 0;
  double angle_deg = 0;     // [0, 360), image axes (x right, y down)
  double symmetry_deg = 360;  // period of the measurable angle; 0 = none
  double area_px = 0;
};

struct SourceFrame {
  // CV_8UC1 (mono) or CV_8UC3 (BGR) at sensor resolution. May share memory
  // with the source's own cache: consumers must not write into it.
  cv::Mat image;
  uint64_t device_timestamp_ns = 0;  // 0 when the device gives none
  std::vector<TruthPart> truth;
};

struct SourceInfo {
  std::string vendor;
  std::string model;
  std::string serial;
  int sensor_width = 0;
  int sensor_height = 0;
  std::vector<std::string> formats;  // formats the device delivers
};

// Error codes of source results.
enum SourceError : int {
  kSourceTimeout = 1,      // no frame in time; try again
  kSourceUnavailable = 2,  // device gone or not openable; reopen with back-off
  kSourceBadConfig = 3,    // the source string is wrong; retrying will not help
};

class Source {
 public:
  virtual ~Source() = default;

  // Opens the device. Failure is a value: the camera retries with back-off.
  virtual Result<void> open() = 0;
  virtual void close() = 0;
  // Valid after a successful open().
  virtual SourceInfo info() const = 0;
  // Produces one frame. Sources that render or read on demand (synthetic,
  // file) make it now; the caller paces them.
  virtual Result<SourceFrame> grab(std::chrono::milliseconds timeout) = 0;
};

// Builds a source from its string ("synthetic:", "synthetic:?width=..",
// "file:/path/img.png"). Errors name what is wrong with the string.
Result<std::unique_ptr<Source>> makeSource(const std::string& uri);

}  // namespace picksight::video
