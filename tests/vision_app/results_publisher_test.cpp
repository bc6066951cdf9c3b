// The results publisher builds and sends a result only while someone
// subscribes to its topic: an unwatched stream takes no CPU from the next
// request. Real ZeroMQ sockets on a free port.
#include <catch2/catch.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <thread>

#include <zmq.hpp>

#include "picksight/results/results_publisher.hpp"

using namespace picksight::results;
using namespace std::chrono_literals;

namespace {
std::shared_ptr<RequestRecord> blobsRecord() {
  auto r = std::make_shared<RequestRecord>();
  r->request = "BLOBS";
  r->request_line = "BLOBS";
  r->reply = "OK 0";
  return r;
}

// Polls `done` until it holds or 10 s pass.
bool eventually(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

// A SUB socket on `topic`.
struct Subscriber {
  zmq::socket_t socket;
  Subscriber(zmq::context_t& context, const std::string& endpoint, const std::string& topic)
      : socket(context, zmq::socket_type::sub) {
    socket.set(zmq::sockopt::subscribe, topic);
    socket.set(zmq::sockopt::linger, 0);
    socket.set(zmq::sockopt::rcvtimeo, 100);
    socket.connect(endpoint);
  }
  bool received() {
    zmq::message_t topic, body;
    if (!socket.recv(topic)) return false;
    return topic.more() && socket.recv(body).has_value();
  }
};
}  // namespace

TEST_CASE("the results stream builds nothing while nobody subscribes to its topic",
          "[results][unwatched]") {
  ResultsOptions options;
  options.app = "cam0";
  ResultsPublisher publisher(options);
  for (int i = 0; i < 5; ++i) publisher.publish(blobsRecord());
  REQUIRE(eventually([&] { return publisher.unwatched() == 5; }));
  CHECK(publisher.sent() == 0);
  CHECK(publisher.dropped() == 0);

  zmq::context_t context;
  {
    // Another topic's subscriber wants none of it.
    Subscriber other(context, publisher.endpoint(), "cam1");
    Subscriber watcher(context, publisher.endpoint(), "cam");  // a prefix of the topic
    // A subscription arrives a moment after the connection: results are
    // built once it has.
    REQUIRE(eventually([&] {
      publisher.publish(blobsRecord());
      return watcher.received();
    }));
    // Counted just after the send: a moment after the subscriber has it.
    CHECK(eventually([&] { return publisher.sent() >= 1; }));
    CHECK(!other.received());
  }
  // Both gone: the publisher hears the last unsubscription and stops building.
  const uint64_t before = publisher.unwatched();
  REQUIRE(eventually([&] {
    publisher.publish(blobsRecord());
    return publisher.unwatched() > before;
  }));
  // Counted before publishing: the publisher thread may take the first of
  // the three before this thread reads a counter again.
  const uint64_t sent = publisher.sent();
  const uint64_t counted = publisher.unwatched() + publisher.dropped();
  for (int i = 0; i < 3; ++i) publisher.publish(blobsRecord());
  REQUIRE(eventually([&] { return publisher.unwatched() + publisher.dropped() >= counted + 3; }));
  CHECK(publisher.sent() == sent);
}
