// Bounded per-client event queues for /events.
#include "picksight/web/event_hub.hpp"

#include <algorithm>

namespace picksight::web {

void EventQueue::push(const std::shared_ptr<const std::string>& event) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (closed_) return;
  if (events_.size() >= capacity_) {
    events_.pop_front();
    ++dropped_;
  }
  events_.push_back(event);
  ready_.notify_one();
}

std::shared_ptr<const std::string> EventQueue::pop(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  ready_.wait_for(lock, timeout, [&] { return !events_.empty() || closed_; });
  if (events_.empty() || closed_) return nullptr;
  auto event = std::move(events_.front());
  events_.pop_front();
  return event;
}

void EventQueue::close() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_ = true;
  ready_.notify_all();
}

bool EventQueue::closed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return closed_;
}

uint64_t EventQueue::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

std::shared_ptr<EventQueue> EventHub::subscribe() {
  auto queue = std::make_shared<EventQueue>(capacity_);
  std::lock_guard<std::mutex> lock(mutex_);
  clients_.push_back(queue);
  return queue;
}

void EventHub::publish(const std::string& name, const std::string& data) {
  auto event = std::make_shared<const std::string>("event: " + name + "\ndata: " + data + "\n\n");
  std::vector<std::shared_ptr<EventQueue>> live;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    clients_.erase(std::remove_if(clients_.begin(), clients_.end(),
                                  [](const std::weak_ptr<EventQueue>& q) { return q.expired(); }),
                   clients_.end());
    for (const auto& weak : clients_)
      if (auto queue = weak.lock()) live.push_back(std::move(queue));
  }
  for (const auto& queue : live) queue->push(event);
}

void EventHub::closeAll() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& weak : clients_)
    if (auto queue = weak.lock()) queue->close();
}

size_t EventHub::clients() {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<size_t>(
      std::count_if(clients_.begin(), clients_.end(),
                    [](const std::weak_ptr<EventQueue>& q) { return !q.expired(); }));
}

}  // namespace picksight::web
