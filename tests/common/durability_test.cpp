// Durability at the system-call level: the test binary defines fsync() and
// rename() itself (the executable's symbols come before libc's), records
// each call and passes it on to libc, so a write that skips a sync is seen
// even though a killed process would not show it (only a power cut does).
#include <dlfcn.h>
#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "picksight/common/atomic_file.hpp"
#include "picksight/store/model_library.hpp"
#include "temp_dir.hpp"

namespace {

// One recorded call: "fsync <path>" or "rename <to>".
std::mutex g_mutex;
std::vector<std::string> g_calls;

std::string pathOfFd(int fd) {
  char link[64];
  char target[PATH_MAX];
  std::snprintf(link, sizeof(link), "/proc/self/fd/%d", fd);
  const ssize_t n = ::readlink(link, target, sizeof(target) - 1);
  return n > 0 ? std::string(target, static_cast<size_t>(n)) : std::string();
}

void record(std::string call) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_calls.push_back(std::move(call));
}

std::vector<std::string> takeCalls() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return std::exchange(g_calls, {});
}

template <typename F>
F next(const char* name) {
  return reinterpret_cast<F>(::dlsym(RTLD_NEXT, name));
}

}  // namespace

extern "C" int fsync(int fd) {
  static const auto real = next<int (*)(int)>("fsync");
  record("fsync " + pathOfFd(fd));
  return real(fd);
}

extern "C" int rename(const char* from, const char* to) {
  static const auto real = next<int (*)(const char*, const char*)>("rename");
  record(std::string("rename ") + to);
  return real(from, to);
}

using picksight::test::TempDir;

namespace {
std::string realPath(const std::filesystem::path& p) {
  return std::filesystem::weakly_canonical(p).string();
}

}  // namespace

TEST_CASE("an atomic write syncs the new file then renames it then syncs the directory",
          "[common]") {
  TempDir dir;
  const auto target = dir.path() / "calibration.yaml";
  takeCalls();
  REQUIRE(picksight::writeFileAtomically(target.string(), "new content\n"));
  const auto calls = takeCalls();
  INFO([&] {
    std::string all;
    for (const auto& c : calls) all += c + "\n";
    return all;
  }());
  // The temporary (target.tmp.<pid>) is synced before the rename puts it in
  // place, and the directory after it.
  REQUIRE(calls.size() == 3);
  CHECK(calls[0].rfind("fsync " + realPath(target) + ".tmp.", 0) == 0);
  CHECK(calls[1] == "rename " + target.string());
  CHECK(calls[2] == "fsync " + realPath(dir.path()));
}

TEST_CASE("forgetting a model syncs its directory after the file is removed", "[common]") {
  TempDir dir;
  const std::string models = (dir.path() / "models").string();
  picksight::store::ModelLibrary library(models);
  picksight::vision::PartModel model;
  model.type = 3;
  model.name = "plate";
  // A model the library accepts: the smallest valid one.
  model.body.area = 100;
  model.body.area_tolerance = 0.1;
  model.body.hu_tolerance = 0.5;
  model.conformity = 1;
  model.edge_tolerance = 1;
  model.verify_percent = 80;
  picksight::vision::BoundaryLoop loop;
  picksight::vision::Primitive line;
  line.start = {0, 0};
  line.end = {10, 0};
  line.weight = 1;
  loop.primitives.push_back(line);
  model.loops.push_back(loop);
  takeCalls();
  const auto stored = library.store(model);
  INFO((stored ? std::string() : stored.error().message));
  REQUIRE(stored);
  // A new models/ directory is made durable in its parent.
  const auto created = takeCalls();
  CHECK(std::find(created.begin(), created.end(), "fsync " + realPath(dir.path())) !=
        created.end());

  REQUIRE(library.remove(3));
  const auto calls = takeCalls();
  CHECK(std::find(calls.begin(), calls.end(), "fsync " + realPath(models)) != calls.end());
}
