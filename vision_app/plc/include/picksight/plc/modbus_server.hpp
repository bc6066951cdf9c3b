// The Modbus TCP server PLCs connect to: admits peers as TcpListener does
// on every PickSight port, frames each connection's requests and hands
// them to a PlcDevice (which replies with libmodbus). One socket thread
// serves every connection (a request costs microseconds: a LOCATE runs on
// the device's worker), so the robot port, which has threads of its own,
// never waits for a PLC.
//
// Threading: one thread, started by start(); the constructor and stop()
// from the owning thread. The device is borrowed and outlives the server.
#pragma once

#include <atomic>
#include <thread>

#include "picksight/common/tcp_listener.hpp"
#include "picksight/plc/plc_device.hpp"

namespace picksight::plc {

struct ModbusServerOptions {
  // Where and whom: the admission policy every PickSight port shares (a
  // silent connection is closed after idle_timeout).
  TcpListenerOptions listen = [] {
    TcpListenerOptions o;
    o.port = 502;
    o.max_connections = 16;
    o.max_per_address = 8;
    return o;
  }();
};

class ModbusServer {
 public:
  // Binds and listens at once; throws std::runtime_error naming the port.
  ModbusServer(ModbusServerOptions options, PlcDevice& device);
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  uint16_t port() const { return listener_.port(); }
  void start();
  void stop();
  size_t connections() const { return listener_.connections(); }

 private:
  void loop();

  const ModbusServerOptions options_;
  PlcDevice& device_;
  modbus_t* replier_ = nullptr;  // a context for replies, pointed at each connection in turn
  TcpListener listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace picksight::plc
