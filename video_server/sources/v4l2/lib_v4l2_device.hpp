// The real V4L2 device access: libv4l2, which converts formats a camera
// cannot deliver natively and works around driver quirks, plus poll(2).
#pragma once

#include "v4l2_device.hpp"

namespace picksight::video {

class LibV4l2Device : public V4l2Device {
 public:
  int open(const std::string& path, int flags) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(size_t length, int prot, int flags, int fd, off_t offset) override;
  int munmap(void* address, size_t length) override;
  int poll(pollfd* fds, nfds_t count, int timeout_ms) override;
  std::string serialNumber(const std::string& path) override;
};

}  // namespace picksight::video
