// picksight-video-server: parses options, starts the server, prints the bound
// endpoints, runs until SIGINT/SIGTERM.
#include <csignal>
#include <iostream>

#include "picksight/common/large_buffers.hpp"
#include "picksight/common/log.hpp"
#include "picksight/common/service_notify.hpp"
#include "picksight/common/stop_signals.hpp"
#include "picksight/video_server/video_server.hpp"

int main(int argc, char** argv) {
  using namespace picksight;
  setLogPrefix("video-server");
  bool help = false;
  auto config = video::parseServerArgs(std::vector<std::string>(argv + 1, argv + argc), &help);
  if (help) {
    std::cout << video::serverUsage();
    return 0;
  }
  if (!config) {
    std::cerr << "picksight-video-server: " << config.error().message << "\n\n"
              << video::serverUsage();
    return 2;
  }
  retainLargeBuffers();
  const StopSignals stop_signals;
  ServiceNotifier notifier;
  try {
    video::VideoServer server(*config);
    server.start();
    // Machine-readable lines: tests and scripts bind port 0 and read these.
    std::cout << "frames " << server.framesEndpoint() << "\n"
              << "control " << server.controlEndpoint() << "\n"
              << "ready" << std::endl;
    for (const auto& c : config->cameras) logInfo("camera ", c.name, " = ", c.uri);
    // Both sockets are bound: clients started after us can connect.
    notifier.ready(std::to_string(config->cameras.size()) + " cameras, frames " +
                   server.framesEndpoint() + ", control " + server.controlEndpoint());
    logInfo("stopping on signal ", stop_signals.wait());
    notifier.stopping();
    server.stop();
  } catch (const std::exception& e) {
    std::cerr << "picksight-video-server: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
