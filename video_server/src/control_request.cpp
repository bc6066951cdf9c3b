// Which camera a control request names, and whether it may be answered on
// the control socket's thread.
#include "picksight/video_server/control_request.hpp"

namespace picksight::video {

std::optional<std::string> requestCamera(const proto::ControlRequest& request) {
  using R = proto::ControlRequest;
  switch (request.request_case()) {
    case R::kDescribeCamera:
      return request.describe_camera().camera();
    case R::kSetRoi:
      return request.set_roi().camera();
    case R::kSetSize:
      return request.set_size().camera();
    case R::kSetMode:
      return request.set_mode().camera();
    case R::kSetFormat:
      return request.set_format().camera();
    case R::kTrigger:
      return request.trigger().camera();
    case R::kListFeatures:
      return request.list_features().camera();
    case R::kGetFeature:
      return request.get_feature().camera();
    case R::kSetFeature:
      return request.set_feature().camera();
    case R::kOpenStream:
      return request.open_stream().camera();
    case R::kCloseStream:
      return request.close_stream().camera();
    case R::kSnap:
      return request.snap().camera();
    case R::kSetTarget:
      return request.set_target().camera();
    default:
      return std::nullopt;
  }
}

bool answeredAtOnce(const proto::ControlRequest& request) {
  using R = proto::ControlRequest;
  const auto kind = request.request_case();
  // Requests of no known kind are answered NOT_SUPPORTED without any work.
  return kind == R::kTrigger || kind == R::kListCameras || kind == R::kStatistics ||
         !requestCamera(request);
}

}  // namespace picksight::video
