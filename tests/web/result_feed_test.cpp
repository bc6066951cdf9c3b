// ResultFeed's JSON: made only for someone who wants it, newest first, never
// an older result's event after a newer one's.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "picksight/web/result_feed.hpp"

namespace picksight::web {
using namespace std::chrono_literals;

namespace {

proto::VisionResult locateResult(uint64_t id) {
  proto::VisionResult result;
  result.set_request_id(id);
  result.set_request("LOCATE");
  result.set_elapsed_ms(3);
  return result;
}

uint64_t requestIdOf(const std::string& event) {
  const std::string prefix = "event: result\ndata: ";
  REQUIRE(event.rfind(prefix, 0) == 0);
  const auto json = nlohmann::json::parse(event.substr(prefix.size()));
  return std::stoull(json.at("request_id").get<std::string>());
}

}  // namespace

TEST_CASE(
    "a result without an events client is turned into JSON when asked and later clients get later "
    "results",
    "[web]") {
  zmq::context_t context;
  EventHub hub;
  ResultFeed feed(context, {"cell", "none", "127.0.0.1", 9}, hub);
  CHECK(feed.latestJson().empty());
  feed.accept(locateResult(5));
  CHECK(feed.lastResultId() == 5);
  CHECK(feed.figures().at("LOCATE").count == 1);
  const auto json = nlohmann::json::parse(feed.latestJson());
  CHECK(json["request_id"] == "5");
  CHECK(json["app"] == "cell");
  // A client that comes later gets the results from then on.
  auto client = hub.subscribe();
  feed.accept(locateResult(6));
  auto event = client->pop(60s);
  REQUIRE(event);
  CHECK(requestIdOf(*event) == 6);
}

TEST_CASE("events of results in a burst arrive in order and end with the newest", "[web]") {
  zmq::context_t context;
  EventHub hub(256);
  ResultFeed feed(context, {"cell", "none", "127.0.0.1", 9}, hub);
  auto client = hub.subscribe();
  constexpr uint64_t kLast = 200;
  for (uint64_t id = 1; id <= kLast; ++id) feed.accept(locateResult(id));
  // Results the converter had no time for are skipped, for the page alone:
  // every one is counted all the same.
  CHECK(feed.figures().at("LOCATE").count == kLast);
  uint64_t last = 0;
  while (last != kLast) {
    auto event = client->pop(60s);
    REQUIRE(event);
    const uint64_t id = requestIdOf(*event);
    CHECK(id > last);
    last = id;
  }
  CHECK(nlohmann::json::parse(feed.latestJson())["request_id"] == std::to_string(kLast));
}

}  // namespace picksight::web
