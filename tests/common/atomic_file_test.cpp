// Pins atomic file replacement: create, replace, no temporary left behind,
// clean errors for impossible writes and missing files, and atomicity for
// real: a writer killed at every step leaves the old file or the new one.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>

#include "temp_dir.hpp"

#include "picksight/common/atomic_file.hpp"

namespace fs = std::filesystem;

namespace {

using picksight::test::TempDir;

std::set<std::string> namesIn(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

}  // namespace

TEST_CASE("writeFileAtomically creates a file with the exact bytes", "[common]") {
  TempDir dir;
  const std::string path = (dir.path() / "points.txt").string();
  const std::string content("line 1\nbinary \0 byte\r\nlast", 26);
  REQUIRE(picksight::writeFileAtomically(path, content));
  auto read = picksight::readFile(path);
  REQUIRE(read);
  CHECK(*read == content);
}

TEST_CASE("writeFileAtomically replaces an existing file", "[common]") {
  TempDir dir;
  const std::string path = (dir.path() / "model.yaml").string();
  REQUIRE(picksight::writeFileAtomically(path, "old content that is rather long\n"));
  REQUIRE(picksight::writeFileAtomically(path, "new\n"));
  auto read = picksight::readFile(path);
  REQUIRE(read);
  CHECK(*read == "new\n");
  REQUIRE(picksight::writeFileAtomically(path, ""));
  read = picksight::readFile(path);
  REQUIRE(read);
  CHECK(read->empty());
}

TEST_CASE("writeFileAtomically leaves no temporary file behind", "[common]") {
  TempDir dir;
  const std::string path = (dir.path() / "calib.yaml").string();
  for (int i = 0; i < 3; ++i) {
    REQUIRE(picksight::writeFileAtomically(path, "version " + std::to_string(i) + "\n"));
  }
  CHECK(namesIn(dir.path()) == std::set<std::string>{"calib.yaml"});
}

TEST_CASE("writeFileAtomically into a missing directory is an error, not a crash", "[common]") {
  TempDir dir;
  const fs::path missing = dir.path() / "no_such_dir";
  const std::string path = (missing / "file.txt").string();
  auto written = picksight::writeFileAtomically(path, "content");
  REQUIRE_FALSE(written);
  CHECK(written.error().code);
  CHECK_THAT(written.error().message, Catch::Contains("no_such_dir"));
  CHECK_FALSE(fs::exists(missing));
  CHECK(namesIn(dir.path()).empty());
}

TEST_CASE("writeFileAtomically over a directory fails and removes its temporary", "[common]") {
  TempDir dir;
  const fs::path target = dir.path() / "occupied";
  fs::create_directory(target);
  auto written = picksight::writeFileAtomically(target.string(), "content");
  REQUIRE_FALSE(written);
  CHECK_FALSE(written.error().message.empty());
  CHECK(fs::is_directory(target));
  CHECK(namesIn(dir.path()) == std::set<std::string>{"occupied"});
}

TEST_CASE("readFile of a missing file is an error naming the file", "[common]") {
  TempDir dir;
  const std::string path = (dir.path() / "absent.txt").string();
  auto read = picksight::readFile(path);
  REQUIRE_FALSE(read);
  CHECK(read.error().code == std::errc::no_such_file_or_directory);
  CHECK_THAT(read.error().message, Catch::Contains("absent.txt"));
}

TEST_CASE("readFile of a directory is an error", "[common]") {
  TempDir dir;
  auto read = picksight::readFile(dir.path().string());
  CHECK_FALSE(read);
}

TEST_CASE("writeFileAtomically syncs the new file before the rename and the directory after",
          "[common]") {
  // A rename of unsynced data can reach the disk before the data (a crash
  // leaves an empty file); an unsynced rename can be lost altogether.
  TempDir dir;
  std::vector<std::string> steps;
  REQUIRE(picksight::writeFileAtomically(dir.file("order.yaml"), "content\n",
                                         [&](std::string_view step) { steps.emplace_back(step); }));
  CHECK(steps ==
        std::vector<std::string>{"create", "write", "sync", "close", "rename", "sync-dir"});
}

TEST_CASE("a writer killed at any step leaves the old file or the new one and never a torn one",
          "[common]") {
  const std::string old_content(100000, 'o');
  const std::string new_content = "new\n" + std::string(50000, 'n');
  bool renamed = false;
  for (int kill_at = 0;; ++kill_at) {
    INFO("killed before step " << kill_at);
    TempDir dir;
    const std::string path = dir.file("model.yaml");
    REQUIRE(picksight::writeFileAtomically(path, old_content));
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // The child dies by SIGKILL at step `kill_at`: nothing of it runs on.
      // Its exit code tells which step it reached; 100: it finished.
      int step = 0;
      const auto written =
          picksight::writeFileAtomically(path, new_content, [&](std::string_view s) {
            if (s == "sync-dir") ::_exit(50 + step);  // the rename is done
            if (step++ == kill_at) ::kill(::getpid(), SIGKILL);
          });
      ::_exit(written ? 100 : 101);
    }
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    const auto content = picksight::readFile(path);
    REQUIRE(content);
    const bool killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
    INFO("status " << status << ", " << content->size() << " bytes");
    if (killed) {
      // Killed before the rename: the old file, whole.
      CHECK(*content == old_content);
      continue;
    }
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) != 101);
    // Past the rename: the new file, whole.
    CHECK(*content == new_content);
    renamed = true;
    break;
  }
  CHECK(renamed);
}
