// Running a thread of the web server only on a core nothing else wants, for
// work done for browsers (JPEGs, results as JSON) that must never take a
// core from a vision pass.
//
// Threading: applies to the calling thread only.
#pragma once

#include <string>

namespace picksight::web {

// Puts the calling thread in SCHED_IDLE (allowed without privileges); a
// failure is logged, naming `what`, and only costs that guarantee.
void runAtIdlePriority(const std::string& what);

}  // namespace picksight::web
