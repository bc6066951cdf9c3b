// Options and paths shared by the LOCATE benchmarks (locate_bench, cell_bench).
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <string>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/text.hpp"

namespace picksight::bench {

struct LocateArgs {
  int requests = 300;
  int width = 1920;
  int height = 1080;
  int parts = 20;
};

// --requests N --width N --height N --parts N (positive integers), over the
// given defaults, and whatever `more` adds to the command line. --help, or a
// bad option, prints the help and exits: the callers are benchmark mains
// with nothing to clean up yet.
inline LocateArgs parseLocateArgs(int argc, char** argv, LocateArgs a,
                                  const std::function<void(cli::App&)>& more = {}) {
  cli::App app("LOCATE benchmark against the real processes.", argc > 0 ? argv[0] : "bench");
  if (more) more(app);
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--requests", a.requests, "LOCATE requests to time")
      ->check(cli::positiveNumber())
      ->showDefault();
  app.addOption("--width", a.width, "image width")->check(cli::positiveNumber())->showDefault();
  app.addOption("--height", a.height, "image height")->check(cli::positiveNumber())->showDefault();
  app.addOption("--parts", a.parts, "parts in the scene")
      ->check(cli::positiveNumber())
      ->showDefault();
  if (auto exit_code = cli::parseMainArgs(app, argc, argv)) std::exit(*exit_code);
  return a;
}

// The directory of the running benchmark, where the PickSight binaries are.
inline std::string binDir() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  std::string p(path, n > 0 ? static_cast<size_t>(n) : 0);
  return p.substr(0, p.find_last_of('/'));
}

}  // namespace picksight::bench
