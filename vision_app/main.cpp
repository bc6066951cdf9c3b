// picksight-vision: subscribes to one camera, serves robot controllers; or,
// with a subcommand (learn, locate, blobs, lens), works on image files.
#include <sys/stat.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <iostream>
#include <memory>

#include "picksight/app/app_options.hpp"
#include "picksight/app/offline_commands.hpp"
#include "picksight/app/plc_port.hpp"
#include "picksight/app/vision_cell.hpp"
#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/common/log.hpp"
#include "picksight/common/service_notify.hpp"
#include "picksight/common/stop_signals.hpp"
#include "picksight/link/video_server_camera.hpp"
#include "picksight/protocol/robot_server.hpp"

// The cell's wiring in the order it starts and stops (options, cell,
// results stream, robot, set-up and PLC ports), with the start-up lines an
// operator reads in the journal: long for those lines, not for decisions.
int main(int argc, char** argv) {
  using namespace picksight;
  setLogPrefix("vision");
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (app::isOfflineCommand(args)) {
    // Image after image in one process (test-run over a folder): each
    // frame's buffers kept for the next, as the service keeps them. Without,
    // `test-run` over 45 frames of 1920x1080 took 2.1 s instead of 1.25.
    retainLargeBuffers();
    try {
      return app::runOfflineCommand(args, std::cout, std::cerr);
    } catch (const std::exception& e) {
      // An installation fault (the codecs module missing), not a bad image.
      std::cerr << "picksight-vision: " << e.what() << "\n";
      return 1;
    }
  }
  bool help = false;
  auto options = app::parseAppArgs(args, &help);
  if (help) {
    std::cout << app::appUsage() << "\n" << app::offlineUsage();
    return 0;
  }
  if (!options) {
    std::cerr << "picksight-vision: " << options.error().message << "\n\n" << app::appUsage();
    return 2;
  }
  if (::mkdir(options->data_dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::cerr << "picksight-vision: --data-dir " << options->data_dir << ": "
              << std::strerror(errno) << "\n";
    return 2;
  }
  retainLargeBuffers();
  const StopSignals stop_signals;
  ServiceNotifier notifier;
  try {
    zmq::context_t context;
    app::VisionCell cell(options->data_dir,
                         std::make_unique<picksight::link::VideoServerCamera>(
                             context, options->frames_endpoint, options->control_endpoint,
                             options->camera, options->vision.frame_timeout, options->curve),
                         options->vision, options->vision_settings_given);
    // A bad file costs what it holds, never the start.
    for (const auto& problem : cell.load()) logError(problem);
    if (!options->vision_settings_given.empty()) {
      std::string keys;
      for (const auto& k : options->vision_settings_given) keys += (keys.empty() ? "" : ", ") + k;
      logInfo("vision settings from the command line, over ", options->data_dir,
              "/vision.json: ", keys, " (a VISION change replaces them until the next start)");
    }
    logInfo("vision settings: ", cell::visionSettingsText(cell.vision().options()));
    logInfo(cell.models().snapshot()->size(), " part models from ", cell.models().directory());
    // The filmstrip: recent requests' frames. A directory that cannot be
    // made costs the filmstrip (FILMSTRIP answers ERROR 57), never the start.
    if (!options->filmstrip.dir.empty()) {
      auto problems = cell.openFilmstrip(options->filmstrip);
      if (!problems) {
        logError("filmstrip off: ", problems.error().message);
      } else {
        for (const auto& p : *problems) logError("filmstrip: ", p);
        logInfo("filmstrip in ", options->filmstrip.dir, ": ", cell.filmstrip()->figures().entries,
                " entries");
      }
    }
    // The results stream: subscribers see what each request saw, after
    // its reply; they never slow a robot.
    std::unique_ptr<results::ResultsPublisher> results;
    if (options->results_bind != "none") {
      results::ResultsOptions results_options;
      results_options.bind = options->results_bind;
      results_options.app = options->name.empty() ? options->camera : options->name;
      results = std::make_unique<results::ResultsPublisher>(results_options);
      cell.publishResultsTo(results.get());
    }
    const bool read_only = options->robot_read_only;
    protocol::RobotServer robots(
        options->robot, [&cell, read_only](std::string_view line, protocol::Session& session) {
          return cell.handle(line, read_only, &session);
        });
    std::unique_ptr<protocol::RobotServer> setup;
    if (options->setup) {
      setup = std::make_unique<protocol::RobotServer>(
          *options->setup, [&cell](std::string_view line, protocol::Session& session) {
            return cell.handle(line, false, &session);
          });
    }
    // The PLC port has threads of its own: a PLC never delays a robot.
    std::unique_ptr<app::PlcPort> plc;
    if (options->plc.enabled) plc = std::make_unique<app::PlcPort>(options->plc, cell);
    cell.start();
    robots.start();
    if (setup) setup->start();
    if (plc) plc->start();
    std::cout << "robot " << robots.port() << "\n";
    if (setup) std::cout << "setup " << setup->port() << "\n";
    if (plc) std::cout << "modbus " << plc->port() << "\n";
    if (results) std::cout << "results " << results->endpoint() << "\n";
    std::cout << "ready" << std::endl;
    logInfo("camera ", options->camera, " from ", options->frames_endpoint, ", robots on ",
            options->robot.listen.bind_address, ":", robots.port(), read_only ? " (read-only)" : "",
            ", allowed: ", options->robot.listen.allow.describe());
    if (setup) {
      logInfo("set-up port on ", options->setup->listen.bind_address, ":", setup->port());
    }
    if (results) {
      logInfo("results ", results->endpoint(), " (topic ",
              options->name.empty() ? options->camera : options->name, ")");
    }
    if (plc) {
      logInfo("PLCs on Modbus port ", plc->port(), " (unit ",
              static_cast<int>(options->plc.device.unit_id), ", word order ",
              plc::wordOrderName(options->plc.device.word_order), ", allowed ",
              options->plc.server.listen.allow.describe(), ")");
    }
    // The robot port is listening: a robot program started after us connects.
    notifier.ready("camera " + options->camera + ", robot port " + std::to_string(robots.port()));
    if (options->curve) logInfo("CURVE to the video server as ", options->curve->own.public_key);
    logInfo("stopping on signal ", stop_signals.wait());
    notifier.stopping();
    if (plc) plc->stop();
    if (setup) setup->stop();
    robots.stop();
    cell.stop();
    cell.publishResultsTo(nullptr);
  } catch (const std::exception& e) {
    std::cerr << "picksight-vision: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
