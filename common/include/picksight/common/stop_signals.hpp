// How a PickSight service stops: SIGINT and SIGTERM are blocked in every
// thread (so none is interrupted mid-write) and the main thread waits for
// them; SIGPIPE is ignored, so a client that hangs up is an error value on
// its socket, never the end of the process.
#pragma once

#include <pthread.h>

#include <csignal>

namespace picksight {

class StopSignals {
 public:
  // Call before starting any thread: threads inherit the blocked set.
  StopSignals() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, nullptr);
    std::signal(SIGPIPE, SIG_IGN);
  }

  // Blocks until SIGINT or SIGTERM arrives; returns it.
  int wait() const {
    int sig = 0;
    sigwait(&set_, &sig);
    return sig;
  }

 private:
  sigset_t set_;
};

}  // namespace picksight
