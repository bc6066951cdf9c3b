// GET /metrics for a scraper without a session: with the bearer token of
// --metrics-token, or from an address of --metrics-allow; nothing else
// opens, and a token file others may read stops the server at start.
#include <sys/stat.h>
#include <sys/wait.h>

#include "picksight/web/web_options.hpp"
#include "raw_http.hpp"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using e2e::VideoServerProcess;
using tool_support::Subprocess;

// A GET from `source` (a loopback address) with extra header lines.
std::string rawGet(const WebProcess& web, const std::string& path, const std::string& source,
                   const std::string& headers = "") {
  RawSocket socket(web.port, source);
  REQUIRE(socket.valid());
  REQUIRE(socket.send("GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(web.port) +
                      "\r\n" + headers + "Connection: close\r\n\r\n"));
  return socket.readAll();
}

}  // namespace

TEST_CASE("a scraper reads /metrics with the bearer token or from an allowed address",
          "[web][metrics]") {
  test::TempDir dir;
  const std::string token = "s3cret-metrics-token-0123456789";
  const std::string token_file = dir.write("metrics-token", token + "\n");
  REQUIRE(::chmod(token_file.c_str(), 0640) == 0);
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--metrics-token", token_file, "--metrics-allow", "127.0.0.2"});
  WebProcess web(args);

  std::string res = rawGet(web, "/metrics", "127.0.0.1");
  CHECK(statusOf(res) == 401);
  res = rawGet(web, "/metrics", "127.0.0.1", "Authorization: Bearer " + token + "\r\n");
  CHECK(statusOf(res) == 200);
  CHECK_THAT(bodyOf(res), Catch::Contains("picksight_camera_frames_total{camera=\"cam0\"}"));
  res = rawGet(web, "/metrics", "127.0.0.1", "Authorization: bearer " + token + "\r\n");
  CHECK(statusOf(res) == 200);
  for (const std::string& wrong : {token + "x", token.substr(1), std::string("Basic abc"), token}) {
    CAPTURE(wrong);
    res =
        rawGet(web, "/metrics", "127.0.0.1",
               "Authorization: " + (wrong == token ? "" : std::string("Bearer ")) + wrong + "\r\n");
    CHECK(statusOf(res) == 401);
  }
  // The token opens /metrics only.
  res = rawGet(web, "/api/cameras", "127.0.0.1", "Authorization: Bearer " + token + "\r\n");
  CHECK(statusOf(res) == 401);

  // The allowed address needs nothing, for /metrics only.
  res = rawGet(web, "/metrics", "127.0.0.2");
  CHECK(statusOf(res) == 200);
  CHECK_THAT(bodyOf(res), Catch::Contains("picksight_camera_fps"));
  CHECK(statusOf(rawGet(web, "/api/cameras", "127.0.0.2")) == 401);
  CHECK(statusOf(rawGet(web, "/frame/cam0.jpg", "127.0.0.2")) == 401);
  CHECK(statusOf(rawGet(web, "/metrics", "127.0.0.3")) == 401);
  // A foreign Host is refused as for every request.
  RawSocket socket(web.port, "127.0.0.2");
  REQUIRE(
      socket.send("GET /metrics HTTP/1.1\r\nHost: attacker.example\r\nConnection: close\r\n\r\n"));
  CHECK(statusOf(socket.readAll()) == 403);
}

TEST_CASE("without a metrics token or allow-list /metrics needs a login", "[web][metrics]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  CHECK(statusOf(rawGet(web, "/metrics", "127.0.0.2")) == 401);
  CHECK(statusOf(rawGet(web, "/metrics", "127.0.0.1",
                        "Authorization: Bearer 0123456789abcdef\r\n")) == 401);
  CHECK(statusOf(rawGet(web, "/metrics", "127.0.0.1", web.cookieLine())) == 200);
}

TEST_CASE("a metrics token file others may read or too short is refused", "[web][metrics]") {
  test::TempDir dir;
  const std::string open_file = dir.write("open", "0123456789abcdef0123\n");
  REQUIRE(::chmod(open_file.c_str(), 0644) == 0);
  auto open = web::parseWebArgs({"--metrics-token", open_file}, nullptr);
  REQUIRE_FALSE(open);
  CHECK_THAT(open.error().message, Catch::Contains("--metrics-token") && Catch::Contains("0644"));
  const std::string short_file = dir.write("short", "abc\n");
  REQUIRE(::chmod(short_file.c_str(), 0600) == 0);
  auto short_token = web::parseWebArgs({"--metrics-token", short_file}, nullptr);
  REQUIRE_FALSE(short_token);
  CHECK_THAT(short_token.error().message, Catch::Contains("16..256"));
  auto missing = web::parseWebArgs({"--metrics-token", dir.path().string() + "/none"}, nullptr);
  REQUIRE_FALSE(missing);
  auto allow = web::parseWebArgs({"--metrics-allow", "10.0.0.0/99"}, nullptr);
  REQUIRE_FALSE(allow);
  CHECK_THAT(allow.error().message, Catch::Contains("--metrics-allow"));
  // The server does not start with it.
  Subprocess web(
      {e2e::binPath("picksight-web"), "--listen", "127.0.0.1:0", "--metrics-token", open_file});
  const auto status = web.wait(std::chrono::seconds(10));
  REQUIRE(status);
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 2);
}

}  // namespace picksight::webtest
