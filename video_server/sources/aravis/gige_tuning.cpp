// GigE Vision host tuning: packet sockets, a real-time stream thread, the
// socket buffer the kernel grants.
#include "gige_tuning.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <fstream>
#include <sstream>

namespace picksight::video {
namespace {

constexpr int kCapNetRaw = 13;  // linux/capability.h

// Whether the effective capability set holds `bit`, from /proc/self/status
// (no libcap needed for one bit).
bool hasCapability(int bit) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("CapEff:", 0) != 0) continue;
    unsigned long long mask = 0;
    std::istringstream(line.substr(7)) >> std::hex >> mask;
    return (mask >> bit) & 1ull;
  }
  return false;
}

bool onLoopback(ArvGvDevice* device) {
  GSocketAddress* address = arv_gv_device_get_device_address(device);  // the device's own
  if (address == nullptr || !G_IS_INET_SOCKET_ADDRESS(address)) return false;
  GInetAddress* inet = g_inet_socket_address_get_address(G_INET_SOCKET_ADDRESS(address));
  return inet != nullptr && g_inet_address_get_is_loopback(inet);
}

}  // namespace

ArvGvStreamOption gigeStreamOption(ArvGvDevice* device) {
  if (hasCapability(kCapNetRaw) && !onLoopback(device)) return ARV_GV_STREAM_OPTION_NONE;
  return ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED;
}

std::optional<size_t> grantedSocketBuffer(size_t requested) {
  std::ifstream in("/proc/sys/net/core/rmem_max");
  size_t limit = 0;
  if (!(in >> limit) || limit == 0) return std::nullopt;
  return std::min(requested, limit);
}

std::string socketBufferWarning(size_t requested, size_t granted) {
  if (granted >= requested) return {};
  return "the kernel caps the stream's socket buffer at " + std::to_string(granted / 1024) +
         " KiB (net.core.rmem_max), " + std::to_string(requested / 1024) +
         " KiB asked: frames will lose packets under load; run "
         "sysctl -w net.core.rmem_max=" +
         std::to_string(requested) +
         " (and put it in /etc/sysctl.d to keep it, see docs/CAMERAS.md)";
}

void onStreamEvent(void* data, ArvStreamCallbackType type, ArvBuffer* /*buffer*/) noexcept {
  if (type != ARV_STREAM_CALLBACK_TYPE_INIT || data == nullptr) return;
  sched_param param{};
  param.sched_priority = kStreamPriority;
  const bool granted = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
  static_cast<std::atomic<int>*>(data)->store(granted ? 1 : -1);
}

}  // namespace picksight::video
