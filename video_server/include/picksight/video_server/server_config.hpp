// Video server configuration from the command line and/or a YAML file.
#pragma once

#include <string>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/video_server/camera.hpp"

namespace picksight::video {

struct ServerConfig {
  std::string frames_endpoint = "tcp://*:5555";
  std::string control_endpoint = "tcp://*:5556";
  // CURVE (docs/SECURITY.md): with a secret key file both sockets encrypt;
  // with an allow-list (a *.key directory or a file of public-key lines)
  // only the listed clients get in. Empty: plain sockets.
  std::string curve_secret_key;
  std::string curve_allow_list;
  std::vector<CameraConfig> cameras;
};

// Reads a YAML configuration; errors name the file and the key.
Result<ServerConfig> loadServerConfig(const std::string& path);

// Parses command-line arguments (argv without the program name). --config
// loads a file first; flags given beside it override it. `help` is set when
// --help was asked for.
Result<ServerConfig> parseServerArgs(const std::vector<std::string>& args, bool* help);

std::string serverUsage();

}  // namespace picksight::video
