// Which camera a control request names, whether it may be answered on the
// control socket's thread, and the bounds every request is checked against.
#include "picksight/video_server/control_request.hpp"

#include <charconv>
#include <cmath>
#include <string_view>

#include "picksight/common/text.hpp"
#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/frame_pipeline.hpp"
#include "picksight/video_server/video_errors.hpp"

namespace picksight::video {

using transport::kMaxControlRequestBytes;

namespace {

// "nan", "-inf", "Infinity"...: text a driver would read as a non-finite number.
bool spellsNonFinite(std::string_view text) {
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) text.remove_prefix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && ptr == text.data() + text.size() && !std::isfinite(value);
}

Result<void> checkName(const std::string& name, const char* field) {
  if (name.size() <= kMaxControlName) return {};
  return makeError(VideoErrc::kBadRequest, std::string(field) + " is " +
                                               std::to_string(name.size()) + " bytes long (limit " +
                                               std::to_string(kMaxControlName) + ")");
}

// The number as the client sent it, non-finite values included.
std::string shown(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return formatFixed(v, 3);
}

Result<void> checkNumbers(const proto::ControlRequest& request) {
  using R = proto::ControlRequest;
  switch (request.request_case()) {
    case R::kSetMode: {
      const auto& m = request.set_mode();
      const double fps = m.fps();
      // 0 leaves the rate as it is.
      if (!(fps >= 0 && fps <= kMaxFps)) {
        return makeError(VideoErrc::kOutOfRange, "set_mode.fps must be 0 (unchanged) or in (0, " +
                                                     shown(kMaxFps) + "], got " + shown(fps));
      }
      if (auto ok = checkName(m.trigger_line(), "set_mode.trigger_line"); !ok) return ok;
      if (!m.trigger_activation().empty() && !isTriggerActivation(m.trigger_activation())) {
        return makeError(VideoErrc::kOutOfRange,
                         std::string("set_mode.trigger_activation must be one of ") +
                             kTriggerActivations + ", got '" +
                             m.trigger_activation().substr(0, kMaxControlName) + "'");
      }
      if (m.trigger_timeout_ms() > kMaxTriggerTimeout.count()) {
        return makeError(VideoErrc::kOutOfRange, "set_mode.trigger_timeout_ms must be at most " +
                                                     std::to_string(kMaxTriggerTimeout.count()) +
                                                     ", got " +
                                                     std::to_string(m.trigger_timeout_ms()));
      }
      return {};
    }
    case R::kSetSize: {
      const double scale = request.set_size().scale();
      if (!(scale >= 0 && scale <= kMaxOutputScale)) {
        return makeError(VideoErrc::kOutOfRange, "set_size.scale must be 0 (none) or in (0, " +
                                                     shown(kMaxOutputScale) + "], got " +
                                                     shown(scale));
      }
      return {};
    }
    case R::kSetFeature: {
      const auto& f = request.set_feature();
      if (auto ok = checkName(f.name(), "set_feature.name"); !ok) return ok;
      if (f.value().size() > kMaxControlValue) {
        return makeError(VideoErrc::kBadRequest,
                         "set_feature.value is " + std::to_string(f.value().size()) +
                             " bytes long (limit " + std::to_string(kMaxControlValue) + ")");
      }
      if (spellsNonFinite(f.value())) {
        return makeError(VideoErrc::kOutOfRange, "set_feature.value of " + f.name() +
                                                     " must be a finite number, got '" + f.value() +
                                                     "'");
      }
      return {};
    }
    case R::kGetFeature:
      return checkName(request.get_feature().name(), "get_feature.name");
    default:
      return {};
  }
}
}  // namespace

Result<proto::ControlRequest> decodeRequest(const void* data, size_t size) {
  if (size > kMaxControlRequestBytes) {
    return makeError(VideoErrc::kBadRequest, "control request of " + std::to_string(size) +
                                                 " bytes (limit " +
                                                 std::to_string(kMaxControlRequestBytes) + ")");
  }
  proto::ControlRequest request;
  // The size check above keeps the int cast exact.
  if (!request.ParseFromArray(data, static_cast<int>(size)) ||
      request.request_case() == proto::ControlRequest::REQUEST_NOT_SET) {
    return makeError(VideoErrc::kBadRequest, "malformed or empty control request");
  }
  const std::optional<std::string> camera = requestCamera(request);
  if (camera) {
    if (auto ok = checkName(*camera, "camera"); !ok) return ok.error();
  } else if (request.has_statistics()) {
    if (auto ok = checkName(request.statistics().camera(), "camera"); !ok) return ok.error();
  }
  if (auto ok = checkNumbers(request); !ok) return ok.error();
  return request;
}

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
