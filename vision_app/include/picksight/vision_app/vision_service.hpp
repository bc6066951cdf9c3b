// The vision work behind robot requests: get a frame taken after the
// request (a software trigger, or the next free-run frame), find the parts,
// and express them in sensor pixels.
//
// Threading: locate() may be called from any connection thread; requests are
// served one at a time (they share the control socket and the CPU).
#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight/common/result.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/vision/binarize.hpp"
#include "picksight/vision/regions.hpp"
#include "picksight/vision_app/frame_feed.hpp"

namespace picksight::app {

// Error codes of VisionService results; they are also the robot protocol's.
enum VisionError : int {
  kNoFrame = 20,        // no fresh frame in time
  kNoVideoServer = 21,  // the video server did not answer or refused
};

struct LocatedPart {
  double x = 0;  // sensor pixels
  double y = 0;
  double angle_deg = 0;  // [0, 360), image axes
  double area = 0;       // sensor pixels
  int holes = 0;
};

struct FrameInfo {
  std::string camera;
  uint64_t sequence = 0;
  uint64_t host_timestamp_ns = 0;
  uint32_t width = 0;
  uint32_t height = 0;
  bool triggered = false;
};

struct LocateOutcome {
  FrameInfo frame;
  std::vector<LocatedPart> parts;  // largest first
};

struct VisionOptions {
  vision::BinarizeOptions binarize;
  vision::RegionOptions regions;
  std::chrono::milliseconds frame_timeout{3000};
};

// Finds the parts in one frame and maps them to sensor pixels through the
// frame header's ROI offset and scale.
std::vector<LocatedPart> locateParts(const ReceivedFrame& frame, const VisionOptions& options);

class VisionService {
 public:
  VisionService(zmq::context_t& context, const std::string& frames_endpoint,
                const std::string& control_endpoint, std::string camera, VisionOptions options);

  void start();
  void stop();

  // Every part in a frame taken after this call.
  Result<LocateOutcome> locate();
  // The frame the last request worked on.
  std::optional<FrameInfo> lastFrame() const;
  const std::string& camera() const { return camera_; }

 private:
  Result<std::shared_ptr<const ReceivedFrame>> freshFrame();

  const std::string camera_;
  const VisionOptions options_;
  FrameFeed feed_;

  mutable std::mutex mutex_;  // serializes requests; guards control_ and last_frame_
  ControlClient control_;
  std::optional<FrameInfo> last_frame_;
};

}  // namespace picksight::app
