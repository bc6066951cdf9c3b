// A PLC for the tests: libmodbus's own client on a real TCP connection, with
// the handshake's steps and a deadline on every wait.
#pragma once

#include <modbus/modbus.h>

#include <catch2/catch.hpp>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <functional>
#include <thread>
#include <vector>

#include "picksight/plc/register_map.hpp"

namespace picksight::plc::test {

class ModbusClient {
 public:
  explicit ModbusClient(uint16_t port, int unit = 1) {
    ctx_ = modbus_new_tcp("127.0.0.1", port);
    REQUIRE(ctx_ != nullptr);
    modbus_set_slave(ctx_, unit);
    modbus_set_response_timeout(ctx_, 5, 0);
    REQUIRE(modbus_connect(ctx_) == 0);
  }
  ~ModbusClient() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  ModbusClient(const ModbusClient&) = delete;
  ModbusClient& operator=(const ModbusClient&) = delete;

  modbus_t* ctx() { return ctx_; }

  std::vector<uint16_t> read(int address, int count) {
    std::vector<uint16_t> out(static_cast<size_t>(count));
    const int n = modbus_read_registers(ctx_, address, count, out.data());
    INFO("read " << address << "+" << count << ": " << modbus_strerror(errno));
    REQUIRE(n == count);
    return out;
  }
  uint16_t read(int address) { return read(address, 1)[0]; }
  void write(int address, uint16_t value) {
    INFO("write " << address << "=" << value << ": " << modbus_strerror(errno));
    REQUIRE(modbus_write_register(ctx_, address, value) == 1);
  }
  // The Modbus exception a write draws (errno after the call), 0 if none.
  int writeError(int address, uint16_t value) {
    return modbus_write_register(ctx_, address, value) == 1 ? 0 : errno;
  }
  int readError(int address, int count) {
    std::vector<uint16_t> out(static_cast<size_t>(count));
    return modbus_read_registers(ctx_, address, count, out.data()) == count ? 0 : errno;
  }

  uint16_t status() { return read(reg::kStatus); }

  // Polls the status until `bits` are all set; REQUIREs it within `limit`.
  uint16_t waitFor(uint16_t bits, std::chrono::seconds limit = std::chrono::seconds(20)) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    uint16_t s = 0;
    while (((s = status()) & bits) != bits) {
      INFO("status " << s << ", waiting for " << bits);
      REQUIRE(std::chrono::steady_clock::now() < deadline);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return s;
  }

  // Selects `type`, raises the trigger, waits for results valid or error,
  // drops the trigger; returns the status after that.
  uint16_t trigger(uint16_t type) {
    waitFor(kStatusReady);
    write(reg::kPartType, type);
    write(reg::kControl, kControlTrigger);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    uint16_t s = 0;
    while (((s = status()) & (kStatusResultsValid | kStatusError)) == 0) {
      REQUIRE(std::chrono::steady_clock::now() < deadline);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    write(reg::kControl, 0);
    return status();
  }
  // Acknowledges the results (a rising edge of the ack bit, then back to 0).
  void acknowledge() {
    write(reg::kControl, kControlResultsAck);
    write(reg::kControl, 0);
  }

  struct Part {
    int type;
    float x, y, rz, score;
  };
  std::vector<Part> parts(WordOrder order = WordOrder::kABCD) {
    const int count = read(reg::kPartCount);
    std::vector<Part> out;
    if (count == 0) return out;
    for (int i = 0; i < count; ++i) {  // a read is at most 125 registers
      const auto r = read(reg::kFirstPart + reg::kPartStride * i, reg::kPartStride);
      const uint16_t* b = r.data();
      out.push_back({static_cast<int16_t>(b[reg::kOffsetType]), getFloat(b + reg::kOffsetX, order),
                     getFloat(b + reg::kOffsetY, order), getFloat(b + reg::kOffsetRz, order),
                     getFloat(b + reg::kOffsetScore, order)});
    }
    return out;
  }

 private:
  modbus_t* ctx_ = nullptr;
};

}  // namespace picksight::plc::test
