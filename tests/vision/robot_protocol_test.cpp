// Robot protocol parsing and the replies that need no camera.
#include <catch2/catch.hpp>

#include "picksight/vision_app/robot_protocol.hpp"

using namespace picksight::app;

namespace {
// A vision service pointing at a video server that does not exist: enough for
// every command that fails before asking for a frame.
struct Fixture {
  zmq::context_t context;
  VisionService vision{context, "tcp://127.0.0.1:1", "tcp://127.0.0.1:1", "cam0", VisionOptions{}};
  RobotProtocol protocol{vision};
};
}  // namespace

TEST_CASE("requests split on spaces, tabs and commas, commands case-insensitive", "[vision_app][protocol]") {
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
}
