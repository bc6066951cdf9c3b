// /metrics in the Prometheus text exposition format (version 0.0.4).
// A plain function over figures gathered by the caller.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "picksight/web/camera_monitor.hpp"
#include "picksight/web/result_feed.hpp"

namespace picksight::web {

struct AppFigures {
  std::string app;
  std::map<std::string, RequestFigures> requests;  // by request kind
};

std::string metricsText(const std::vector<CameraFigures>& cameras,
                        const std::vector<AppFigures>& apps);

// A label value with \, " and newlines escaped.
std::string escapeLabel(const std::string& value);

}  // namespace picksight::web
