// picksight-vision: subscribes to one camera, serves robot controllers.
#include <sys/stat.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <iostream>

#include "picksight/common/log.hpp"
#include "picksight/vision_app/app_options.hpp"
#include "picksight/vision_app/robot_protocol.hpp"
#include "picksight/vision_app/robot_server.hpp"
#include "picksight/vision_app/vision_service.hpp"

int main(int argc, char** argv) {
  using namespace picksight;
  setLogPrefix("vision");
  bool help = false;
  auto options = app::parseAppArgs(std::vector<std::string>(argv + 1, argv + argc), &help);
  if (help) {
    std::cout << app::appUsage();
    return 0;
  }
  if (!options) {
    std::cerr << "picksight-vision: " << options.error().message << "\n\n" << app::appUsage();
    return 2;
  }
  if (::mkdir(options->data_dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::cerr << "picksight-vision: --data-dir " << options->data_dir << ": " << std::strerror(errno) << "\n";
    return 2;
  }
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  try {
    zmq::context_t context;
    app::VisionService vision(context, options->frames_endpoint, options->control_endpoint,
                              options->camera, options->vision);
    app::RobotProtocol protocol(vision);
    app::RobotServer robots(options->robot,
                            [&protocol](std::string_view line) { return protocol.handle(line); });
    vision.start();
    robots.start();
    std::cout << "robot " << robots.port() << "\n" << "ready" << std::endl;
    logInfo("camera ", options->camera, " from ", options->frames_endpoint, ", robots on port ", robots.port());
    int sig = 0;
    sigwait(&signals, &sig);
    logInfo("stopping on signal ", sig);
    robots.stop();
    vision.stop();
  } catch (const std::exception& e) {
    std::cerr << "picksight-vision: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
