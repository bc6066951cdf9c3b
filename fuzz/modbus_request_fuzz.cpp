// libFuzzer target: arbitrary bytes as a Modbus TCP stream through the PLC
// port's framing and request handler (PlcDevice), without a network: the
// replies go to one end of a socket pair and are checked at the other.
// Every framed request must get exactly one well-formed reply (its own or
// an exception), and nothing may crash, hang or grow without bound.
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <memory>

#include "picksight/plc/plc_device.hpp"

namespace {
using namespace picksight;
using namespace picksight::plc;

// A LOCATE that answers at once: odd types fail, even ones give more parts
// than the registers hold, so both result paths run.
Result<PlcResult> fakeLocate(int type) {
  if (type % 2 != 0) return makeError(std::errc::timed_out, "no frame");
  PlcResult result;
  result.frame_sequence = static_cast<uint64_t>(type) * 7919;
  for (int i = 0; i < 20; ++i) result.parts.push_back({type, i * 1.5, -i * 2.5, i * 17.0, 0.9});
  return result;
}

struct Harness {
  Harness()
      : device(
            PlcDeviceOptions{}, fakeLocate, [] { return kFrameRobot; },
            [](const Error&) { return 20; }) {
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) std::abort();
    ctx = modbus_new_tcp("127.0.0.1", 502);
    if (!ctx) std::abort();
    modbus_set_socket(ctx, fds[0]);
    device.start();
  }
  ~Harness() {
    device.stop();
    modbus_set_socket(ctx, -1);
    modbus_free(ctx);
    ::close(fds[0]);
    ::close(fds[1]);
  }
  PlcDevice device;
  modbus_t* ctx = nullptr;
  int fds[2] = {-1, -1};
};

Harness& harness() {
  static Harness instance;
  return instance;
}

void checkReply(int fd, const uint8_t* request) {
  uint8_t reply[600];
  const ssize_t n = ::recv(fd, reply, sizeof(reply), MSG_DONTWAIT);
  if (n < 9) std::abort();  // MBAP, function, at least one byte
  const auto length = aduLength(reply, static_cast<size_t>(n));
  if (!length || *length != static_cast<size_t>(n)) std::abort();  // one reply, well framed
  if (reply[0] != request[0] || reply[1] != request[1] || reply[6] != request[6]) std::abort();
  if ((reply[7] & 0x7F) != request[7]) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Harness& h = harness();
  size_t at = 0;
  while (at < size) {
    const auto length = aduLength(data + at, size - at);
    if (!length || *length == 0) break;  // the server closes, or waits for more
    if (h.device.handle(h.ctx, data + at, *length)) checkReply(h.fds[1], data + at);
    at += *length;
  }
  return 0;
}
