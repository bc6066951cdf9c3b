// libv4l2-backed V4L2 device access.
#include "lib_v4l2_device.hpp"

#include <libv4l2.h>

namespace picksight::video {

int LibV4l2Device::open(const std::string& path, int flags) {
  return v4l2_open(path.c_str(), flags);
}

int LibV4l2Device::close(int fd) { return v4l2_close(fd); }

int LibV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  return v4l2_ioctl(fd, request, arg);
}

void* LibV4l2Device::mmap(size_t length, int prot, int flags, int fd, off_t offset) {
  return v4l2_mmap(nullptr, length, prot, flags, fd, static_cast<int64_t>(offset));
}

int LibV4l2Device::munmap(void* address, size_t length) { return v4l2_munmap(address, length); }

// libv4l2 has no poll of its own: the descriptor v4l2_open returns is the
// device's, and its readiness is the device's.
int LibV4l2Device::poll(pollfd* fds, nfds_t count, int timeout_ms) {
  return ::poll(fds, count, timeout_ms);
}

}  // namespace picksight::video
