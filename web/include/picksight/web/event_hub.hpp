// Server-Sent Events fan-out: every client has its own bounded queue, and a
// client that lags loses its oldest events, never slows the publisher.
//
// Threading: publish() from any thread (the result feeds, the camera
// poller); each client's queue is read by the HTTP thread serving it.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace picksight::web {

class EventQueue {
 public:
  explicit EventQueue(size_t capacity) : capacity_(capacity) {}
  // Adds one formatted event; drops the oldest when full.
  void push(const std::shared_ptr<const std::string>& event);
  // The next event, or nullopt after `timeout` or once closed.
  std::shared_ptr<const std::string> pop(std::chrono::milliseconds timeout);
  void close();
  bool closed() const;
  uint64_t dropped() const;

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::shared_ptr<const std::string>> events_;  // under mutex_
  uint64_t dropped_ = 0;                                   // under mutex_
  bool closed_ = false;                                    // under mutex_
};

class EventHub {
 public:
  explicit EventHub(size_t queue_capacity = 64) : capacity_(queue_capacity) {}

  // A new client's queue; it leaves the hub when the caller drops it.
  std::shared_ptr<EventQueue> subscribe();
  // Sends `event: <name>` with one data line (no newline inside) to every client.
  void publish(const std::string& name, const std::string& data);
  // Wakes and closes every client (server stop).
  void closeAll();
  size_t clients();

 private:
  const size_t capacity_;
  std::mutex mutex_;
  std::vector<std::weak_ptr<EventQueue>> clients_;  // under mutex_
};

}  // namespace picksight::web
