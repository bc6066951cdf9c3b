// SCHED_IDLE for the web server's threads that work for browsers.
#include "picksight/web/idle_priority.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

#include "picksight/common/log.hpp"

namespace picksight::web {

// Nice alone does not do it: a nice 19 thread still gets its share of a busy
// core, and preempts a vision thread when it wakes.
void runAtIdlePriority(const std::string& what) {
  sched_param param{};
  param.sched_priority = 0;
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param); rc != 0)
    logWarning(what, " at normal priority: ", std::strerror(rc));
}

}  // namespace picksight::web
