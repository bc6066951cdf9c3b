// The V4L2 camera: USB webcams and capture cards through libv4l2, mmap
// streaming, with the device's controls exposed as features. Its members are
// defined in v4l2_source.cpp (open, close, rate), v4l2_format_negotiation.cpp,
// v4l2_streaming.cpp and v4l2_controls.cpp.
#pragma once

#include <linux/videodev2.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "picksight/sources/source.hpp"
#include "v4l2_device.hpp"
#include "v4l2_options.hpp"

namespace picksight::video {

// Threading: called from the camera's acquisition thread only. The kernel
// fills the buffers; grab() only copies one out and queues it straight back.
//
// Software trigger: a webcam has none. In trigger mode it keeps streaming and
// softwareTrigger() marks the moment; grab() then returns the first frame
// stamped at least one frame interval after it (the buffer's monotonic
// timestamp marks the end of exposure, not its start), dropping older ones
// that were waiting in the driver.
class V4l2Source : public Source {
 public:
  // `device` is the system interface; null means libv4l2.
  explicit V4l2Source(V4l2Options options, std::unique_ptr<V4l2Device> device = nullptr);
  ~V4l2Source() override;
  V4l2Source(const V4l2Source&) = delete;
  V4l2Source& operator=(const V4l2Source&) = delete;

  Result<void> open() override;
  void close() override;
  SourceInfo info() const override;
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;
  bool streams() const override { return true; }
  Result<void> configureAcquisition(const AcquisitionRequest& request) override;
  Result<void> softwareTrigger() override;

  // Controls, named from their V4L2 names lower-cased with underscores
  // ("Exposure Time, Absolute" -> exposure_time_absolute).
  std::vector<Feature> features() override;
  Result<Feature> feature(const std::string& name) override;
  Result<void> setFeature(const std::string& name, const std::string& value) override;

  // Frames dropped since open(): flagged bad by the driver, or short.
  uint64_t droppedFrames() const { return dropped_; }
  // Since construction: those drops (incomplete_buffers) and the frames
  // missing from the driver's sequence numbers (sequence_gaps).
  DriverCounters driverCounters() const override { return counters_; }

 private:
  // ioctl, retried while interrupted by a signal.
  int xioctl(unsigned long request, void* arg);
  // errno after a failed call, as a source error.
  Error deviceError(const std::string& what, bool streaming = false);
  Error notOpen() const;
  // The rate to run at: a run-time change, else the URI's, else the camera's default.
  double desiredFps() const;
  Result<void> openDevice();
  Result<void> chooseFormat();
  Result<void> startStreaming();
  void stopStreaming();
  Result<void> queueBuffer(uint32_t index);
  Result<void> applyFrameRate(double fps);
  void drainReadyBuffers();
  // One frame interval at the rate set: the margin a triggered frame's
  // timestamp must keep after the trigger.
  uint64_t frameIntervalNs() const;
  // Counts a jump in the buffers' sequence numbers as lost frames.
  void countSequence(uint32_t sequence);
  std::vector<v4l2_queryctrl> queryControls();
  // By the name made from the kernel's label, or another kernel's name for it.
  std::optional<v4l2_queryctrl> findControl(const std::string& name);
  // Switches the automatic mode overriding `manual` (auto_exposure for
  // exposure_time_absolute...) to manual; the mode's name if it did.
  std::optional<std::string> leaveAutoMode(const v4l2_queryctrl& manual);
  Result<Feature> describeControl(const v4l2_queryctrl& control);
  // A menu control's choices by index, by name (integer menus: by value).
  std::vector<std::pair<int32_t, std::string>> menuChoices(const v4l2_queryctrl& control);

  const V4l2Options options_;
  const std::unique_ptr<V4l2Device> device_;
  V4l2Fd fd_;
  std::vector<V4l2Mapping> buffers_;  // index = V4L2 buffer index
  bool streaming_ = false;

  std::string card_;
  std::string driver_;
  std::string bus_;
  std::string serial_;                // the device's own, from sysfs; empty when it has none
  std::vector<std::string> formats_;  // what the device offers, by fourcc
  v4l2_pix_format format_{};          // as the driver set it
  PixelLayout layout_ = PixelLayout::kYUYV;

  double applied_fps_ = 0;
  std::optional<double> camera_fps_;   // last rate the camera passed
  std::optional<double> runtime_fps_;  // set once the camera's rate changed at run time
  bool trigger_mode_ = false;
  bool trigger_pending_ = false;
  bool timestamps_monotonic_ = false;  // as the last buffer said
  uint64_t trigger_ns_ = 0;            // CLOCK_MONOTONIC at the trigger
  uint64_t dropped_ = 0;
  DriverCounters counters_;
  int skip_left_ = 0;  // frames still to drop since STREAMON
  std::optional<uint32_t> last_device_sequence_;
  std::set<uint32_t> switched_to_manual_;  // controls whose auto mode a write turned off  // of the
                                           // last buffer since STREAMON
};

}  // namespace picksight::video
