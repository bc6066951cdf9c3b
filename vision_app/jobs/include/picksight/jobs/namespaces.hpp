// Until the vision app's cell, store and protocol libraries leave the
// namespace they shared (picksight::app) for their own, the jobs library
// names their types by the namespaces they are moving to; these
// directives make those names resolve meanwhile, and go with the move.
#pragma once

namespace picksight::app {}
namespace picksight::store {
using namespace ::picksight::app;
}
namespace picksight::cell {
using namespace ::picksight::app;
}
namespace picksight::protocol {
using namespace ::picksight::app;
}
