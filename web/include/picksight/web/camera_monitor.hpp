// The cameras of the cell's video servers, as the page and /metrics see them:
// one thread polls every control socket once a second (ListCameras,
// DescribeCamera, Statistics: the same load whatever the number of
// browsers), starts a CameraFeed for each camera it finds, and publishes the
// list as an `event: cameras`. Camera actions from the page go through
// control(), one client per video server under a mutex, apart from the
// poller's, so a slow action never delays the list.
//
// Threading: the poll thread owns its ControlClients; everything readable
// from HTTP threads is under mutex_ or atomic.
#pragma once

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/web/camera_feed.hpp"
#include "picksight/web/event_hub.hpp"
#include "picksight/web/web_options.hpp"

namespace picksight::web {

// Figures of one camera for /metrics.
struct CameraFigures {
  std::string camera;
  uint64_t frames = 0;
  uint64_t drops = 0;
  double fps = 0;
  int viewers = 0;
  double encode_seconds = 0;
};

class CameraMonitor {
 public:
  CameraMonitor(zmq::context_t& context, std::vector<VideoServerEndpoints> servers,
                EventHub& events, int jpeg_quality);
  ~CameraMonitor();  // stops the poller and the feeds
  CameraMonitor(const CameraMonitor&) = delete;
  CameraMonitor& operator=(const CameraMonitor&) = delete;

  // The /api/cameras array.
  nlohmann::json cameras() const;
  std::vector<CameraFigures> figures() const;
  // The feed of `camera`, null when no video server has it.
  std::shared_ptr<CameraFeed> feed(const std::string& camera) const;

  // Sends a control request to the video server of `camera` (kNotFound when
  // none has it); the reply or the server's error (ControlErrc). A request
  // that succeeded makes the poller refresh the list at once.
  Result<proto::ControlReply> control(const std::string& camera,
                                      const proto::ControlRequest& request);

  void stop();

 private:
  struct Server;
  struct CameraState {
    size_t server = 0;
    proto::CameraSummary summary;
    proto::DescribeCameraReply describe;
    bool described = false;
    proto::CameraStatistics statistics;
  };

  void run();
  void pollServer(size_t index, std::map<std::string, CameraState>& found);
  nlohmann::json cameraJson(const CameraState& state) const;

  zmq::context_t& context_;
  EventHub& events_;
  const int jpeg_quality_;
  std::vector<std::unique_ptr<Server>> servers_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;                                     // under mutex_
  bool refresh_ = false;                                      // under mutex_
  std::map<std::string, CameraState> cameras_;                // under mutex_
  std::map<std::string, std::shared_ptr<CameraFeed>> feeds_;  // under mutex_
  std::thread thread_;
};

}  // namespace picksight::web
