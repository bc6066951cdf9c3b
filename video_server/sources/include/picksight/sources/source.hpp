// The camera source interface: every driver (synthetic, file, dir, stream,
// v4l2, aravis) implements it in its own folder under sources/, and
// makeSource (source_factory.cpp) builds one from its source string.
//
// Threading: a Source is owned by one Camera and called from that camera's
// acquisition thread only, except where a method says otherwise.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/frame.hpp"
#include "picksight/common/result.hpp"

namespace picksight::video {

// kTrigger: one frame per software trigger. kHardwareTrigger: one frame per
// pulse on the camera's trigger input (Aravis cameras); the device decides
// when a frame comes, so waiting for one is not silence.
enum class AcquisitionMode { kFreeRun, kTrigger, kHardwareTrigger };

// The camera input a hardware trigger comes on, as GenICam names it.
struct TriggerInput {
  std::string line = "Line1";  // TriggerSource
  std::string activation;      // TriggerActivation; empty = as the camera is set
};

// The acquisition a camera wants. A streaming source writes to the device
// only what was asked: a trigger or a frame rate the device was configured
// with (its own settings, or features) survives otherwise.
struct AcquisitionRequest {
  AcquisitionMode mode = AcquisitionMode::kFreeRun;
  double fps = 10;          // the rate; on-demand sources are paced at it regardless
  bool mode_asked = false;  // free-run asked explicitly: leave any trigger mode
  bool fps_asked = false;   // the rate asked explicitly: set the device's
  TriggerInput input;       // kHardwareTrigger only
};

// The driver's own counters of what went wrong below us, summed over the
// source's lifetime (reopenings included). 0 where the driver has none.
struct DriverCounters {
  uint64_t incomplete_buffers = 0;  // buffers the driver flagged bad or incomplete
  uint64_t missing_packets = 0;     // GigE Vision: packets never received
  uint64_t resent_packets = 0;      // GigE Vision: packets asked for again
  uint64_t underruns = 0;           // frames lost for want of a free buffer
  uint64_t sequence_gaps = 0;       // frames the device numbered but never delivered
  // Complete frames passed over because a newer one was already waiting
  // (free-run hands over the newest): latency avoided, not a fault.
  uint64_t skipped_stale = 0;
};

// How a source's frame bytes are laid out. Mono10/12/16 and Bayer**10/12/16
// arrive unpacked in 16-bit words (CV_16UC1, the value in the low bits),
// YUYV/UYVY as CV_8UC2, MJPEG as one row of bytes (CV_8UC1, 1 x size); the
// packed mono formats as CV_8UC1 rows of their packed bytes (a row holds
// whole pixel groups: 4 pixels in 5 bytes for Mono10p, 2 in 3 bytes for the
// others); the rest as their OpenCV 8-bit equivalents.
enum class PixelLayout {
  kMono8,
  kMono10,
  kMono12,
  kMono16,
  kBayerRG8,
  kBayerGR8,
  kBayerBG8,
  kBayerGB8,
  kRGB8,
  kBGR8,
  kYUYV,
  kUYVY,
  kMJPEG,
  // GenICam PFNC packing: bits of consecutive pixels, least significant first.
  kMono10p,
  kMono12p,
  // GigE Vision's older packing: two pixels in three bytes, high bits in the
  // outer bytes and the low bits of both in the middle one.
  kMono10Packed,
  kMono12Packed,
  kBayerRG10,
  kBayerGR10,
  kBayerBG10,
  kBayerGB10,
  kBayerRG12,
  kBayerGR12,
  kBayerBG12,
  kBayerGB12,
  kBayerRG16,
  kBayerGR16,
  kBayerBG16,
  kBayerGB16,
};

const char* pixelLayoutName(PixelLayout layout);

// A camera setting by name: GenICam features for Aravis, controls for V4L2.
enum class FeatureType { kInteger, kFloat, kEnumeration, kBoolean, kString, kCommand };

struct Feature {
  std::string name;
  FeatureType type = FeatureType::kString;
  std::string value;  // current value as text; empty for commands
  bool has_range = false;
  double min = 0;
  double max = 0;
  double increment = 0;              // 0 = any
  std::vector<std::string> choices;  // enumerations
  std::string unit;
  std::string description;
  bool writable = true;
};

// Ground truth of one part in a frame, in sensor pixels (synthetic sources):
// the frame's own type, carried unchanged to subscribers.
using picksight::TruthPart;

struct SourceFrame {
  // The frame at sensor resolution, laid out as `layout` says. May share
  // memory with the source's own buffers: consumers must not write into it,
  // and must not keep it past the next grab() unless they copied it.
  cv::Mat image;
  PixelLayout layout = PixelLayout::kMono8;
  uint64_t device_timestamp_ns = 0;  // 0 when the device gives none
  std::vector<TruthPart> truth;
  // True when the source never writes into these pixels again while anyone
  // else holds them (a fresh buffer, or a pooled one reused only once
  // released): consumers may then keep the image, and the camera publishes
  // it without copying.
  bool keepable = false;
  // How long before grab() returned it the frame was (by estimate) exposed,
  // from sources whose frames reach the host a pipeline delay late and carry
  // no clock the host can read (streams: the time since it arrived plus the
  // measured decode and buffering delay plus the configured latency). 0: the
  // frame counts as taken when grabbed.
  std::chrono::nanoseconds age{0};
  // The pixels went through lossy compression on their way here (a network
  // stream, a JPEG file; an MJPEG webcam's frames are known by `layout`):
  // colour at half resolution and quantised, which costs a part told from its
  // surface by colour alone tenths of a pixel (FrameInfo::compressed).
  bool compressed = false;
};

struct SourceInfo {
  std::string vendor;
  std::string model;
  std::string serial;
  int sensor_width = 0;
  int sensor_height = 0;
  std::vector<std::string> formats;  // formats the device delivers
};

// A simulated robot holding a calibration target in front of a synthetic
// camera: where the target is and the hidden robot-camera transform, for
// checking a calibration against (docs/PROTOCOL.md states the frames).
struct SimulatedRobot {
  bool target_visible = false;
  double target_x_mm = 0;  // robot mm, when visible
  double target_y_mm = 0;
  std::string target_kind;  // "disc" or "grid"
  double target_radius_mm = 0;
  int grid_rows = 0;  // grid targets only
  int grid_cols = 0;
  double grid_pitch_mm = 0;
  // robot = R(rz_deg) * vision + (dx_mm, dy_mm); vision = (u, -v) * mm_per_px
  double mm_per_px = 0;
  double rz_deg = 0;
  double dx_mm = 0;
  double dy_mm = 0;
  double tilt_x_deg = 0;
  double tilt_y_deg = 0;
  cv::Matx33d robot_to_sensor = cv::Matx33d::eye();  // sensor px ~ H * (X, Y, 1)
};

// Why a source call failed: the camera thread decides from it whether to
// retry, reopen or give up.
enum class SourceErrc {
  kTimeout = 1,     // no frame in time; try again
  kUnavailable,     // device gone or not openable; reopen with back-off
  kBadConfig,       // the source string is wrong; retrying will not help
  kUnknownFeature,  // no feature of that name
  kBadValue,        // feature value out of range or of the wrong type
  kNotSupported,    // the device cannot do that
};
const char* errorName(SourceErrc e);
PICKSIGHT_ERROR_DOMAIN(SourceErrc, "source")

class Source {
 public:
  virtual ~Source() = default;

  // Opens the device. Failure is a value: the camera retries with back-off.
  virtual Result<void> open() = 0;
  virtual void close() = 0;
  // Valid after a successful open().
  virtual SourceInfo info() const = 0;
  // Produces one frame. Sources that render or read on demand (synthetic,
  // file) make it now; the caller paces them. Streaming sources return the
  // next frame the device delivers, or SourceErrc::kTimeout.
  virtual Result<SourceFrame> grab(std::chrono::milliseconds timeout) = 0;

  // --- Acquisition. Defaults suit on-demand sources.
  // True when the device delivers frames at its own pace once configured
  // (a camera); the Camera then does not pace free-run itself.
  virtual bool streams() const { return false; }
  // True when grab() reports each frame's age (SourceFrame::age): the camera
  // then serves a request only with a frame estimated to be exposed after
  // it. A property of the driver, constant.
  virtual bool reportsAge() const { return false; }
  // Called after open() and whenever the mode or rate changes. A streaming
  // source sets its trigger mode (software) and frame rate here, as asked.
  virtual Result<void> configureAcquisition(const AcquisitionRequest& /*request*/) { return {}; }
  // In trigger mode, asks the device for one frame; grab() then returns it.
  virtual Result<void> softwareTrigger() { return {}; }
  // Whether configureAcquisition() can take kHardwareTrigger: a property of
  // the driver, constant, so any thread may ask.
  virtual bool hardwareTrigger() const { return false; }
  // The driver's counters as of now.
  virtual DriverCounters driverCounters() const { return {}; }

  // --- Features by name. Values travel as text and are checked by type and
  // range; errors name the feature and, for a range, the range.
  virtual std::vector<Feature> features() { return {}; }
  // The same list in pieces, so that a camera with hundreds of features
  // can grab frames between them: the names features() would list, read
  // without touching the device where the driver can, then each one as
  // features() would list it (nullopt: features() would leave it out). The
  // defaults go through features(), for drivers whose list is cheap.
  virtual std::vector<std::string> featureNames();
  virtual std::optional<Feature> listedFeature(const std::string& name);
  virtual Result<Feature> feature(const std::string& name) {
    return makeError(SourceErrc::kUnknownFeature, "unknown feature '" + name + "'");
  }
  virtual Result<void> setFeature(const std::string& name, const std::string& /*value*/) {
    return makeError(SourceErrc::kUnknownFeature, "unknown feature '" + name + "'");
  }

  // --- Simulated robot (synthetic sources): moves the calibration target to
  // robot (x, y) mm, or hides it (nullopt), from the next frame on; returns
  // the robot's state. Other sources: kNotSupported.
  virtual Result<SimulatedRobot> moveTarget(std::optional<cv::Point2d> /*at_mm*/) {
    return makeError(SourceErrc::kNotSupported, "this camera has no simulated robot");
  }
  virtual Result<SimulatedRobot> simulatedRobot() const {
    return makeError(SourceErrc::kNotSupported, "this camera has no simulated robot");
  }
};

// Builds a source from its string ("synthetic:", "synthetic:?width=..",
// "file:/path/img.png"). Errors name what is wrong with the string.
Result<std::unique_ptr<Source>> makeSource(const std::string& uri);

}  // namespace picksight::video

PICKSIGHT_ERROR_ENUM(picksight::video::SourceErrc)
