// picksight-web's limits seen from outside: a static path that climbs out
// of the assets directory to a file that exists is not served (raw bytes, as
// a client library would not send them), and --max-streams caps the event
// streams open at once (the next one is a 503).
#include <filesystem>

#include "raw_http.hpp"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;

std::string rawGet(int port, const std::string& path) {
  return rawRequest(port, "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                              "\r\nConnection: close\r\n\r\n");
}
}  // namespace

TEST_CASE("a static path climbing out of the assets directory does not serve the file there",
          "[web][security]") {
  // The secret lies beside the assets directory: "../secret.txt" from it
  // names a file that exists, so only the server's check keeps it back.
  test::TempDir root;
  const std::filesystem::path assets = root.path() / "assets";
  std::filesystem::create_directory(assets);
  root.write("assets/app.js", "console.log(1);");
  root.write("secret.txt", "secret-4711");
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--assets", assets.string()});
  WebProcess web(args);
  // A file inside is served (the positive control).
  const std::string inside = rawGet(web.port, "/static/app.js");
  CHECK(statusOf(inside) == 200);
  CHECK(bodyOf(inside) == "console.log(1);");
  for (const char* path : {"/static/../secret.txt", "/static/%2e%2e/secret.txt",
                           "/static/%2E%2E%2Fsecret.txt", "/static/.%2e/secret.txt"}) {
    INFO(path);
    const std::string response = rawGet(web.port, path);
    CHECK(statusOf(response) >= 400);
    CHECK(response.find("secret-4711") == std::string::npos);
  }
}

TEST_CASE("with --max-streams 1 a second event stream gets 503", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--max-streams", "1"});
  WebProcess web(args);
  const std::string request =
      "GET /events HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(web.port) + "\r\n" +
      web.cookieLine() + "Connection: close\r\n\r\n";
  RawSocket first(web.port);
  REQUIRE(first.valid());
  REQUIRE(first.send(request));
  // The first stream's headers arrive and it stays open.
  const std::string head = first.readAll(2s);
  REQUIRE(statusOf(head) == 200);
  const std::string second = rawRequest(web.port, request);
  CHECK(statusOf(second) == 503);
  CHECK_THAT(bodyOf(second), Catch::Contains("--max-streams 1"));
}

}  // namespace picksight::webtest
