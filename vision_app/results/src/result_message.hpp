// A request record as the results stream's VisionResult (proto/results.proto),
// every coordinate in sensor pixels. Private to picksight_results.
#pragma once

#include <cstdint>
#include <string>

#include "picksight/results/request_record.hpp"
#include "results.pb.h"

namespace picksight::results {

// Fills `out` (cleared first). Runs on the publisher thread: the regions of
// requests other than LOCATE are found here, from the record's frame.
void buildVisionResult(const RequestRecord& record, const std::string& app, uint64_t request_id,
                       proto::VisionResult& out);

}  // namespace picksight::results
