// libv4l2-backed V4L2 device access.
#include "lib_v4l2_device.hpp"

#include <libv4l2.h>

#include <filesystem>
#include <fstream>
#include <system_error>

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

// /sys/class/video4linux/videoN/device is the USB interface the node belongs
// to; its parent, the USB device, holds the iSerialNumber string as `serial`.
std::string LibV4l2Device::serialNumber(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path node = fs::canonical(path, ec);  // follows /dev/v4l/by-id links
  if (ec) return {};
  const fs::path device = fs::path("/sys/class/video4linux") / node.filename() / "device";
  const fs::path usb = fs::canonical(device, ec).parent_path();
  if (ec) return {};
  std::ifstream in(usb / "serial");
  std::string serial;
  std::getline(in, serial);
  while (!serial.empty() && (serial.back() == ' ' || serial.back() == '\r')) serial.pop_back();
  return serial;
}

}  // namespace picksight::video
