// The PLC device's gates driven without a network (requests framed by hand,
// replies to a socket pair, as the fuzzer does): a trigger while results
// are still valid is a missed trigger and runs no LOCATE, and the largest
// part type a PLC may select is 9999 inclusive.
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <memory>
#include <thread>

#include "picksight/plc/plc_device.hpp"

using namespace picksight;
using namespace picksight::plc;

namespace {

// A PlcDevice whose LOCATE answers at once and counts its calls, fed whole
// Modbus TCP requests; its replies land on the far end of a socket pair.
class DeviceOnPair {
 public:
  DeviceOnPair()
      : device_(
            PlcDeviceOptions{},
            [this](int type) -> Result<PlcResult> {
              ++calls_;
              last_type_ = type;
              return PlcResult{};
            },
            [] { return kFrameVisionMm; }, [](const Error&) { return 99; }) {
    REQUIRE(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds_) == 0);
    ctx_ = modbus_new_tcp("127.0.0.1", 502);
    REQUIRE(ctx_ != nullptr);
    modbus_set_socket(ctx_, fds_[0]);
    device_.start();
  }
  ~DeviceOnPair() {
    device_.stop();
    modbus_set_socket(ctx_, -1);
    modbus_free(ctx_);
    ::close(fds_[0]);
    ::close(fds_[1]);
  }
  DeviceOnPair(const DeviceOnPair&) = delete;
  DeviceOnPair& operator=(const DeviceOnPair&) = delete;

  // Writes one register (function 6); returns the reply's function code
  // (6, or 0x86 for an exception) and its exception code in `exception`.
  uint8_t write(uint16_t address, uint16_t value, uint8_t* exception = nullptr) {
    const uint8_t adu[] = {0,
                           ++transaction_,
                           0,
                           0,
                           0,
                           6,
                           1,
                           MODBUS_FC_WRITE_SINGLE_REGISTER,
                           static_cast<uint8_t>(address >> 8),
                           static_cast<uint8_t>(address),
                           static_cast<uint8_t>(value >> 8),
                           static_cast<uint8_t>(value)};
    REQUIRE(device_.handle(ctx_, adu, sizeof(adu)));
    uint8_t reply[64];
    const ssize_t n = ::recv(fds_[1], reply, sizeof(reply), MSG_DONTWAIT);
    REQUIRE(n >= 9);
    if (exception) *exception = reply[8];
    return reply[7];
  }
  uint16_t reg(uint16_t address) const { return device_.registers()[address]; }
  // Waits (bounded) until the worker has finished the LOCATE it was given.
  void waitIdle() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (reg(reg::kStatus) & kStatusBusy) {
      REQUIRE(std::chrono::steady_clock::now() < deadline);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  int calls() const { return calls_; }
  int lastType() const { return last_type_; }

 private:
  std::atomic<int> calls_{0};
  std::atomic<int> last_type_{-2};
  PlcDevice device_;
  modbus_t* ctx_ = nullptr;
  int fds_[2] = {-1, -1};
  uint8_t transaction_ = 0;
};

}  // namespace

TEST_CASE("a trigger before the results are acknowledged is missed and runs no LOCATE",
          "[plc][handshake]") {
  DeviceOnPair plc;
  REQUIRE(plc.write(reg::kControl, kControlTrigger) == MODBUS_FC_WRITE_SINGLE_REGISTER);
  plc.waitIdle();
  REQUIRE((plc.reg(reg::kStatus) & kStatusResultsValid) != 0);
  REQUIRE(plc.calls() == 1);
  // The trigger dropped and raised again without an acknowledge: the PLC
  // has not taken the results yet, so they must not be overwritten.
  plc.write(reg::kControl, 0);
  plc.write(reg::kControl, kControlTrigger);
  plc.waitIdle();
  CHECK(plc.reg(reg::kMissedTriggers) == 1);
  CHECK(plc.reg(reg::kTriggerCount) == 1);
  CHECK(plc.calls() == 1);
  CHECK((plc.reg(reg::kStatus) & kStatusResultsValid) != 0);
  // Acknowledged, the next trigger runs.
  plc.write(reg::kControl, kControlResultsAck);
  CHECK(plc.reg(reg::kStatus) & kStatusReady);
  plc.write(reg::kControl, kControlTrigger);
  plc.waitIdle();
  CHECK(plc.reg(reg::kTriggerCount) == 2);
  CHECK(plc.calls() == 2);
}

TEST_CASE("part types 0 to 9999 and all types are accepted and 10000 and above refused",
          "[plc][exceptions]") {
  DeviceOnPair plc;
  for (uint16_t type : {uint16_t{0}, uint16_t{9999}, kAllTypes}) {
    INFO("type " << type);
    CHECK(plc.write(reg::kPartType, type) == MODBUS_FC_WRITE_SINGLE_REGISTER);
    CHECK(plc.reg(reg::kPartType) == type);
  }
  plc.write(reg::kPartType, 9999);
  for (uint16_t type : {uint16_t{10000}, uint16_t{65534}}) {
    INFO("type " << type);
    uint8_t exception = 0;
    CHECK(plc.write(reg::kPartType, type, &exception) == (MODBUS_FC_WRITE_SINGLE_REGISTER | 0x80));
    CHECK(exception == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    CHECK(plc.reg(reg::kPartType) == 9999);
  }
  // The largest type reaches the LOCATE as itself.
  plc.write(reg::kControl, kControlTrigger);
  plc.waitIdle();
  CHECK(plc.lastType() == 9999);
}
