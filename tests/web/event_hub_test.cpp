// The /events fan-out: bounded queues that drop the oldest for a lagging client.
#include <catch2/catch.hpp>

#include "picksight/web/event_hub.hpp"

namespace picksight::web {
using namespace std::chrono_literals;

TEST_CASE("a lagging events client loses its oldest events and nobody waits", "[web]") {
  EventHub hub(4);
  auto slow = hub.subscribe();
  auto fast = hub.subscribe();
  for (int i = 0; i < 10; ++i) {
    hub.publish("result", std::to_string(i));
    if (auto event = fast->pop(0ms))
      CHECK(*event == "event: result\ndata: " + std::to_string(i) + "\n\n");
  }
  CHECK(slow->dropped() == 6);
  CHECK(fast->dropped() == 0);
  for (int i = 6; i < 10; ++i) {
    auto event = slow->pop(0ms);
    REQUIRE(event);
    CHECK(*event == "event: result\ndata: " + std::to_string(i) + "\n\n");
  }
  CHECK(!slow->pop(0ms));
}

TEST_CASE("an events client that left is forgotten and closing wakes the others", "[web]") {
  EventHub hub(4);
  auto stays = hub.subscribe();
  {
    auto leaves = hub.subscribe();
    CHECK(hub.clients() == 2);
  }
  CHECK(hub.clients() == 1);
  hub.closeAll();
  CHECK(stays->closed());
  CHECK(!stays->pop(10s));  // returns at once once closed
}

}  // namespace picksight::web
