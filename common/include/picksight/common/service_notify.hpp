// Tells systemd (Type=notify units) that a service is ready, alive and
// stopping, through libsystemd's sd_notify. Without systemd (NOTIFY_SOCKET
// unset) every call does nothing, so the services run unchanged by hand.
#pragma once

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace picksight {

// Threads: ready() and stopping() are called by the main thread; the
// watchdog thread is started by ready() when the unit has WatchdogSec= set
// (WATCHDOG_USEC for this process) and joined by stopping() or the
// destructor. The pings say the process is scheduled and not wedged in
// start-up or shutdown; a crash or an abort is systemd's Restart= business.
class ServiceNotifier {
 public:
  ServiceNotifier() = default;
  ~ServiceNotifier();
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;

  // READY=1 with a one-line STATUS=; call once the sockets are bound.
  void ready(const std::string& status);
  // STOPPING=1, and the watchdog pings end.
  void stopping();

 private:
  void pingLoop(unsigned long long interval_usec);

  std::thread watchdog_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;  // under mutex_
};

}  // namespace picksight
