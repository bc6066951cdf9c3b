// The Modbus TCP server PLCs connect to: listens, refuses peers the
// allow-list does not name, frames each connection's requests and hands
// them to a PlcDevice (which replies with libmodbus). One socket thread
// serves every connection (a request costs microseconds: a LOCATE runs on
// the device's worker), so the robot port, which has threads of its own,
// never waits for a PLC.
//
// Threading: one thread, started by start(); the constructor and stop()
// from the owning thread. The device is borrowed and outlives the server.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>

#include "picksight/common/allow_list.hpp"
#include "picksight/plc/plc_device.hpp"

namespace picksight::plc {

struct ModbusServerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t port = 502;                            // 0 = any free port (read it back with port())
  AllowList allow;                                // empty: every peer
  size_t max_connections = 16;                    // more are closed at once
  std::chrono::milliseconds idle_timeout{60000};  // a silent connection is closed
};

class ModbusServer {
 public:
  // Binds and listens at once; throws std::runtime_error naming the port.
  ModbusServer(ModbusServerOptions options, PlcDevice& device);
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  uint16_t port() const { return port_; }
  void start();
  void stop();
  size_t connections() const { return connections_.load(); }

 private:
  void loop();

  const ModbusServerOptions options_;
  PlcDevice& device_;
  modbus_t* replier_ = nullptr;  // a context for replies, pointed at each connection in turn
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> connections_{0};
};

}  // namespace picksight::plc
