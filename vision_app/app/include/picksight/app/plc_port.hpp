// A cell's PLC port: the Modbus device over the cell's LOCATE path and the
// Modbus TCP server in front of it, wired as picksight-vision runs them.
//
// Threading: as PlcDevice (a worker) and ModbusServer (a socket thread);
// construct, start and stop from one thread. The cell outlives the port.
#pragma once

#include <cstdint>

#include "picksight/app/vision_cell.hpp"
#include "picksight/plc/modbus_server.hpp"
#include "picksight/plc/plc_device.hpp"

namespace picksight::app {

struct PlcPortOptions {
  bool enabled = false;  // --modbus-port given
  plc::ModbusServerOptions server;
  plc::PlcDeviceOptions device;
};

class PlcPort {
 public:
  // Listens at once; throws std::runtime_error naming the port.
  PlcPort(const PlcPortOptions& options, VisionCell& cell);
  ~PlcPort() { stop(); }

  void start();
  void stop();
  uint16_t port() const { return server_.port(); }
  const plc::PlcDevice& device() const { return device_; }

 private:
  plc::PlcDevice device_;
  plc::ModbusServer server_;
};

}  // namespace picksight::app
