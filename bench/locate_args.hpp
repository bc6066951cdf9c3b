// Options and paths shared by the LOCATE benchmarks (locate_bench, cell_bench).
#pragma once

#include <unistd.h>

#include <string>

#include "picksight/common/text.hpp"

namespace picksight::bench {

struct LocateArgs {
  int requests = 300;
  int width = 1920;
  int height = 1080;
  int parts = 20;
};

// --requests N --width N --height N --parts N, over the given defaults;
// parsing stops at the first value that is not a positive integer.
inline LocateArgs parseLocateArgs(int argc, char** argv, LocateArgs a) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string name = argv[i];
    const auto v = parseInt(argv[i + 1]);
    if (!v || *v <= 0) break;
    if (name == "--requests") a.requests = static_cast<int>(*v);
    if (name == "--width") a.width = static_cast<int>(*v);
    if (name == "--height") a.height = static_cast<int>(*v);
    if (name == "--parts") a.parts = static_cast<int>(*v);
  }
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
