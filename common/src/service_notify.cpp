// sd_notify readiness, watchdog pings and stop notice for systemd units.
#include "picksight/common/service_notify.hpp"

#include <systemd/sd-daemon.h>

#include <chrono>

#include "picksight/common/log.hpp"

namespace picksight {

ServiceNotifier::~ServiceNotifier() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
}

void ServiceNotifier::ready(const std::string& status) {
  // unset_environment = 0: the variables stay for the watchdog check below.
  const std::string message = "READY=1\nSTATUS=" + status;
  if (sd_notify(0, message.c_str()) < 0) logWarning("sd_notify READY failed");
  uint64_t usec = 0;
  // > 0 only when systemd asked this very process (WATCHDOG_PID) for pings.
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0 && !watchdog_.joinable()) {
    // Half the timeout, as sd_watchdog_enabled(3) recommends: one late
    // ping never kills a healthy service.
    watchdog_ = std::thread([this, usec] { pingLoop(usec / 2); });
  }
}

void ServiceNotifier::stopping() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (watchdog_.joinable()) watchdog_.join();
  sd_notify(0, "STOPPING=1");
}

void ServiceNotifier::pingLoop(unsigned long long interval_usec) {
  const auto interval = std::chrono::microseconds(interval_usec);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    lock.unlock();
    sd_notify(0, "WATCHDOG=1");
    lock.lock();
    wake_.wait_for(lock, interval, [this] { return stop_; });
  }
}

}  // namespace picksight
