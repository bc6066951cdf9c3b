// picksight-cam usage errors, server errors, timeouts and JSON encoding:
// exit codes and messages that scripts rely on.
#include "cam_test_support.hpp"

using namespace picksight::camtest;
namespace proto = picksight::proto;

TEST_CASE("usage errors exit 2 with a message and contact no server", "[cam]") {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"roi", "cam0", "abc", "20", "300", "200"},
       "roi: X must be a non-negative integer, got 'abc'"},
      {{"roi", "cam0", "10", "-5", "300", "200"},
       "roi: Y must be a non-negative integer, got '-5'"},
      {{"roi", "cam0", "10", "20", "1.5", "200"},
       "roi: W must be a non-negative integer, got '1.5'"},
      {{"roi", "cam0", "10", "20", "300", "99999999999"}, "roi: H is too large, got '99999999999'"},
      {{"roi", "cam0", "10", "20", "300"},
       "roi: missing arguments; usage: picksight-cam roi CAM X Y W H"},
      {{"info"}, "info: missing arguments"},
      {{"info", "cam0", "cam1"}, "info: too many arguments (unexpected 'cam1')"},
      {{"info", ""}, "info: CAM must not be empty"},
      {{"list", "extra"}, "list: too many arguments (unexpected 'extra')"},
      {{"size", "cam0", "640"}, "size: missing arguments"},
      {{"size", "cam0", "640", "x480"}, "size: H must be a non-negative integer, got 'x480'"},
      {{"size", "cam0", "--scale", "0"}, "size: S must be a positive number, got '0'"},
      // A decimal comma is what a German locale would accept.
      {{"size", "cam0", "--scale", "1,5"}, "size: S must be a positive number, got '1,5'"},
      {{"mode", "cam0", "burst"},
       "mode: mode must be 'freerun', 'trigger' or 'hardware', got 'burst'"},
      {{"mode", "cam0", "freerun", "--line", "Line1"}, "mode: --line goes with the hardware mode"},
      {{"mode", "cam0", "hardware", "--activation", "sideways"},
       "mode: --activation must be rising, falling, any, high or low, got 'sideways'"},
      {{"mode", "cam0", "hardware", "--trigger-timeout", "0"},
       "mode: --trigger-timeout must be positive"},
      {{"mode", "cam0", "hardware", "--line", ""}, "mode: LINE must not be empty"},
      {{"mode", "cam0", "freerun", "fast"}, "mode: FPS must be a positive number, got 'fast'"},
      {{"mode", "cam0", "freerun", "15", "x"}, "mode: too many arguments (unexpected 'x')"},
      {{"format", "cam0", "rgb8"}, "format: format must be 'mono8' or 'bgr8', got 'rgb8'"},
      {{"trigger"}, "trigger: missing arguments; usage: picksight-cam trigger CAM"},
      {{"stats", "cam0", "cam1"}, "stats: too many arguments (unexpected 'cam1')"},
      {{"frobnicate", "cam0"}, "unknown command 'frobnicate'"},
      {{}, "missing command"},
      {{"--verbose", "list"}, "unknown option '--verbose'"},
      {{"--timeout", "soon", "list"}, "--timeout: MS must be a positive integer, got 'soon'"},
      {{"--timeout", "0", "list"}, "--timeout: MS must be a positive integer, got '0'"},
      {{"list", "--control"}, "--control: missing value"},
      {{"features"}, "features: missing arguments; usage: picksight-cam features CAM"},
      {{"features", "cam0", "Gain"}, "features: too many arguments (unexpected 'Gain')"},
      {{"get", "cam0"}, "get: missing arguments; usage: picksight-cam get CAM FEATURE"},
      {{"get", "cam0", ""}, "get: FEATURE must not be empty"},
      {{"set", "cam0", "GainRaw"},
       "set: missing arguments; usage: picksight-cam set CAM FEATURE VALUE"},
      {{"set", "", "GainRaw", "3"}, "set: CAM must not be empty"},
      {{"set", "cam0", "GainRaw", "3", "4"}, "set: too many arguments (unexpected '4')"},
      {{"open"}, "open: missing arguments; usage: picksight-cam open CAM"},
      {{"close", "cam0", "now"}, "close: too many arguments (unexpected 'now')"},
      {{"snap", "cam0"}, "snap: missing arguments; usage: picksight-cam snap CAM FILE"},
      {{"snap", "cam0", ""}, "snap: FILE must not be empty"},
      {{"snap", "cam0", "frame.xyz"}, "snap: no image writer for 'frame.xyz'"},
      {{"snap", "cam0", "frame"}, "snap: no image writer for 'frame'"},
  };
  zmq::context_t context;
  FakeServer server(context, okReply());
  for (const Case& c : cases) {
    std::string joined;
    for (const std::string& arg : c.args) joined += " '" + arg + "'";
    INFO("args:" << joined);
    const Run run = runAt(context, server, c.args);
    CHECK(run.code == 2);
    CHECK(run.out.empty());
    CHECK_THAT(run.err, Catch::StartsWith("picksight-cam: " + c.message));
  }
  // runCamCli waits for a reply to whatever it sends, so anything sent has
  // been received by the time the loop ends.
  CHECK(server.stop().empty());
  CHECK(server.failure().empty());
}

TEST_CASE("a malformed endpoint is a usage error", "[cam]") {
  zmq::context_t context;
  const Run run = runCli(context, {"--control", "not-an-endpoint", "list"});
  CHECK(run.code == 2);
  CHECK_THAT(run.err, Catch::Contains("invalid endpoint 'not-an-endpoint'"));
}

TEST_CASE("--help prints the usage on stdout", "[cam]") {
  zmq::context_t context;
  const Run run = runCli(context, {"list", "--help"});
  CHECK(run.code == 0);
  CHECK(run.err.empty());
  CHECK_THAT(run.out, Catch::StartsWith("usage: picksight-cam [--control ENDPOINT]"));
  CHECK_THAT(run.out, Catch::Contains("size CAM --scale S"));
  CHECK_THAT(run.out, Catch::Contains("features CAM"));
  CHECK_THAT(run.out, Catch::Contains("get CAM FEATURE"));
  CHECK_THAT(run.out, Catch::Contains("set CAM FEATURE VALUE"));
  CHECK_THAT(run.out, Catch::Contains("open CAM"));
  CHECK_THAT(run.out, Catch::Contains("close CAM"));
  CHECK_THAT(run.out, Catch::Contains("snap CAM FILE"));
}

TEST_CASE("a server error exits 1 with the server's text and code", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::UNKNOWN_CAMERA);
  reply.mutable_error()->set_text("unknown camera 'cam9'");
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"roi", "cam9", "0", "0", "64", "64"});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK(run.err ==
        "picksight-cam: roi: unknown camera 'cam9' (server error UNKNOWN_CAMERA, code 2)\n");
  CHECK(onlyRequest(server).set_roi().camera() == "cam9");
}

TEST_CASE("no server: exit 3 naming the endpoint and the timeout", "[cam]") {
  zmq::context_t context;
  const std::string endpoint = unusedEndpoint(context);
  const Run run = runCli(context, {"--control", endpoint, "--timeout", "200", "info", "cam0"});
  CHECK(run.code == 3);
  CHECK(run.out.empty());
  CHECK(run.err == "picksight-cam: no answer from " + endpoint +
                       " within 200 ms: is picksight-video-server running?\n");
}

TEST_CASE("JSON strings are escaped", "[cam]") {
  using picksight::cam::toJson;
  CHECK(toJson("plain") == "\"plain\"");
  CHECK(toJson("a\"b\\c") == "\"a\\\"b\\\\c\"");
  CHECK(toJson("line\nnext\ttab\r") == "\"line\\nnext\\ttab\\r\"");
  CHECK(toJson(std::string("\x01\x1f", 2)) == "\"\\u0001\\u001f\"");
  CHECK(toJson(std::string("nul\0x", 5)) == "\"nul\\u0000x\"");
  CHECK(toJson("caf\xc3\xa9") == "\"caf\xc3\xa9\"");  // UTF-8 passes through
  // Invalid UTF-8 (a camera's vendor string) must not make the output unreadable.
  CHECK(toJson("bad\xff") == "\"bad\xef\xbf\xbd\"");
}

TEST_CASE("toJson keeps key order and writes numbers JSON can read", "[cam]") {
  using picksight::cam::Json;
  Json json = Json::object();
  json["a"] = Json::array({1, 2.5, false, "x"});
  json["empty"] = Json::object();
  json["nan"] = std::numeric_limits<double>::quiet_NaN();
  json["big"] = std::numeric_limits<std::uint64_t>::max();
  json["k\"ey"] = Json::array({Json::object(), Json::object()});
  CHECK(picksight::cam::toJson(json) ==
        R"({"a":[1,2.5,false,"x"],"empty":{},"nan":null,"big":18446744073709551615,)"
        R"("k\"ey":[{},{}]})");
}
