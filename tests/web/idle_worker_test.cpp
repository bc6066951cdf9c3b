// The idle-priority worker of on-demand images: jobs run at SCHED_IDLE; a
// starved job runs on its caller, one caller at a time; beyond that, refused.
#include <sched.h>

#include <atomic>
#include <future>
#include <stdexcept>
#include <thread>

#include <catch2/catch.hpp>

#include "picksight/web/idle_worker.hpp"

namespace picksight::web {
using namespace std::chrono_literals;

TEST_CASE("an on-demand image job runs at idle priority", "[web]") {
  IdleWorker worker("test images");
  int policy = -1;
  CHECK(worker.run([&] { policy = sched_getscheduler(0); }) == IdleWorker::Outcome::kIdle);
  CHECK(policy == SCHED_IDLE);
}

TEST_CASE("a starved image job runs on its caller and one caller at a time", "[web]") {
  IdleWorker worker("test images", 16, 100ms);
  std::promise<void> release_worker;
  std::shared_future<void> worker_released = release_worker.get_future().share();
  std::atomic<bool> worker_busy{false};
  // The worker is held by a first job, as by a core that never frees.
  auto first = std::async(std::launch::async, [&] {
    return worker.run([&] {
      worker_busy = true;
      worker_released.wait();
    });
  });
  while (!worker_busy) std::this_thread::sleep_for(1ms);
  std::promise<void> release_caller;
  std::shared_future<void> caller_released = release_caller.get_future().share();
  std::atomic<bool> caller_busy{false};
  auto second = std::async(std::launch::async, [&] {
    return worker.run([&] {
      caller_busy = true;
      caller_released.wait();
    });
  });
  while (!caller_busy) std::this_thread::sleep_for(1ms);
  // A third, starved too, finds the one caller's place taken.
  bool ran = false;
  CHECK(worker.run([&] { ran = true; }) == IdleWorker::Outcome::kRefused);
  CHECK_FALSE(ran);
  release_caller.set_value();
  CHECK(second.get() == IdleWorker::Outcome::kCaller);
  release_worker.set_value();
  CHECK(first.get() == IdleWorker::Outcome::kIdle);
  CHECK(worker.run([&] { ran = true; }) == IdleWorker::Outcome::kIdle);
  CHECK(ran);
}

TEST_CASE("an image job that throws fails its own request, not the worker", "[web]") {
  // Say a PNG encoder that throws, or the codecs module missing: on the
  // worker's thread the exception would have ended the web server.
  IdleWorker worker("test images");
  CHECK_THROWS_WITH(worker.run([] { throw std::runtime_error("no codecs here"); }),
                    "no codecs here");
  bool ran = false;
  CHECK(worker.run([&] { ran = true; }) == IdleWorker::Outcome::kIdle);
  CHECK(ran);
}

}  // namespace picksight::web
