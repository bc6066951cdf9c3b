// The camera poller and the camera actions.
#include "picksight/web/camera_monitor.hpp"

#include <algorithm>
#include <cctype>

#include "picksight/common/log.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {

using transport::ControlClient;

namespace {
using namespace std::chrono_literals;

// "freerun", "trigger" or "hardware": the wire enum's own name in the API's
// lower case, the hardware trigger's as POST .../mode takes it.
std::string modeName(proto::AcquisitionMode mode) {
  if (mode == proto::ACQUISITION_MODE_UNSPECIFIED) return "unknown";
  if (mode == proto::HARDWARE_TRIGGER) return "hardware";
  std::string name = proto::AcquisitionMode_Name(mode);
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return name;
}

}  // namespace

struct CameraMonitor::Server {
  Server(zmq::context_t& context, const VideoServerEndpoints& e)
      : endpoints(e), poller(context, e.control), actions(context, e.control) {}
  VideoServerEndpoints endpoints;
  ControlClient poller;  // poll thread only
  std::mutex actions_mutex;
  ControlClient actions;  // under actions_mutex
};

CameraMonitor::CameraMonitor(zmq::context_t& context, std::vector<VideoServerEndpoints> servers,
                             EventHub& events, int jpeg_quality)
    : context_(context), events_(events), jpeg_quality_(jpeg_quality) {
  for (const auto& s : servers) servers_.push_back(std::make_unique<Server>(context, s));
  thread_ = std::thread([this] { run(); });
}

CameraMonitor::~CameraMonitor() { stop(); }

void CameraMonitor::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    wake_.notify_all();
  }
  if (thread_.joinable()) thread_.join();
  std::map<std::string, std::shared_ptr<CameraFeed>> feeds;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    feeds.swap(feeds_);
  }
  for (auto& [name, feed] : feeds) feed->stop();
}

void CameraMonitor::pollServer(size_t index, std::map<std::string, CameraState>& found) {
  Server& server = *servers_[index];
  proto::ControlRequest list;
  list.mutable_list_cameras();
  auto listed = server.poller.call(list);
  if (!listed) {
    logDebug("video server ", server.endpoints.control, ": ", listed.error().message);
    return;  // its cameras vanish from the list until it answers again
  }
  proto::ControlRequest stats_request;
  stats_request.mutable_statistics();
  auto stats = server.poller.call(stats_request);
  for (const auto& summary : listed->list_cameras().cameras()) {
    CameraState state;
    state.server = index;
    state.summary = summary;
    {
      // Keep the last description when this poll's one fails (e.g. BUSY).
      std::lock_guard<std::mutex> lock(mutex_);
      auto old = cameras_.find(summary.name());
      if (old != cameras_.end() && old->second.server == index) {
        state.describe = old->second.describe;
        state.described = old->second.described;
      }
    }
    proto::ControlRequest describe;
    describe.mutable_describe_camera()->set_camera(summary.name());
    if (auto d = server.poller.call(describe)) {
      state.describe = d->describe_camera();
      state.described = true;
    }
    if (stats) {
      for (const auto& s : stats->statistics().cameras())
        if (s.camera() == summary.name()) state.statistics = s;
    }
    found.emplace(summary.name(), std::move(state));
  }
}

void CameraMonitor::run() {
  while (true) {
    std::map<std::string, CameraState> found;
    for (size_t i = 0; i < servers_.size(); ++i) pollServer(i, found);
    std::vector<std::shared_ptr<CameraFeed>> retired;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) break;
      cameras_ = std::move(found);
      for (const auto& [name, state] : cameras_) {
        const std::string& endpoint = servers_[state.server]->endpoints.frames;
        auto feed = feeds_.find(name);
        if (feed != feeds_.end() && feed->second->framesEndpoint() == endpoint) continue;
        if (feed != feeds_.end()) retired.push_back(feed->second);
        feeds_[name] = std::make_shared<CameraFeed>(context_, endpoint, name, jpeg_quality_);
      }
    }
    for (auto& feed : retired) feed->stop();
    events_.publish("cameras", cameras().dump());
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, 1s, [&] { return stopping_ || refresh_; });
    refresh_ = false;
    if (stopping_) break;
  }
}

nlohmann::json CameraMonitor::cameraJson(const CameraState& s) const {
  const auto& d = s.describe;
  const auto& st = s.statistics;
  // The effective ROI (the video server says 0 for "full sensor").
  const uint32_t roi_w = d.roi().width() ? d.roi().width() : d.sensor_width();
  const uint32_t roi_h = d.roi().height() ? d.roi().height() : d.sensor_height();
  double scale_x = roi_w ? static_cast<double>(d.output_width()) / roi_w : 1.0;
  double scale_y = roi_h ? static_cast<double>(d.output_height()) / roi_h : 1.0;
  uint32_t width = d.output_width();
  uint32_t height = d.output_height();
  auto feed = feeds_.find(s.summary.name());
  if (feed != feeds_.end()) {
    if (auto frame = feed->second->latest()) {
      // The newest frame's own mapping is the one to draw over it.
      scale_x = frame->mapping.scale_x;
      scale_y = frame->mapping.scale_y;
      width = frame->info.width;
      height = frame->info.height;
    }
  }
  return {{"name", s.summary.name()},
          {"source", s.summary.source()},
          {"state", st.state().empty() ? s.summary.state() : st.state()},
          {"mode", modeName(s.summary.mode())},
          {"width", width},
          {"height", height},
          {"sensor_width", d.sensor_width()},
          {"sensor_height", d.sensor_height()},
          {"roi", {{"x", d.roi().x()}, {"y", d.roi().y()}, {"width", roi_w}, {"height", roi_h}}},
          {"scale_x", scale_x},
          {"scale_y", scale_y},
          {"fps", st.fps()},
          {"frames", st.frames_published()},
          {"drops", st.frames_dropped()},
          {"reconnects", st.reconnects()},
          {"last_error", st.last_error()},
          {"sequence", st.last_sequence()},
          {"simulated_robot", d.has_simulated_robot()},
          {"trigger_line", d.trigger_line()},
          {"trigger_activation", d.trigger_activation()},
          {"trigger_timeout_ms", d.trigger_timeout_ms()}};
}

nlohmann::json CameraMonitor::cameras() const {
  std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [name, state] : cameras_) list.push_back(cameraJson(state));
  return list;
}

std::vector<CameraFigures> CameraMonitor::figures() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<CameraFigures> out;
  for (const auto& [name, state] : cameras_) {
    CameraFigures f;
    f.camera = name;
    f.frames = state.statistics.frames_published();
    f.drops = state.statistics.frames_dropped();
    f.fps = state.statistics.fps();
    auto feed = feeds_.find(name);
    if (feed != feeds_.end()) {
      f.viewers = feed->second->viewers();
      f.encode_seconds = feed->second->encodeSeconds();
    }
    out.push_back(f);
  }
  return out;
}

std::shared_ptr<CameraFeed> CameraMonitor::feed(const std::string& camera) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = feeds_.find(camera);
  return it == feeds_.end() ? nullptr : it->second;
}

Result<proto::ControlReply> CameraMonitor::control(const std::string& camera,
                                                   const proto::ControlRequest& request) {
  size_t index = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = cameras_.find(camera);
    if (it == cameras_.end()) return makeError(WebErrc::kNotFound, "no camera '" + camera + "'");
    index = it->second.server;
  }
  Server& server = *servers_[index];
  auto reply = [&] {
    std::lock_guard<std::mutex> lock(server.actions_mutex);
    return server.actions.call(request);
  }();
  if (reply) {
    std::lock_guard<std::mutex> lock(mutex_);
    refresh_ = true;
    wake_.notify_all();
  }
  return reply;
}

}  // namespace picksight::web
