// PLC port wiring.
#include "picksight/app/plc_port.hpp"

#include "picksight/plc/cell_picker.hpp"

namespace picksight::app {

PlcPort::PlcPort(const PlcPortOptions& options, VisionCell& cell)
    : device_(options.device, plc::cellPicker(cell.context(), cell.results(), cell.filmstrip()),
              plc::cellFrameState(cell.calibration()), plc::robotErrorCodeOf),
      server_(options.server, device_) {
  device_.setJobs(plc::cellJobLoader(cell.jobs()), plc::cellJobState(cell.jobs()));
}

void PlcPort::start() {
  device_.start();
  server_.start();
}

void PlcPort::stop() {
  // No request after the device stops: the server goes first.
  server_.stop();
  device_.stop();
}

}  // namespace picksight::app
