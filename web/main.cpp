// picksight-web: parses options, starts the web HMI's server, prints its URL,
// runs until SIGINT/SIGTERM.
#include <iostream>

#include "picksight/common/large_buffers.hpp"
#include "picksight/common/log.hpp"
#include "picksight/common/service_notify.hpp"
#include "picksight/common/stop_signals.hpp"
#include "picksight/web/user_store.hpp"
#include "picksight/web/web_server.hpp"

int main(int argc, char** argv) {
  using namespace picksight;
  setLogPrefix("web");
  bool help = false;
  auto options = web::parseWebArgs(std::vector<std::string>(argv + 1, argv + argc), &help);
  if (help) {
    std::cout << web::webUsage();
    return 0;
  }
  if (!options) {
    std::cerr << "picksight-web: " << options.error().message << "\n\n" << web::webUsage();
    return 2;
  }
  if (!options->first_admin_file.empty()) {
    auto made = web::UserStore::makeFirstAdmin(options->users_file, options->first_admin_file);
    if (!made) {
      std::cerr << "picksight-web: " << made.error().message << "\n";
      return 1;
    }
    if (*made)
      std::cout << "made 'admin' in " << options->users_file << "; its password is in "
                << options->first_admin_file << " (mode 0600)" << std::endl;
    else
      std::cout << options->users_file << " has users already: nothing changed" << std::endl;
    return 0;
  }
  retainLargeBuffers();
  const StopSignals stop_signals;
  ServiceNotifier notifier;
  try {
    web::WebServer server(*options);
    if (auto started = server.start(); !started) {
      std::cerr << "picksight-web: " << started.error().message << "\n";
      return 1;
    }
    // Machine-readable: tests and the demo listen on port 0 and read this.
    if (!server.redirectUrl().empty()) std::cout << "redirect " << server.redirectUrl() << "\n";
    std::cout << "web " << server.url() << "\nready" << std::endl;
    logInfo("serving ", server.url(), " for ", options->video_servers.size(), " video servers and ",
            options->vision_apps.size(),
            " vision apps; allowed peers: ", options->allow.describe());
    notifier.ready("serving " + server.url());
    logInfo("stopping on signal ", stop_signals.wait());
    notifier.stopping();
    server.stop();
  } catch (const std::exception& e) {
    std::cerr << "picksight-web: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
