// Command-line options of picksight-vision.
#pragma once

#include <string>
#include <vector>

#include "picksight/cell/vision_service.hpp"
#include "picksight/common/result.hpp"
#include "picksight/protocol/robot_server.hpp"
#include "picksight/vision_app/plc_port.hpp"

namespace picksight::app {

struct AppOptions {
  std::string frames_endpoint = "tcp://127.0.0.1:5555";
  std::string control_endpoint = "tcp://127.0.0.1:5556";
  std::string camera = "cam0";
  std::string data_dir = "picksight-data";
  RobotServerOptions robot;
  VisionOptions vision;
  PlcPortOptions plc;  // off unless --modbus-port is given
};

// Parses argv without the program name; errors name the option.
Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help);
std::string appUsage();

}  // namespace picksight::app
