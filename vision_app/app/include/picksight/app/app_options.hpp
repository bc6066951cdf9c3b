// Command-line options of picksight-vision.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "picksight/app/plc_port.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/common/result.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/protocol/robot_server.hpp"
#include "picksight/transport/curve_keys.hpp"

namespace picksight::app {

struct AppOptions {
  std::string frames_endpoint = "tcp://127.0.0.1:5555";
  std::string control_endpoint = "tcp://127.0.0.1:5556";
  std::string camera = "cam0";
  // The vision app's name: the results stream's topic (empty: the camera's).
  std::string name;
  // The results stream's PUB endpoint ("none": no stream).
  std::string results_bind = "tcp://127.0.0.1:*";
  std::string data_dir = "picksight-data";
  protocol::RobotServerOptions robot;
  // The robot port refuses requests that change the cell (docs/SECURITY.md).
  bool robot_read_only = false;
  // A second, full-access port for set-up (--setup-port); same limits and
  // allow-list as the robot port, on loopback unless --setup-bind says.
  std::optional<protocol::RobotServerOptions> setup;
  cell::VisionOptions vision;
  // The vision settings keys (vision_settings.hpp) the command line or
  // --config set: they win over <data dir>/vision.json at start.
  std::vector<std::string> vision_settings_given;
  PlcPortOptions plc;  // off unless --modbus-port is given
  // The frames of recent requests (--filmstrip-*): in <data dir>/filmstrip
  // unless --filmstrip-dir says; dir empty: none.
  filmstrip::FilmstripOptions filmstrip;
  // CURVE keys for the camera link (loaded by parseAppArgs); nullopt: plain.
  std::optional<transport::CurveClientKeys> curve;
};

// Parses argv without the program name; errors name the option. With
// --config FILE the YAML map in FILE supplies options first (each key is an
// option without its dashes, a list repeats it, a flag is true or false) and
// the command line overrides them; errors there name the file and the key.
Result<AppOptions> parseAppArgs(const std::vector<std::string>& args, bool* help);
std::string appUsage();

}  // namespace picksight::app
