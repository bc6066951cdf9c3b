// Results publisher: a bounded queue of request records, one thread that
// turns each into a VisionResult and sends it without blocking, when
// someone subscribes.
#include "picksight/results/results_publisher.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <stdexcept>
#include <thread>
#include <zmq.hpp>

#include "picksight/common/log.hpp"
#include "result_message.hpp"

namespace picksight::results {

struct ResultsPublisher::Impl {
  // XPUB: a PUB socket that also hands over its subscriptions, so that no
  // result is built while nobody listens.
  explicit Impl(ResultsOptions o) : options(std::move(o)), socket(context, zmq::socket_type::xpub) {
    // HWM counts message parts: two per result.
    socket.set(zmq::sockopt::sndhwm, 2 * std::max(options.send_hwm, 1));
    socket.set(zmq::sockopt::linger, 0);
    try {
      socket.bind(options.bind);
    } catch (const zmq::error_t& e) {
      throw std::runtime_error("results stream: cannot bind '" + options.bind + "': " + e.what());
    }
    endpoint = socket.get(zmq::sockopt::last_endpoint);
    thread = std::thread([this] { run(); });
  }

  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    wake.notify_all();
    thread.join();
  }

  void run() {
    proto::VisionResult message;
    std::string bytes;
    for (;;) {
      std::shared_ptr<const RequestRecord> record;
      uint64_t id = 0;
      {
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait(lock, [this] { return stop || !queue.empty(); });
        if (stop) return;
        record = std::move(queue.front().first);
        id = queue.front().second;
        queue.pop_front();
      }
      readSubscriptions();
      if (!watched()) {
        // Nobody would receive it: building the message (regions, outlines,
        // rejections) would only take CPU from the next request.
        ++unwatched;
        continue;
      }
      try {
        buildVisionResult(*record, options.app, id, message);
        message.SerializeToString(&bytes);
        // Never blocks: at the high-water mark ZeroMQ drops for that
        // subscriber, and a PUB socket never refuses a message.
        const bool topic_sent = socket
                                    .send(zmq::buffer(options.app),
                                          zmq::send_flags::sndmore | zmq::send_flags::dontwait)
                                    .has_value();
        if (topic_sent && socket.send(zmq::buffer(bytes), zmq::send_flags::dontwait)) {
          ++sent;
        } else {
          ++dropped;
        }
      } catch (const std::exception& e) {
        // One bad result costs that result, never the stream.
        ++dropped;
        logError("results stream: request ", id, ": ", e.what());
      }
    }
  }

  // The subscriptions the socket received since last time (a message each:
  // 1 subscribe or 0 unsubscribe, then the topic prefix), never waiting.
  // XPUB passes on the first subscription to a prefix and the last
  // unsubscription (a subscriber's disconnection included).
  void readSubscriptions() {
    zmq::message_t m;
    while (socket.recv(m, zmq::recv_flags::dontwait)) {
      if (m.size() == 0) continue;
      const auto* bytes = static_cast<const char*>(m.data());
      const std::string prefix(bytes + 1, m.size() - 1);
      // Only prefixes of this stream's topic matter, which also bounds the map.
      if (options.app.compare(0, prefix.size(), prefix) != 0) continue;
      if (bytes[0] == 1) {
        ++subscriptions[prefix];
      } else if (bytes[0] == 0) {
        const auto it = subscriptions.find(prefix);
        if (it != subscriptions.end() && --it->second <= 0) subscriptions.erase(it);
      }
    }
  }
  bool watched() const { return !subscriptions.empty(); }

  const ResultsOptions options;
  zmq::context_t context{1};
  zmq::socket_t socket;
  std::string endpoint;
  std::mutex mutex;  // guards queue, stop, next_id
  std::condition_variable wake;
  std::deque<std::pair<std::shared_ptr<const RequestRecord>, uint64_t>> queue;
  uint64_t next_id = 1;
  bool stop = false;
  std::atomic<uint64_t> sent{0};
  std::atomic<uint64_t> dropped{0};
  std::atomic<uint64_t> unwatched{0};
  std::map<std::string, int> subscriptions;  // publisher thread: prefixes of the topic
  std::thread thread;                        // last: started once everything else is ready
};

ResultsPublisher::ResultsPublisher(ResultsOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

ResultsPublisher::~ResultsPublisher() = default;

const std::string& ResultsPublisher::endpoint() const { return impl_->endpoint; }

void ResultsPublisher::publish(std::shared_ptr<const RequestRecord> record) {
  if (!record) return;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    auto& queue = impl_->queue;
    if (queue.size() >= std::max<size_t>(impl_->options.queue, 1)) {
      // The oldest: a viewer wants the newest. But a change is the audit
      // trail's record of who changed the cell: the oldest of the others
      // goes first (LOCATEs in a loop never push a change out).
      auto victim = std::find_if(queue.begin(), queue.end(),
                                 [](const auto& entry) { return !entry.first->changed; });
      queue.erase(victim == queue.end() ? queue.begin() : victim);
      ++impl_->dropped;
    }
    impl_->queue.emplace_back(std::move(record), impl_->next_id++);
  }
  impl_->wake.notify_one();
}

uint64_t ResultsPublisher::sent() const { return impl_->sent; }
uint64_t ResultsPublisher::dropped() const { return impl_->dropped; }
uint64_t ResultsPublisher::unwatched() const { return impl_->unwatched; }

std::function<void(const std::string& reply)> publishWhenSent(
    std::shared_ptr<RequestRecord> record, std::chrono::steady_clock::time_point received,
    ResultsPublisher* results) {
  return [record = std::move(record), received, results](const std::string& reply) {
    record->reply = reply;
    record->elapsed_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - received)
            .count();
    if (results) results->publish(record);
  };
}

}  // namespace picksight::results
