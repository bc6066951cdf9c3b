// Pins atomic file replacement: create, replace, no temporary left behind,
// clean errors for impossible writes and missing files.
#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

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
