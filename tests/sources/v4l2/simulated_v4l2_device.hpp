// A simulated V4L2 webcam behind the driver's device interface: formats and
// frame sizes, mmap buffers, YUYV and MJPEG frames with known content,
// controls with a menu and an inactive control, and injected faults
// (EINTR, EAGAIN, error-flagged frames, a device that disappears).
#pragma once

#include <linux/videodev2.h>

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "v4l2/v4l2_device.hpp"

namespace picksight::video::testing {

class SimulatedV4l2Device : public V4l2Device {
 public:
  static constexpr const char* kPath = "/dev/video0";

  SimulatedV4l2Device();

  // The Y value (YUYV) or grey level (MJPEG) of frame `n`, distinct for
  // neighbouring frames.
  static uint8_t level(uint64_t n) { return static_cast<uint8_t>(16 + (n * 7) % 200); }

  int open(const std::string& path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(size_t length, int prot, int flags, int fd, off_t offset) override;
  int munmap(void* address, size_t length) override;
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override;
  std::string serialNumber(const std::string& path) override;

  // --- Test controls, safe from any thread.
  void setGrantedBuffers(uint32_t n);  // what REQBUFS grants at most
  void injectIoctlEintr(int n);        // the next n ioctls fail with EINTR
  void injectPollEintr(int n);
  void injectDqbufEagain(int n);  // poll says readable, DQBUF says EAGAIN
  void injectErrorFrames(int n);  // the next n frames carry V4L2_BUF_FLAG_ERROR
  void injectLostFrames(int n);   // the next n frames are numbered but never delivered
  void setPaused(bool paused);    // no frames: poll times out
  // Unplugs: every call fails with ENODEV (poll too when `poll_fails`, else
  // poll reports POLLERR and DQBUF fails).
  void unplug(bool poll_fails);
  void replug();
  void setSerial(const std::string& serial);  // what sysfs would say ("" = none)
  // Fills up to n queued buffers now, as frames captured before whatever comes next.
  void captureNow(int n);

  struct State {
    int open_fds = 0;
    int mapped = 0;
    uint32_t buffers = 0;
    bool streaming = false;
    int streamons = 0;
    uint32_t pixelformat = 0;
    uint32_t width = 0;
    uint32_t height = 0;
    double fps = 0;
    uint64_t frames = 0;  // frames produced so far
  };
  State state() const;
  int32_t controlValue(uint32_t id) const;

 private:
  struct Format {
    uint32_t fourcc;
    std::vector<std::pair<uint32_t, uint32_t>> sizes;
    std::vector<std::vector<double>> rates;  // per size, frames per second
  };
  struct Control {
    v4l2_queryctrl query;
    int32_t value;
    std::vector<std::pair<uint32_t, std::string>> menu;  // valid indices only
  };
  struct Buffer {
    std::vector<uint8_t> bytes;
    v4l2_buffer done{};  // as DQBUF reports it once filled
  };

  int doIoctl(unsigned long request, void* arg);  // mutex_ held
  void fill(uint32_t index);                      // mutex_ held
  Control* control(uint32_t id);                  // mutex_ held
  const Format* format(uint32_t fourcc) const;    // mutex_ held
  void setFormat(v4l2_pix_format& pix);           // mutex_ held

  mutable std::mutex mutex_;  // guards everything below
  std::vector<Format> formats_;
  std::vector<Control> controls_;
  v4l2_pix_format pix_{};
  double fps_ = 30;
  uint32_t granted_ = 3;
  std::vector<Buffer> buffers_;
  std::deque<uint32_t> queued_;  // empty, waiting for a frame
  std::deque<uint32_t> done_;    // filled, waiting for DQBUF
  bool streaming_ = false;
  int streamons_ = 0;
  int open_fds_ = 0;
  int mapped_ = 0;
  uint64_t frames_ = 0;
  int ioctl_eintr_ = 0;
  int poll_eintr_ = 0;
  int dqbuf_eagain_ = 0;
  int error_frames_ = 0;
  int lost_frames_ = 0;
  std::string serial_;
  bool paused_ = false;
  bool gone_ = false;
  bool poll_fails_ = false;
};

}  // namespace picksight::video::testing
