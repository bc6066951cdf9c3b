// The narrow system interface the V4L2 driver talks to a device through:
// libv4l2 in production, a simulated device in tests (these machines have no
// V4L2 devices and cannot load kernel modules).
#pragma once

#include <poll.h>
#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace picksight::video {

// Every call has the POSIX contract of its namesake: -1 (MAP_FAILED for
// mmap) and errno on failure. Retrying on EINTR is the caller's job, so the
// driver's handling of it is testable. Implementations must be safe to call
// from one thread at a time per device.
class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  virtual int open(const std::string& path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual void* mmap(size_t length, int prot, int flags, int fd, off_t offset) = 0;
  virtual int munmap(void* address, size_t length) = 0;
  virtual int poll(pollfd* fds, nfds_t count, int timeout_ms) = 0;
  // The serial number the device behind `path` (a /dev/videoN or a
  // /dev/v4l/by-id link to one) reports, from sysfs; empty when it has
  // none, as many cheap webcams.
  virtual std::string serialNumber(const std::string& path) = 0;
};

// A fixed-size, maybe unterminated kernel string.
template <size_t N>
std::string kernelString(const uint8_t (&bytes)[N]) {
  const auto* chars = reinterpret_cast<const char*>(bytes);
  return std::string(chars, strnlen(chars, N));
}

// A device file descriptor, closed through its device. Move-only.
class V4l2Fd {
 public:
  V4l2Fd() = default;
  V4l2Fd(V4l2Device& device, int fd) : device_(&device), fd_(fd) {}
  ~V4l2Fd() { reset(); }
  V4l2Fd(V4l2Fd&& other) noexcept : device_(other.device_), fd_(other.fd_) { other.fd_ = -1; }
  V4l2Fd& operator=(V4l2Fd&& other) noexcept {
    if (this != &other) {
      reset();
      device_ = other.device_;
      fd_ = other.fd_;
      other.fd_ = -1;
    }
    return *this;
  }
  V4l2Fd(const V4l2Fd&) = delete;
  V4l2Fd& operator=(const V4l2Fd&) = delete;

  int get() const { return fd_; }
  explicit operator bool() const { return fd_ >= 0; }
  void reset() {
    if (fd_ >= 0) device_->close(fd_);
    fd_ = -1;
  }

 private:
  V4l2Device* device_ = nullptr;  // borrowed: the source owns both
  int fd_ = -1;
};

// One mmap'ed capture buffer, unmapped through its device. Move-only.
class V4l2Mapping {
 public:
  V4l2Mapping(V4l2Device& device, void* address, size_t length)
      : device_(&device), address_(address), length_(length) {}
  ~V4l2Mapping() {
    if (address_ != nullptr) device_->munmap(address_, length_);
  }
  V4l2Mapping(V4l2Mapping&& other) noexcept
      : device_(other.device_), address_(other.address_), length_(other.length_) {
    other.address_ = nullptr;
  }
  V4l2Mapping& operator=(V4l2Mapping&&) = delete;
  V4l2Mapping(const V4l2Mapping&) = delete;
  V4l2Mapping& operator=(const V4l2Mapping&) = delete;

  const unsigned char* data() const { return static_cast<const unsigned char*>(address_); }
  size_t length() const { return length_; }

 private:
  V4l2Device* device_;  // borrowed: the source owns both
  void* address_;
  size_t length_;
};

}  // namespace picksight::video
