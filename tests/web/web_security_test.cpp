// picksight-web refusing what a hostile page or network could send: a
// cross-site form post, a rebinding page's foreign Host, requests that a
// form could make; written as raw HTTP against a real cell, and checked by
// what did not change (the model is still there, the camera still open).
#include <nlohmann/json.hpp>

#include "raw_http.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;
using e2e::VisionProcess;
using nlohmann::json;

// A POST as raw bytes: `headers` are whole lines, each ending in CRLF.
std::string rawPost(const WebProcess& web, const std::string& path, const std::string& headers,
                    const std::string& body) {
  return rawRequest(web.port, "POST " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" +
                                  std::to_string(web.port) + "\r\n" + web.cookieLine() + headers +
                                  "Content-Length: " + std::to_string(body.size()) +
                                  "\r\nConnection: close\r\n\r\n" + body);
}

// A GET as the logged-in admin, naming `host`.
std::string rawGet(const WebProcess& web, const std::string& path, const std::string& host) {
  return rawRequest(web.port, "GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\n" +
                                  web.cookieLine() + "Connection: close\r\n\r\n");
}

std::string cameraState(const WebProcess& web) {
  auto res = web.client().Get("/api/cameras");
  REQUIRE(res);
  const json cameras = json::parse(res->body);
  REQUIRE(cameras.is_array());
  REQUIRE(!cameras.empty());
  return cameras[0].value("state", "");
}

}  // namespace

TEST_CASE("a cross-site form post neither forgets a model nor closes the camera",
          "[web][security]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--fps", "10"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  auto learned = robot.request("LEARN 4", 10s);
  REQUIRE(learned);
  REQUIRE(learned->rfind("OK 4 ", 0) == 0);
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:" + std::to_string(vision.robot_port)});
  REQUIRE(pollUntil([&] { return cameraState(web) == "streaming"; }));
  const int port = web.port;
  const std::string forget = R"({"line":"FORGET 4","x":"="})";
  const std::string command = "/api/apps/cam0/command";
  const std::string self = "Origin: http://127.0.0.1:" + std::to_string(port) + "\r\n";

  // The issue's exact attack: a form's text/plain body, a foreign Origin.
  std::string res = rawPost(
      web, command, "Origin: http://attacker.example\r\nContent-Type: text/plain\r\n", forget);
  CHECK(statusOf(res) == 403);
  CHECK(json::parse(bodyOf(res))["error"].get<std::string>().find("Origin") != std::string::npos);
  // Each defence alone refuses it: a form's type from the page's own origin,
  // JSON without the header a form cannot add, a foreign Origin with both.
  res = rawPost(web, command, self + "Content-Type: text/plain\r\nX-PickSight: 1\r\n", forget);
  CHECK(statusOf(res) == 415);
  res = rawPost(web, command, self + "Content-Type: application/x-www-form-urlencoded\r\n", forget);
  CHECK(statusOf(res) == 415);
  res = rawPost(web, command, self + "Content-Type: application/json\r\n", forget);
  CHECK(statusOf(res) == 403);
  res = rawPost(web, command,
                "Origin: null\r\nContent-Type: application/json\r\nX-PickSight: 1\r\n", forget);
  CHECK(statusOf(res) == 403);
  res = rawPost(web, command,
                "Origin: http://127.0.0.1.attacker.example:" + std::to_string(port) +
                    "\r\nContent-Type: application/json\r\nX-PickSight: 1\r\n",
                forget);
  CHECK(statusOf(res) == 403);
  // The camera close, likewise.
  res = rawPost(web, "/api/cameras/cam0/close",
                "Origin: http://attacker.example\r\nContent-Type: text/plain\r\n", "{}");
  CHECK(statusOf(res) == 403);
  res = rawPost(web, "/api/cameras/cam0/close", "Content-Type: text/plain\r\n", "{}");
  CHECK(statusOf(res) == 415);

  // Nothing changed: the model is still there, the camera still streams.
  auto models = robot.request("MODELS", 5s);
  REQUIRE(models);
  CHECK(models->rfind("OK 1", 0) == 0);
  CHECK(cameraState(web) == "streaming");

  // The page's own request does it (so the checks above could see a change).
  res =
      rawPost(web, command,
              self + "Content-Type: application/json; charset=utf-8\r\nX-PickSight: 1\r\n", forget);
  CHECK(statusOf(res) == 200);
  CHECK(json::parse(bodyOf(res))["reply"] == "OK");
  CHECK(*robot.request("MODELS", 5s) == "OK 0");
  res = rawPost(web, "/api/cameras/cam0/close",
                "Content-Type: application/json\r\nX-PickSight: 1\r\n", "{}");
  CHECK(statusOf(res) == 200);
  CHECK(pollUntil([&] { return cameraState(web) == "closed"; }));
}

TEST_CASE("a foreign Host is refused for reads too against DNS rebinding", "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  WebProcess web(videoServerArgs(server));
  const int port = web.port;
  const std::string p = ":" + std::to_string(port);
  for (const char* path : {"/", "/api/cameras", "/snapshot/cam0.png", "/frame/cam0.jpg", "/events",
                           "/metrics", "/static/app.js"}) {
    CAPTURE(path);
    const std::string res = rawGet(web, path, "rebind.attacker.example" + p);
    CHECK(statusOf(res) == 403);
    CHECK(bodyOf(res).find("Host") != std::string::npos);
  }
  CHECK(statusOf(rawRequest(port, "GET /api/cameras HTTP/1.0\r\n\r\n")) == 400);
  // The machine's own names, in any case, with or without the port.
  for (const std::string& host : std::vector<std::string>{
           "127.0.0.1" + p, "localhost" + p, "LOCALHOST", "[::1]" + p, "localhost." + p}) {
    CAPTURE(host);
    CHECK(statusOf(rawGet(web, "/api/cameras", host)) == 200);
  }
}

TEST_CASE("the hosts the server answers to are those of --allow-host", "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--allow-host", "cell7.example,127.0.0.1"});
  WebProcess web(args);
  CHECK(statusOf(rawGet(web, "/api/cameras", "Cell7.Example:8443")) == 200);
  CHECK(statusOf(rawGet(web, "/api/cameras", "127.0.0.1")) == 200);
  CHECK(statusOf(rawGet(web, "/api/cameras", "localhost")) == 403);
}

TEST_CASE("every response forbids framing and foreign scripts and type sniffing",
          "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  WebProcess web(videoServerArgs(server));
  const std::string host = "127.0.0.1:" + std::to_string(web.port);
  for (const std::string& res :
       std::vector<std::string>{rawGet(web, "/", host), rawGet(web, "/nothing", host),
                                rawGet(web, "/api/cameras", "attacker.example")}) {
    CHECK(headerOf(res, "X-Frame-Options") == "DENY");
    CHECK(headerOf(res, "X-Content-Type-Options") == "nosniff");
    const std::string csp = headerOf(res, "Content-Security-Policy");
    CHECK(csp.find("default-src 'none'") != std::string::npos);
    CHECK(csp.find("script-src 'self'") != std::string::npos);
    CHECK(csp.find("frame-ancestors 'none'") != std::string::npos);
    CHECK(csp.find("unsafe") == std::string::npos);
  }
}

TEST_CASE("malformed input gets a 4xx with a plain message and never a 500 with internals",
          "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:1"});
  const int port = web.port;
  const std::string json_post = "Content-Type: application/json\r\nX-PickSight: 1\r\n";
  struct Case {
    std::string response;
    int status;
  };
  const std::vector<Case> cases = {
      {rawPost(web, "/api/apps/cam0/command", json_post, R"({"line": 1e999})"), 400},
      {rawPost(web, "/api/cameras/cam0/roi", json_post, R"({"x": -1e999})"), 400},
      {rawPost(web, "/api/cameras/cam0/feature", json_post, "{\"name\": \"\xff\"}"), 400},
      {rawGet(web, "/static/%ff", "127.0.0.1"), 404},
      {rawGet(web, "/static/%ff%fe.js", "127.0.0.1"), 404},
      {rawGet(web, "/snapshot/%ff.png", "127.0.0.1"), 404},
      {rawGet(web, "/no/such/route", "127.0.0.1"), 404},
      {rawRequest(port, "BREW / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"), 400},
  };
  for (const auto& c : cases) {
    CAPTURE(c.response.substr(0, 300));
    CHECK(statusOf(c.response) == c.status);
    CHECK(headerOf(c.response, "EXCEPTION_WHAT").empty());
    const json body = json::parse(bodyOf(c.response), nullptr, false);
    REQUIRE(body.is_object());
    const std::string error = body.value("error", "");
    CHECK(!error.empty());
    CHECK(error.find("json.exception") == std::string::npos);
  }
  // The overflowing number is named as such.
  CHECK_THAT(json::parse(bodyOf(cases[0].response))["error"].get<std::string>(),
             Catch::Contains("1e999"));
}

}  // namespace picksight::webtest
