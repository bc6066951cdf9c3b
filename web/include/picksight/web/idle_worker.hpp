// Image work done for a browser on request (a snapshot's PNG, the
// binarized image), run by a thread at SCHED_IDLE so that it takes only a
// core no vision pass wants, as the JPEG encoders do. Four clients looping
// on /binary and /snapshot at normal priority tripled LOCATE time (issue
// 32).
//
// Threading: run() from any thread; it blocks its caller until the job is
// done. Jobs run one at a time in submission order on the worker's thread.
// A job that has waited kIdleStarved for the worker (every core busy) is
// run by its caller instead, one such caller at a time in the whole
// worker: a saturated machine serves an image now and then, never none.
// A job that throws on the worker has its exception thrown again by run(),
// in the caller's thread, as if the caller had run it.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace picksight::web {

constexpr std::chrono::milliseconds kIdleStarved{3000};

class IdleWorker {
 public:
  // `what` names the thread in the log should SCHED_IDLE be refused;
  // `max_queued`: jobs waiting at once, beyond which run() refuses.
  IdleWorker(std::string what, size_t max_queued = 16,
             std::chrono::milliseconds starved = kIdleStarved);
  ~IdleWorker();
  IdleWorker(const IdleWorker&) = delete;
  IdleWorker& operator=(const IdleWorker&) = delete;

  enum class Outcome { kIdle, kCaller, kRefused };
  // Runs `job` on the worker (kIdle), or after `starved` on the caller's
  // thread (kCaller), or not at all when max_queued jobs wait or another
  // caller is already running its own (kRefused).
  Outcome run(const std::function<void()>& job);

 private:
  struct Job {
    std::function<void()> fn;
    bool started = false;
    bool done = false;
    std::exception_ptr error;  // what the job threw on the worker
  };
  void loop();

  const size_t max_queued_;
  const std::chrono::milliseconds starved_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable finished_;
  std::deque<std::shared_ptr<Job>> queue_;  // under mutex_
  bool stopping_ = false;                   // under mutex_
  std::mutex caller_;                       // held by the one caller running its own job
  std::thread thread_;
  const std::string what_;
};

}  // namespace picksight::web
