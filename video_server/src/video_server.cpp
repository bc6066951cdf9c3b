// Video server wiring and control request handling: handle() only
// dispatches, one function per request kind answers.
#include "picksight/video_server/video_server.hpp"

#include <cmath>
#include <stdexcept>

#include "picksight/common/log.hpp"
#include "picksight/video_server/control_errors.hpp"
#include "picksight/video_server/control_request.hpp"
#include "picksight/video_server/video_errors.hpp"

namespace picksight::video {

using transport::CurveServer;
using transport::frameHeaderOf;

namespace {
proto::AcquisitionMode toProto(AcquisitionMode m) {
  switch (m) {
    case AcquisitionMode::kTrigger:
      return proto::TRIGGER;
    case AcquisitionMode::kHardwareTrigger:
      return proto::HARDWARE_TRIGGER;
    default:
      return proto::FREERUN;
  }
}

// The snap of a camera waiting for a pulse waits as long as its trigger
// timeout says; the others this long, for a frame they were sent or stream
// anyway.
constexpr std::chrono::milliseconds kSnapTimeout{3000};

void fillFeature(const Feature& f, proto::Feature* out) {
  out->set_name(f.name);
  out->set_type(static_cast<proto::FeatureType>(static_cast<int>(f.type) + 1));
  out->set_value(f.value);
  out->set_has_range(f.has_range);
  out->set_min(f.min);
  out->set_max(f.max);
  out->set_increment(f.increment);
  for (const auto& c : f.choices) out->add_choices(c);
  out->set_unit(f.unit);
  out->set_description(f.description);
  out->set_writable(f.writable);
}

void fillSummary(const CameraStatus& s, proto::CameraSummary* out) {
  out->set_name(s.name);
  out->set_source(s.uri);
  out->set_state(s.state);
  out->set_mode(toProto(s.mode));
}
void fillSimulatedRobot(const SimulatedRobot& r, proto::SimulatedRobot* out);

proto::ControlReply okReply() {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);
  return reply;
}

// The ROI in sensor pixels and the output size the current settings give.
std::pair<cv::Rect, cv::Size> outputGeometry(const CameraStatus& s) {
  const cv::Rect roi = s.output.roi.empty()
                           ? cv::Rect(0, 0, s.info.sensor_width, s.info.sensor_height)
                           : s.output.roi;
  cv::Size out = s.output.size;
  if (out.empty()) {
    const double scale = s.output.scale > 0 ? s.output.scale : 1.0;
    out = cv::Size(static_cast<int>(std::lround(roi.width * scale)),
                   static_cast<int>(std::lround(roi.height * scale)));
  }
  return {roi, out};
}

proto::ControlReply describeCamera(Camera& camera) {
  const CameraStatus s = camera.status();
  proto::ControlReply reply = okReply();
  auto* d = reply.mutable_describe_camera();
  fillSummary(s, d->mutable_summary());
  d->set_vendor(s.info.vendor);
  d->set_model(s.info.model);
  d->set_serial(s.info.serial);
  d->set_sensor_width(static_cast<uint32_t>(s.info.sensor_width));
  d->set_sensor_height(static_cast<uint32_t>(s.info.sensor_height));
  const auto [roi, out] = outputGeometry(s);
  d->mutable_roi()->set_x(static_cast<uint32_t>(roi.x));
  d->mutable_roi()->set_y(static_cast<uint32_t>(roi.y));
  d->mutable_roi()->set_width(static_cast<uint32_t>(roi.width));
  d->mutable_roi()->set_height(static_cast<uint32_t>(roi.height));
  d->set_output_width(static_cast<uint32_t>(out.width));
  d->set_output_height(static_cast<uint32_t>(out.height));
  d->set_pixel_format(s.output.format == OutputFormat::kBgr8 ? proto::BGR8 : proto::MONO8);
  d->set_fps(s.fps_setting);
  for (const auto& f : s.info.formats) d->add_source_formats(f);
  d->set_trigger_line(s.hardware.input.line);
  d->set_trigger_activation(s.hardware.input.activation);
  d->set_trigger_timeout_ms(static_cast<uint32_t>(s.hardware.timeout.count()));
  // Only synthetic sources have one; the others answer kNotSupported.
  if (auto robot = camera.simulatedRobot())
    fillSimulatedRobot(*robot, d->mutable_simulated_robot());
  return reply;
}

// Applies `change` to the camera's output settings; a rejected setting is
// OUT_OF_RANGE and leaves the camera as it was.
proto::ControlReply changeOutput(Camera& camera,
                                 const std::function<void(OutputSettings&)>& change) {
  OutputSettings o = camera.output();
  change(o);
  if (auto ok = camera.setOutput(o); !ok) {
    return errorReply(ok.error());
  }
  return okReply();
}

proto::ControlReply setRoi(Camera& camera, const proto::SetRoiRequest& request) {
  return changeOutput(camera, [&r = request.roi()](OutputSettings& o) {
    o.roi = cv::Rect(static_cast<int>(r.x()), static_cast<int>(r.y()), static_cast<int>(r.width()),
                     static_cast<int>(r.height()));
    if (r.width() == 0 && r.height() == 0) o.roi = cv::Rect();  // back to the full sensor
  });
}

proto::ControlReply setSize(Camera& camera, const proto::SetSizeRequest& request) {
  return changeOutput(camera, [&request](OutputSettings& o) {
    o.size = cv::Size(static_cast<int>(request.width()), static_cast<int>(request.height()));
    o.scale = request.scale();
  });
}

proto::ControlReply setFormat(Camera& camera, const proto::SetFormatRequest& request) {
  const auto f = request.pixel_format();
  if (f != proto::MONO8 && f != proto::BGR8) {
    return errorReply(makeError(VideoErrc::kOutOfRange, "pixel format must be mono8 or bgr8"));
  }
  return changeOutput(camera, [f](OutputSettings& o) {
    o.format = f == proto::BGR8 ? OutputFormat::kBgr8 : OutputFormat::kMono8;
  });
}

proto::ControlReply setMode(Camera& camera, const proto::SetModeRequest& request) {
  std::optional<HardwareTrigger> hardware;
  AcquisitionMode mode = AcquisitionMode::kFreeRun;
  switch (request.mode()) {
    case proto::FREERUN:
      break;
    case proto::TRIGGER:
      mode = AcquisitionMode::kTrigger;
      break;
    case proto::HARDWARE_TRIGGER: {
      mode = AcquisitionMode::kHardwareTrigger;
      // Unset fields keep the defaults (Line1, the camera's edge, 10 s).
      HardwareTrigger h;
      if (!request.trigger_line().empty()) h.input.line = request.trigger_line();
      h.input.activation = request.trigger_activation();
      if (request.trigger_timeout_ms() > 0) {
        h.timeout = std::chrono::milliseconds(request.trigger_timeout_ms());
      }
      hardware = h;
      break;
    }
    default:
      return errorReply(
          makeError(VideoErrc::kOutOfRange, "mode must be freerun, trigger or hardware_trigger"));
  }
  if (auto ok = camera.setMode(mode, request.fps(), hardware); !ok) {
    return errorReply(ok.error());
  }
  return okReply();
}

proto::ControlReply trigger(Camera& camera) {
  const auto t = camera.trigger();
  if (!t) return errorReply(t.error());
  proto::ControlReply reply = okReply();
  reply.mutable_trigger()->set_sequence(t->sequence);
  reply.mutable_trigger()->set_triggered(t->triggered);
  reply.mutable_trigger()->set_mode(toProto(t->mode));
  if (t->mode == AcquisitionMode::kHardwareTrigger) {
    reply.mutable_trigger()->set_trigger_line(t->hardware.input.line);
    reply.mutable_trigger()->set_trigger_timeout_ms(
        static_cast<uint32_t>(t->hardware.timeout.count()));
  }
  return reply;
}

proto::ControlReply listFeatures(Camera& camera) {
  auto features = camera.features();
  if (!features) return errorReply(features.error());
  proto::ControlReply reply = okReply();
  auto* list = reply.mutable_list_features();
  for (const auto& f : *features) fillFeature(f, list->add_features());
  return reply;
}

// The feature as it now is, or the source's error.
proto::ControlReply featureReply(const Result<Feature>& f) {
  if (!f) return errorReply(f.error());
  proto::ControlReply reply = okReply();
  fillFeature(*f, reply.mutable_feature()->mutable_feature());
  return reply;
}

proto::ControlReply setOpen(Camera& camera, bool open) {
  camera.setOpen(open);
  return okReply();
}

proto::ControlReply snap(Camera& camera) {
  const std::string& name = camera.name();
  if (!camera.status().open_requested) {
    return errorReply(makeError(VideoErrc::kCameraClosed, "camera '" + name + "' is closed"));
  }
  const auto t = camera.trigger();
  if (!t) return errorReply(t.error());
  // The ticket's own mode: a mode change after it does not change its wait.
  const bool hardware = t->mode == AcquisitionMode::kHardwareTrigger;
  const std::chrono::milliseconds timeout = hardware ? t->hardware.timeout : kSnapTimeout;
  auto frame = camera.waitForFrame(t->sequence, timeout);
  if (!frame) {
    const std::string waited = " within " + std::to_string(timeout.count()) + " ms";
    if (hardware) {
      return errorReply(makeError(VideoErrc::kNoFrame, "no hardware trigger on " +
                                                           t->hardware.input.line + " of camera '" +
                                                           name + "'" + waited));
    }
    return errorReply(
        makeError(VideoErrc::kNoFrame, "no frame from camera '" + name + "'" + waited));
  }
  proto::ControlReply reply = okReply();
  auto* out = reply.mutable_snap();
  *out->mutable_header() = frameHeaderOf(*frame);
  const cv::Mat& img = frame->image;
  out->set_pixels(reinterpret_cast<const char*>(img.data), img.total() * img.elemSize());
  return reply;
}

void fillSimulatedRobot(const SimulatedRobot& r, proto::SimulatedRobot* out) {
  out->set_target_visible(r.target_visible);
  out->set_target_x_mm(r.target_x_mm);
  out->set_target_y_mm(r.target_y_mm);
  out->set_target_kind(r.target_kind);
  out->set_target_radius_mm(r.target_radius_mm);
  out->set_grid_rows(static_cast<uint32_t>(r.grid_rows));
  out->set_grid_cols(static_cast<uint32_t>(r.grid_cols));
  out->set_grid_pitch_mm(r.grid_pitch_mm);
  out->set_mm_per_px(r.mm_per_px);
  out->set_rz_deg(r.rz_deg);
  out->set_dx_mm(r.dx_mm);
  out->set_dy_mm(r.dy_mm);
  out->set_tilt_x_deg(r.tilt_x_deg);
  out->set_tilt_y_deg(r.tilt_y_deg);
  for (int i = 0; i < 9; ++i) out->add_robot_to_sensor(r.robot_to_sensor.val[i]);
}

proto::ControlReply setTarget(Camera& camera, const proto::SetTargetRequest& request) {
  std::optional<cv::Point2d> at_mm;
  if (!request.hide()) {
    const double x = request.x_mm();
    const double y = request.y_mm();
    if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x) > 1e6 || std::abs(y) > 1e6) {
      return errorReply(
          makeError(VideoErrc::kOutOfRange, "target x_mm and y_mm must be finite, within 1e6 mm"));
    }
    at_mm = cv::Point2d(x, y);
  }
  auto robot = camera.moveTarget(at_mm);
  if (!robot) return errorReply(robot.error());
  proto::ControlReply reply = okReply();
  fillSimulatedRobot(*robot, reply.mutable_simulated_robot());
  return reply;
}

proto::ControlReply notSupported() {
  return errorReply(makeError(VideoErrc::kNotSupported, "request not supported by this server"));
}
}  // namespace

VideoServer::VideoServer(const ServerConfig& config, const SourceFactory& make_source) {
  if (!config.curve_secret_key.empty()) {
    auto curve = CurveServer::start(context_, config.curve_secret_key, config.curve_allow_list);
    if (!curve) throw std::runtime_error("CURVE: " + curve.error().message);
    curve_ = std::move(*curve);
    frame_key_ = transport::newFrameKey();
    if (curve_->restricted()) {
      logInfo("CURVE: control encrypted and frames sealed; only the clients listed in ",
              config.curve_allow_list, " get in and get the frames' key");
    } else {
      logWarning(
          "CURVE: control encrypted and frames sealed, but without an allow-list every client "
          "that knows the server's public key gets in and gets the frames' key");
    }
  } else if (!config.curve_allow_list.empty()) {
    throw std::runtime_error("a CURVE allow-list needs the server's secret key as well");
  }
  // zmq::error_t alone ("Address already in use") would not say which endpoint.
  try {
    publisher_ =
        std::make_unique<FramePublisher>(context_, config.frames_endpoint, 8, 4, frame_key_);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("frames endpoint " + config.frames_endpoint + ": " + e.what());
  }
  for (const auto& c : config.cameras) {
    auto source = make_source(c.uri);
    if (!source) throw std::runtime_error("camera " + c.name + ": " + source.error().message);
    if (c.mode == AcquisitionMode::kHardwareTrigger && !(*source)->hardwareTrigger()) {
      throw std::runtime_error("camera " + c.name + ": mode hardware: " + c.uri +
                               " has no hardware trigger input");
    }
    cameras_.push_back(std::make_unique<Camera>(c, std::move(*source), *publisher_));
  }
  ControlServerOptions control_options;
  control_options.curve = curve_.get();
  try {
    control_ = std::make_unique<ControlServer>(
        context_, config.control_endpoint,
        [this](const proto::ControlRequest& r) { return handle(r); }, control_options);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("control endpoint " + config.control_endpoint + ": " + e.what());
  }
}

VideoServer::~VideoServer() { stop(); }

void VideoServer::start() {
  publisher_->start();
  for (auto& c : cameras_) c->start();
  control_->start();
}

void VideoServer::stop() {
  if (control_) control_->stop();
  for (auto& c : cameras_) c->stop();
  if (publisher_) publisher_->stop();
}

Camera* VideoServer::find(const std::string& name) {
  for (auto& c : cameras_) {
    if (c->name() == name) return c.get();
  }
  return nullptr;
}

proto::ControlReply VideoServer::listCameras() {
  proto::ControlReply reply = okReply();
  auto* list = reply.mutable_list_cameras();
  for (auto& c : cameras_) fillSummary(c->status(), list->add_cameras());
  return reply;
}

proto::ControlReply VideoServer::statistics(const proto::StatisticsRequest& request) {
  const std::string& only = request.camera();
  if (!only.empty() && !find(only)) {
    return errorReply(makeError(VideoErrc::kUnknownCamera, "unknown camera '" + only + "'"));
  }
  proto::ControlReply reply = okReply();
  auto* stats = reply.mutable_statistics();
  stats->set_subscribers(static_cast<uint32_t>(publisher_->subscribers()));
  for (auto& c : cameras_) {
    if (!only.empty() && c->name() != only) continue;
    const CameraStatus s = c->status();
    const PublisherCounters counters = publisher_->counters(s.name);
    auto* cs = stats->add_cameras();
    cs->set_camera(s.name);
    cs->set_frames_acquired(s.frames_acquired);
    cs->set_frames_published(counters.published);
    cs->set_frames_dropped(counters.dropped);
    cs->set_acquisition_errors(s.acquisition_errors);
    cs->set_reconnects(s.reconnects);
    cs->set_fps(s.fps_measured);
    cs->set_last_sequence(s.last_sequence);
    cs->set_state(s.state);
    cs->set_last_error(s.last_error);
    cs->set_driver_incomplete_buffers(s.driver.incomplete_buffers);
    cs->set_driver_missing_packets(s.driver.missing_packets);
    cs->set_driver_resent_packets(s.driver.resent_packets);
    cs->set_driver_underruns(s.driver.underruns);
    cs->set_driver_sequence_gaps(s.driver.sequence_gaps);
    cs->set_frames_skipped_stale(s.driver.skipped_stale);
    cs->set_frames_before_request(s.frames_before_request);
  }
  return reply;
}

proto::ControlReply VideoServer::handle(const proto::ControlRequest& request) {
  using R = proto::ControlRequest;
  if (request.request_case() == R::kListCameras) return listCameras();
  if (request.request_case() == R::kStatistics) return statistics(request.statistics());
  if (request.request_case() == R::kFrameKey) {
    // Only clients the control socket's CURVE admitted are asking.
    if (!frame_key_) {
      return errorReply(makeError(VideoErrc::kNotSupported,
                                  "frames are not sealed: this server runs without CURVE"));
    }
    proto::ControlReply reply;
    auto* k = reply.mutable_frame_key();
    k->set_key(frame_key_->key.data(), frame_key_->key.size());
    k->set_key_id(frame_key_->id);
    return reply;
  }

  // Every other request names one camera.
  const std::optional<std::string> name = requestCamera(request);
  if (!name) return notSupported();
  Camera* camera = find(*name);
  if (!camera)
    return errorReply(makeError(VideoErrc::kUnknownCamera, "unknown camera '" + *name + "'"));

  switch (request.request_case()) {
    case R::kDescribeCamera:
      return describeCamera(*camera);
    case R::kSetRoi:
      return setRoi(*camera, request.set_roi());
    case R::kSetSize:
      return setSize(*camera, request.set_size());
    case R::kSetFormat:
      return setFormat(*camera, request.set_format());
    case R::kSetMode:
      return setMode(*camera, request.set_mode());
    case R::kTrigger:
      return trigger(*camera);
    case R::kListFeatures:
      return listFeatures(*camera);
    case R::kGetFeature:
      return featureReply(camera->feature(request.get_feature().name()));
    case R::kSetFeature:
      return featureReply(
          camera->setFeature(request.set_feature().name(), request.set_feature().value()));
    case R::kOpenStream:
      return setOpen(*camera, true);
    case R::kCloseStream:
      return setOpen(*camera, false);
    case R::kSnap:
      return snap(*camera);
    case R::kSetTarget:
      return setTarget(*camera, request.set_target());
    default:
      return notSupported();
  }
}

}  // namespace picksight::video
