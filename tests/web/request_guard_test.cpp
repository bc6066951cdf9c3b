// The Host, Origin and cross-site rules of picksight-web's requests, and the
// refusal log's bound, without a server.
#include <catch2/catch.hpp>

#include "picksight/web/refusal_log.hpp"
#include "picksight/web/request_guard.hpp"

namespace picksight::web {
namespace {

RequestFacts post(const std::string& origin, const std::string& type, const std::string& header) {
  RequestFacts r;
  r.method = "POST";
  r.host = "cell.example:8080";
  r.has_origin = !origin.empty();
  r.origin = origin;
  r.content_type = type;
  r.request_header = header;
  return r;
}

}  // namespace

TEST_CASE("Host headers are matched by name in any case and with any port", "[web][security]") {
  const HostNames names({"Cell.Example", "10.1.2.3", "fd00::7"});
  CHECK(names.allowsHost("cell.example"));
  CHECK(names.allowsHost("CELL.example:8080"));
  CHECK(names.allowsHost("cell.example."));
  CHECK(names.allowsHost("10.1.2.3:443"));
  CHECK(names.allowsHost("[fd00::7]:8080"));
  CHECK(names.allowsHost("[FD00::7]"));
  CHECK_FALSE(names.allowsHost("cell.example.attacker.net"));
  CHECK_FALSE(names.allowsHost("attacker.net"));
  CHECK_FALSE(names.allowsHost("cell.example:80x"));
  CHECK_FALSE(names.allowsHost("cell.example@attacker.net"));
  CHECK_FALSE(names.allowsHost("[fd00::7"));
  CHECK_FALSE(names.allowsHost(""));
  CHECK(names.allowsOrigin("http://cell.example:8080"));
  CHECK(names.allowsOrigin("https://[fd00::7]"));
  CHECK_FALSE(names.allowsOrigin("null"));
  CHECK_FALSE(names.allowsOrigin("file://cell.example"));
  CHECK_FALSE(names.allowsOrigin("http://attacker.net"));
  CHECK(HostNames({"*"}).allowsHost("anything.at.all"));
}

TEST_CASE("the default host names hold loopback and this machine", "[web][security]") {
  const auto defaults = HostNames::defaults("0.0.0.0");
  const HostNames names(defaults);
  CHECK(names.allowsHost("localhost:8080"));
  CHECK(names.allowsHost("127.0.0.1"));
  CHECK(names.allowsHost("[::1]:8080"));
  CHECK_FALSE(names.allowsHost("0.0.0.0"));
  CHECK(HostNames(HostNames::defaults("cell.example")).allowsHost("cell.example"));
}

TEST_CASE("a change needs a matching Origin and a JSON type and the X-PickSight header",
          "[web][security]") {
  const HostNames names({"cell.example"});
  CHECK_FALSE(checkRequest(names, post("http://cell.example:8080", "application/json", "1")));
  CHECK_FALSE(checkRequest(names, post("", "Application/JSON; charset=utf-8", "1")));
  // The cross-site form post.
  auto refusal = checkRequest(names, post("http://attacker.net", "text/plain", ""));
  REQUIRE(refusal);
  CHECK(refusal->status == 403);
  refusal = checkRequest(names, post("", "text/plain", "1"));
  REQUIRE(refusal);
  CHECK(refusal->status == 415);
  refusal = checkRequest(names, post("", "application/jsonx", "1"));
  REQUIRE(refusal);
  CHECK(refusal->status == 415);
  refusal = checkRequest(names, post("http://cell.example", "application/json", ""));
  REQUIRE(refusal);
  CHECK(refusal->status == 403);
  CHECK(refusal->message.find("X-PickSight") != std::string::npos);
  // Reads need no header nor type, only a right Host and Origin.
  RequestFacts get = post("", "", "");
  get.method = "GET";
  CHECK_FALSE(checkRequest(names, get));
  get.host = "attacker.net";
  CHECK(checkRequest(names, get));
  for (const char* method : {"PUT", "DELETE", "PATCH", "POST"}) CHECK(changesState(method));
  for (const char* method : {"GET", "HEAD", "OPTIONS"}) CHECK_FALSE(changesState(method));
}

TEST_CASE("refusals are counted per address", "[web][security]") {
  RefusalLog log("HTTP");
  for (int i = 0; i < 1000; ++i) log.refused("10.0.0.1", "test");
  log.refused("10.0.0.2", "test");
  CHECK(log.count("10.0.0.1") == 1000);
  CHECK(log.count("10.0.0.2") == 1);
  CHECK(log.count("10.0.0.3") == 0);
  CHECK(log.total() == 1001);
}

}  // namespace picksight::web
