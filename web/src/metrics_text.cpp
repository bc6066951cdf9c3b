// The Prometheus text of the web server's figures.
#include "picksight/web/metrics_text.hpp"

#include <sstream>

#include "picksight/common/text.hpp"

namespace picksight::web {
namespace {

// Numbers as Prometheus reads them, whatever the locale.
std::string num(double v) { return formatFixed(v, 6); }

void family(std::ostringstream& out, const char* name, const char* type, const char* help) {
  out << "# HELP " << name << " " << help << "\n# TYPE " << name << " " << type << "\n";
}

}  // namespace

std::string escapeLabel(const std::string& value) {
  std::string out;
  for (char c : value) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

std::string metricsText(const std::vector<CameraFigures>& cameras,
                        const std::vector<AppFigures>& apps) {
  std::ostringstream out;
  struct CameraSeries {
    const char* name;
    const char* type;
    const char* help;
    std::string (*value)(const CameraFigures&);
  };
  static const CameraSeries kCameraSeries[] = {
      {"picksight_camera_frames_total", "counter", "Frames the video server published.",
       [](const CameraFigures& c) { return std::to_string(c.frames); }},
      {"picksight_camera_drops_total", "counter", "Frames the video server's publisher dropped.",
       [](const CameraFigures& c) { return std::to_string(c.drops); }},
      {"picksight_camera_fps", "gauge", "Measured frame rate.",
       [](const CameraFigures& c) { return num(c.fps); }},
      {"picksight_web_viewers", "gauge", "MJPEG streams open on the camera.",
       [](const CameraFigures& c) { return std::to_string(c.viewers); }},
      {"picksight_web_jpeg_encode_seconds_total", "counter",
       "CPU seconds spent encoding the camera's JPEGs.",
       [](const CameraFigures& c) { return num(c.encode_seconds); }},
  };
  for (const auto& series : kCameraSeries) {
    family(out, series.name, series.type, series.help);
    for (const auto& c : cameras)
      out << series.name << "{camera=\"" << escapeLabel(c.camera) << "\"} " << series.value(c)
          << "\n";
  }
  family(out, "picksight_vision_results_total", "counter", "Vision results received.");
  for (const auto& a : apps)
    for (const auto& [request, f] : a.requests)
      out << "picksight_vision_results_total{app=\"" << escapeLabel(a.app) << "\",request=\""
          << escapeLabel(request) << "\"} " << f.count << "\n";
  family(out, "picksight_vision_request_seconds", "histogram",
         "Time from a vision request to its reply (the result's elapsed_ms).");
  for (const auto& a : apps) {
    for (const auto& [request, f] : a.requests) {
      const std::string labels =
          "app=\"" + escapeLabel(a.app) + "\",request=\"" + escapeLabel(request) + "\"";
      for (size_t i = 0; i < kRequestBuckets.size(); ++i)
        out << "picksight_vision_request_seconds_bucket{" << labels << ",le=\""
            << formatFixed(kRequestBuckets[i], 4) << "\"} " << f.buckets[i] << "\n";
      out << "picksight_vision_request_seconds_bucket{" << labels << ",le=\"+Inf\"} " << f.count
          << "\n";
      out << "picksight_vision_request_seconds_sum{" << labels << "} " << num(f.seconds_sum)
          << "\n";
      out << "picksight_vision_request_seconds_count{" << labels << "} " << f.count << "\n";
    }
  }
  return out.str();
}

}  // namespace picksight::web
