// Robot protocol parsing, the replies that need no camera, and the log of
// the changes asked over a port.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "picksight/app/vision_cell.hpp"
#include "temp_dir.hpp"

using namespace picksight::app;
using namespace picksight::protocol;
using namespace picksight::cell;

namespace {
// The whole command table with no camera: enough for every command that
// fails before asking for a frame. Each test has its own data directory, so
// concurrent runs never share models or calibrations.
struct Fixture {
  picksight::test::TempDir dir;
  VisionCell protocol{dir.path().string(), std::make_unique<picksight::link::NoCamera>(),
                      VisionOptions{}};
};
}  // namespace

TEST_CASE("requests split on spaces, tabs and commas, commands case-insensitive",
          "[vision_app][protocol]") {
  auto r = parseRequest("  locate,1 ");
  REQUIRE(r);
  CHECK(r->command == "LOCATE");
  REQUIRE(r->args.size() == 1);
  CHECK(r->args[0] == "1");
  r = parseRequest("Store\t12.5, -3.25");
  REQUIRE(r);
  CHECK(r->command == "STORE");
  CHECK(r->args == std::vector<std::string>{"12.5", "-3.25"});
  CHECK_FALSE(parseRequest(""));
  CHECK_FALSE(parseRequest(" \t ,"));
}

TEST_CASE("simple commands and errors keep the reply on one line", "[vision_app][protocol]") {
  Fixture f;
  CHECK(f.protocol.handle("PING") == "OK");
  CHECK(f.protocol.handle("ping") == "OK");
  CHECK(f.protocol.handle("PING 1").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("").rfind("ERROR 14 ", 0) == 0);
  CHECK(f.protocol.handle("VERSION").rfind("OK ", 0) == 0);
  CHECK(f.protocol.handle("HELP").rfind("OK ", 0) == 0);
  const std::string unknown = f.protocol.handle(std::string("FLY\x01\xff\x00 x", 8));
  CHECK(unknown.rfind("ERROR 10 ", 0) == 0);
  for (char c : unknown) CHECK((c >= 0x20 && c < 0x7f));
}

TEST_CASE("LOCATE rejects bad arguments before touching the camera", "[vision_app][protocol]") {
  Fixture f;
  CHECK(f.protocol.handle("LOCATE").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("LOCATE 1 2").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("LOCATE one").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("LOCATE -1").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("LOCATE 1.5").rfind("ERROR 11 ", 0) == 0);
  CHECK(f.protocol.handle("FRAME").rfind("ERROR 20 ", 0) == 0);
  // Good arguments reach the camera, which is missing: ERROR 20, not a crash.
  CHECK(f.protocol.handle("LOCATE 1").rfind("ERROR 20 ", 0) == 0);
}

TEST_CASE("cell commands check their arguments before the camera or a file",
          "[vision_app][protocol]") {
  Fixture f;
  for (const char* bad : {"CALCAM",
                          "CALCAM 0",
                          "CALCAM -3",
                          "CALCAM x",
                          "CALCAM 1 2",
                          "CALCAM nan",
                          "STORE 1",
                          "STORE 1 2 3",
                          "STORE a b",
                          "STORE nan 2",
                          "STORE 1 inf",
                          "DELETE",
                          "DELETE x",
                          "DELETE -1",
                          "LIST 1",
                          "COMPUTE X",
                          "COMPUTE SIMILARITY LSQ",
                          "RESIDUALS 1",
                          "GRASP",
                          "GRASP 1",
                          "GRASP x ADD 1 2 3",
                          "GRASP 1 ADD 1 2",
                          "GRASP 1 ADD 1 2 inf",
                          "GRASP 1 FLY",
                          "GRASP 1 CLEAR 2",
                          "GRIPPER 1 FINGER 1 2 3",
                          "STATUS 1",
                          "EXPOSURE -1",
                          "EXPOSURE x",
                          "EXPOSURE 1 2",
                          "ROI 1 2 3",
                          "ROI 0 0 0 10",
                          "ROI a b c d",
                          "ROI HALF"}) {
    INFO(bad);
    CHECK(f.protocol.handle(bad).rfind("ERROR 11 ", 0) == 0);
  }
  CHECK(f.protocol.handle("CALCAM 10").rfind("ERROR 20 ", 0) == 0);
  CHECK(f.protocol.handle("STORE 1 2").rfind("ERROR 20 ", 0) == 0);
  CHECK(f.protocol.handle("DELETE 7").rfind("ERROR 40 ", 0) == 0);
  CHECK(f.protocol.handle("DELETE 7").find("7") != std::string::npos);
  CHECK(f.protocol.handle("LIST") == "OK 0");
  CHECK(f.protocol.handle("COMPUTE").rfind("ERROR 41 ", 0) == 0);
  CHECK(f.protocol.handle("COMPUTE similarity").rfind("ERROR 41 ", 0) == 0);
  CHECK(f.protocol.handle("COMPUTE HOMOGRAPHY").rfind("ERROR 41 ", 0) == 0);
  CHECK(f.protocol.handle("RESIDUALS").rfind("ERROR 44 ", 0) == 0);
  CHECK(f.protocol.handle("GRASP 1 ADD 1 2 3").rfind("ERROR 32 ", 0) == 0);
  CHECK(f.protocol.handle("GRIPPER 1 LIST").rfind("ERROR 32 ", 0) == 0);
  CHECK(f.protocol.handle("EXPOSURE 1000").rfind("ERROR 21 ", 0) == 0);
  CHECK(f.protocol.handle("ROI FULL").rfind("ERROR 21 ", 0) == 0);
  CHECK(f.protocol.handle("ROI").rfind("ERROR 21 ", 0) == 0);
  const std::string status = f.protocol.handle("STATUS");
  CHECK(status.rfind("OK frame=vision-px scale=none ", 0) == 0);
  CHECK(status.find(" skipped=0 ") != std::string::npos);
  CHECK(std::filesystem::is_empty(f.dir.path()));  // nothing was written
}

TEST_CASE("a read-only port answers reads and refuses every change with ERROR 17",
          "[vision_app][protocol]") {
  Fixture f;
  const auto readOnly = [&](const std::string& line) { return f.protocol.handle(line, true); };
  // Reads behave as on a full port (here: no camera, no calibration).
  for (const char* read : {"PING", "VERSION", "HELP", "STATUS", "MODELS", "LIST", "FRAME",
                           "LOCATE 1", "BLOBS", "RESIDUALS", "EXPOSURE", "ROI", "GRASP 1 LIST",
                           "gripper 1 list", "TOLERANCE 1", "VISION", "vision"}) {
    INFO(read);
    CHECK(readOnly(read) == f.protocol.handle(read));
    CHECK(readOnly(read).rfind("ERROR 17 ", 0) != 0);
  }
  // Changes to a model, a calibration or a camera are refused, before any
  // argument is looked at.
  for (const char* change :
       {"LEARN 1", "FORGET 1", "CALCAM 5", "STORE 1 2", "DELETE 1", "COMPUTE", "EXPOSURE 500",
        "ROI 0 0 8 8", "ROI FULL", "GRASP 1 ADD 0 0 0", "GRASP 1 CLEAR", "GRIPPER 1 CLEAR", "GRASP",
        "learn", "TOLERANCE 1 verify_percent 90", "VISION polarity light", "VISION RESET",
        "vision bad"}) {
    INFO(change);
    const std::string reply = readOnly(change);
    CHECK(reply.rfind("ERROR 17 ", 0) == 0);
    CHECK_THAT(reply, Catch::Contains("read-only"));
  }
  // Unknown and empty requests keep their own errors.
  CHECK(readOnly("FLY").rfind("ERROR 10 ", 0) == 0);
  CHECK(readOnly("").rfind("ERROR 14 ", 0) == 0);
  CHECK(f.protocol.models().snapshot()->empty());
}

TEST_CASE("every change made at a port's request is logged with who asked and the reply",
          "[vision_app][protocol][audit]") {
  CommandTable table;
  table.add("SET", "SET <n>", [](const Request&) { return std::string("OK"); });
  table.add("BAD", "BAD", [](const Request&) { return std::string("ERROR 11 usage: BAD"); });
  table.add(
      "GET", "GET", [](const Request&) { return std::string("OK 1"); }, neverChanges);
  Session session;
  session.client = "robot 10.0.0.5:4000";
  // The log goes to stderr: caught in a file for the length of the requests.
  picksight::test::TempDir dir;
  const std::string path = (dir.path() / "log").string();
  std::fflush(stderr);
  const int saved = ::dup(2);
  const int file = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  REQUIRE(saved >= 0);
  REQUIRE(file >= 0);
  ::dup2(file, 2);
  table.dispatch("SET 1", false, &session);
  table.dispatch("GET", false, &session);
  table.dispatch("SET 2", true, &session);  // refused on a read-only port: nothing changed
  table.dispatch("SET 3");                  // from inside the app
  table.dispatch("BAD", false, &session);   // refused by the command: nothing changed
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  ::close(file);
  std::ifstream in(path);
  const std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(log);
  CHECK(log.find("audit: robot 10.0.0.5:4000 'SET 1' -> OK") != std::string::npos);
  CHECK(log.find("audit: local 'SET 3' -> OK") != std::string::npos);
  CHECK(log.find("GET") == std::string::npos);
  CHECK(log.find("SET 2") == std::string::npos);
  CHECK(log.find("BAD") == std::string::npos);
}
