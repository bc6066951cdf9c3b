// The idle-priority worker for on-demand images (idle_worker.hpp).
#include "picksight/web/idle_worker.hpp"

#include <algorithm>

#include "picksight/web/idle_priority.hpp"

namespace picksight::web {

IdleWorker::IdleWorker(std::string what, size_t max_queued, std::chrono::milliseconds starved)
    : max_queued_(max_queued), starved_(starved), what_(std::move(what)) {
  thread_ = std::thread([this] { loop(); });
}

IdleWorker::~IdleWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void IdleWorker::loop() {
  runAtIdlePriority(what_);
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) break;
    auto job = queue_.front();
    queue_.pop_front();
    job->started = true;
    lock.unlock();
    try {
      job->fn();
    } catch (...) {
      // Not this thread's to handle (it would end the web server): the
      // caller's, whose request then fails alone.
      job->error = std::current_exception();
    }
    lock.lock();
    job->done = true;
    finished_.notify_all();
  }
  // Callers still waiting run their own jobs.
  for (auto& job : queue_) job->started = false;
  finished_.notify_all();
}

IdleWorker::Outcome IdleWorker::run(const std::function<void()>& job) {
  auto entry = std::make_shared<Job>();
  entry->fn = job;
  std::unique_lock<std::mutex> lock(mutex_);
  if (queue_.size() >= max_queued_) return Outcome::kRefused;
  if (!stopping_) {
    queue_.push_back(entry);
    wake_.notify_one();
    finished_.wait_for(lock, starved_, [&] { return entry->done || stopping_; });
    // Begun on the worker by now: it finishes what it began.
    if (entry->started) finished_.wait(lock, [&] { return entry->done; });
    if (entry->done) {
      if (entry->error) std::rethrow_exception(entry->error);
      return Outcome::kIdle;
    }
    queue_.erase(std::remove(queue_.begin(), queue_.end(), entry), queue_.end());
  }
  lock.unlock();
  // Starved (or stopping): run here, one caller at a time.
  std::unique_lock<std::mutex> mine(caller_, std::try_to_lock);
  if (!mine.owns_lock()) return Outcome::kRefused;
  job();
  return Outcome::kCaller;
}

}  // namespace picksight::web
