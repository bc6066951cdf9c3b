// A cell for the benchmarks: the real picksight-video-server (one synthetic
// camera "cam0", trigger mode) and picksight-vision on free ports, and a
// robot connected to it, the way a robot controller would be.
#pragma once

#include <stdlib.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "locate_args.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"

namespace picksight::bench {

// The synthetic camera of `args`, plus `extra` options ("size=120,types=...").
inline std::string syntheticCamera(const LocateArgs& args, const std::string& extra = "") {
  return "cam0=synthetic:width=" + std::to_string(args.width) +
         ",height=" + std::to_string(args.height) + ",parts=" + std::to_string(args.parts) +
         ",seed=5" + (extra.empty() ? "" : "," + extra);
}

// A new empty data directory for a vision app; empty on failure.
inline std::string makeDataDir() {
  char dir[] = "/tmp/picksight-bench-XXXXXX";
  return ::mkdtemp(dir) ? std::string(dir) : std::string();
}

struct VideoServerRun {
  std::unique_ptr<tool_support::Subprocess> process;
  std::string frames;
  std::string control;
};

// Starts the video server with `camera`; nullopt when it did not come up.
inline std::optional<VideoServerRun> startVideoServer(const std::string& camera) {
  using namespace std::chrono_literals;
  VideoServerRun run;
  run.process = std::make_unique<tool_support::Subprocess>(std::vector<std::string>{
      binDir() + "/picksight-video-server", "--source", camera, "--frames", "tcp://127.0.0.1:*",
      "--control", "tcp://127.0.0.1:*", "--mode", "trigger"});
  const auto frames = run.process->waitForLine("frames ", 10s);
  const auto control = run.process->waitForLine("control ", 10s);
  if (!frames || !control) return std::nullopt;
  run.frames = *frames;
  run.control = *control;
  return run;
}

struct VisionRun {
  std::unique_ptr<tool_support::Subprocess> process;
  tool_support::LineClient robot;
};

// Starts a vision app on `server`'s camera with `data_dir` (and `extra`
// options) and connects a robot to it; nullopt when either failed.
inline std::optional<VisionRun> startVision(const VideoServerRun& server,
                                            const std::string& data_dir,
                                            const std::vector<std::string>& extra = {}) {
  using namespace std::chrono_literals;
  VisionRun run;
  std::vector<std::string> command{binDir() + "/picksight-vision",
                                   "--frames",
                                   server.frames,
                                   "--control",
                                   server.control,
                                   "--data-dir",
                                   data_dir};
  for (const char* option : {"--robot-port", "0", "--bind", "127.0.0.1"}) command.push_back(option);
  command.insert(command.end(), extra.begin(), extra.end());
  run.process = std::make_unique<tool_support::Subprocess>(command);
  const auto port = run.process->waitForLine("robot ", 10s);
  if (!port || !run.process->waitForLine("ready", 10s)) return std::nullopt;
  auto robot =
      tool_support::LineClient::connect("127.0.0.1", static_cast<uint16_t>(std::stoi(*port)), 5s);
  if (!robot) return std::nullopt;
  run.robot = std::move(*robot);
  return run;
}

}  // namespace picksight::bench
