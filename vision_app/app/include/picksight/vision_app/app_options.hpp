// Command-line options of picksight-vision.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "picksight/cell/vision_service.hpp"
#include "picksight/common/result.hpp"
#include "picksight/protocol/robot_server.hpp"
#include "picksight/transport/curve_keys.hpp"

namespace picksight::app {

struct AppOptions {
  std::string frames_endpoint = "tcp://127.0.0.1:5555";
  std::string control_endpoint = "tcp://127.0.0.1:5556";
  std::string camera = "cam0";
  std::string data_dir = "picksight-data";
  RobotServerOptions robot;
  VisionOptions vision;
  // CURVE keys for the camera link (loaded by parseAppArgs); nullopt: plain.
  std::optional<CurveClientKeys> curve;
};

// Parses argv without the program name; errors name the option.
Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help);
std::string appUsage();

}  // namespace picksight::app
