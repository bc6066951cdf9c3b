// V4L2 camera source: opening and closing the device, the frame rate and
// acquisition mode. Format negotiation, streaming and controls are in
// v4l2_format_negotiation.cpp, v4l2_streaming.cpp and v4l2_controls.cpp.
#include "v4l2_source.hpp"

#include <fcntl.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "lib_v4l2_device.hpp"
#include "picksight/common/log.hpp"

namespace picksight::video {
namespace {

// Errnos that mean the device is gone or broken, not that a request was wrong.
bool deviceLost(int err) { return err == ENODEV || err == EIO || err == ENXIO || err == EBADF; }

}  // namespace

V4l2Source::V4l2Source(V4l2Options options, std::unique_ptr<V4l2Device> device)
    : options_(std::move(options)),
      device_(device ? std::move(device) : std::make_unique<LibV4l2Device>()) {}

V4l2Source::~V4l2Source() { close(); }

int V4l2Source::xioctl(unsigned long request, void* arg) {
  int r;
  do {
    r = device_->ioctl(fd_.get(), request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

Error V4l2Source::deviceError(const std::string& what, bool streaming) {
  const int err = errno;
  // While streaming every failure means reopening; before, a request the
  // device refuses (EINVAL) is a configuration it will always refuse.
  const bool lost = streaming || deviceLost(err) || err == EBUSY || err == ENOENT || err == EACCES;
  return makeError(lost ? SourceErrc::kUnavailable : SourceErrc::kBadConfig,
                   "v4l2:" + options_.path + ": " + what + ": " + std::strerror(err));
}

double V4l2Source::desiredFps() const {
  if (runtime_fps_) return *runtime_fps_;
  if (options_.fps > 0) return options_.fps;
  return camera_fps_.value_or(0);
}

Result<void> V4l2Source::open() {
  close();
  auto opened = openDevice();
  if (!opened) close();  // a half-opened device is released, so the retry starts clean
  return opened;
}

Result<void> V4l2Source::openDevice() {
  // Non-blocking, so DQBUF never waits: grab() waits in poll, with its timeout.
  const int fd = device_->open(options_.path, O_RDWR | O_NONBLOCK);
  if (fd < 0) return deviceError("cannot open");
  fd_ = V4l2Fd(*device_, fd);

  v4l2_capability cap{};
  if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) return deviceError("VIDIOC_QUERYCAP");
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
    // A UVC camera also registers a metadata node (often /dev/video1).
    return makeError(SourceErrc::kBadConfig, "v4l2:" + options_.path + " (" +
                                                 kernelString(cap.card) +
                                                 ") is not a streaming video capture device");
  }
  card_ = kernelString(cap.card);
  driver_ = kernelString(cap.driver);
  bus_ = kernelString(cap.bus_info);
  serial_ = device_->serialNumber(options_.path);

  if (auto r = chooseFormat(); !r) return r;
  // A replugged device starts at its default rate.
  applied_fps_ = 0;
  if (auto r = applyFrameRate(desiredFps()); !r) return r;
  if (auto r = startStreaming(); !r) return r;
  trigger_pending_ = false;
  dropped_ = 0;
  switched_to_manual_.clear();  // a reopened device may be back in its auto modes
  return {};
}

void V4l2Source::close() {
  if (!fd_) return;
  stopStreaming();
  const bool had_buffers = !buffers_.empty();
  buffers_.clear();  // munmap before freeing: REQBUFS(0) refuses mapped buffers
  if (had_buffers) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(VIDIOC_REQBUFS, &req);  // a gone device fails here; closing frees them anyway
  }
  fd_.reset();
}

Error V4l2Source::notOpen() const {
  return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": not open");
}

SourceInfo V4l2Source::info() const {
  SourceInfo i;
  i.vendor = driver_;
  i.model = card_;
  // bus_info names the USB port, not the camera: a stand-in, said as such,
  // for cameras without a serial number.
  i.serial = !serial_.empty() ? serial_ : "none (port " + bus_ + ")";
  i.sensor_width = static_cast<int>(format_.width);
  i.sensor_height = static_cast<int>(format_.height);
  i.formats = formats_;
  return i;
}

Result<void> V4l2Source::applyFrameRate(double fps) {
  if (fps <= 0 || std::abs(fps - applied_fps_) < 1e-6) return {};
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_PARM, &parm) < 0 || !(parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    applied_fps_ = fps;  // the device has one rate; nothing to set, nothing to retry
    return {};
  }
  // Drivers refuse S_PARM while streaming (EBUSY): stop, set, restart.
  const bool was_streaming = streaming_;
  stopStreaming();
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator = static_cast<uint32_t>(std::lround(fps * 1000));
  const int set = xioctl(VIDIOC_S_PARM, &parm);
  const Error failed =
      set < 0 ? deviceError("VIDIOC_S_PARM " + std::to_string(fps) + " fps") : Error{};
  if (was_streaming) {
    if (auto r = startStreaming(); !r) return r;
  }
  if (set < 0) return failed;
  applied_fps_ = fps;
  const auto& t = parm.parm.capture.timeperframe;  // what the driver chose
  if (t.numerator > 0 && std::abs(double(t.denominator) / t.numerator - fps) > 0.5) {
    logInfo("v4l2:", options_.path, ": asked ", fps, " fps, device runs at ",
            double(t.denominator) / t.numerator);
  }
  return {};
}

Result<void> V4l2Source::configureAcquisition(const AcquisitionRequest& request) {
  if (request.mode == AcquisitionMode::kHardwareTrigger) {
    // V4L2 has no trigger input: UVC webcams stream at their own pace.
    return makeError(SourceErrc::kNotSupported,
                     "v4l2 cameras have no hardware trigger input; use freerun or trigger");
  }
  const double fps = request.fps;
  trigger_mode_ = request.mode == AcquisitionMode::kTrigger;
  trigger_pending_ = false;
  // The URI's fps holds until the camera's rate changes at run time: the
  // first rate the camera passes is its configured default, not a request.
  if (camera_fps_ && std::abs(*camera_fps_ - fps) > 1e-6) runtime_fps_ = fps;
  camera_fps_ = fps;
  if (!fd_) return {};
  return applyFrameRate(desiredFps());
}

}  // namespace picksight::video
