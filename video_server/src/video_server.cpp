// Video server wiring and control request handling.
#include "picksight/video_server/video_server.hpp"

#include <stdexcept>

#include "picksight/video_server/control_errors.hpp"

namespace picksight::video {
namespace {
proto::AcquisitionMode toProto(AcquisitionMode m) {
  return m == AcquisitionMode::kTrigger ? proto::TRIGGER : proto::FREERUN;
}

proto::ControlReply errorReply(proto::Error::Code code, const std::string& text) {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(code);
  reply.mutable_error()->set_text(text);
  return reply;
}

constexpr std::chrono::milliseconds kSnapTimeout{3000};

// Driver errors to the wire's, through the server's one table.
proto::ControlReply sourceErrorReply(const Error& e) { return video::errorReply(e); }

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
}  // namespace

VideoServer::VideoServer(const ServerConfig& config) {
  // zmq::error_t alone ("Address already in use") would not say which endpoint.
  try {
    publisher_ = std::make_unique<FramePublisher>(context_, config.frames_endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("frames endpoint " + config.frames_endpoint + ": " + e.what());
  }
  for (const auto& c : config.cameras) {
    auto source = makeSource(c.uri);
    if (!source) throw std::runtime_error("camera " + c.name + ": " + source.error().message);
    cameras_.push_back(std::make_unique<Camera>(c, std::move(*source), *publisher_));
  }
  try {
    control_ = std::make_unique<ControlServer>(
        context_, config.control_endpoint,
        [this](const proto::ControlRequest& r) { return handle(r); });
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

proto::ControlReply VideoServer::handle(const proto::ControlRequest& request) {
  using R = proto::ControlRequest;
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);

  if (request.request_case() == R::kListCameras) {
    auto* list = reply.mutable_list_cameras();
    for (auto& c : cameras_) fillSummary(c->status(), list->add_cameras());
    return reply;
  }
  if (request.request_case() == R::kStatistics) {
    auto* stats = reply.mutable_statistics();
    stats->set_subscribers(static_cast<uint32_t>(publisher_->subscribers()));
    const std::string& only = request.statistics().camera();
    if (!only.empty() && !find(only))
      return errorReply(proto::Error::UNKNOWN_CAMERA, "unknown camera '" + only + "'");
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
    }
    return reply;
  }

  // Every other request names one camera.
  std::string name;
  switch (request.request_case()) {
    case R::kDescribeCamera:
      name = request.describe_camera().camera();
      break;
    case R::kSetRoi:
      name = request.set_roi().camera();
      break;
    case R::kSetSize:
      name = request.set_size().camera();
      break;
    case R::kSetMode:
      name = request.set_mode().camera();
      break;
    case R::kSetFormat:
      name = request.set_format().camera();
      break;
    case R::kTrigger:
      name = request.trigger().camera();
      break;
    case R::kListFeatures:
      name = request.list_features().camera();
      break;
    case R::kGetFeature:
      name = request.get_feature().camera();
      break;
    case R::kSetFeature:
      name = request.set_feature().camera();
      break;
    case R::kOpenStream:
      name = request.open_stream().camera();
      break;
    case R::kCloseStream:
      name = request.close_stream().camera();
      break;
    case R::kSnap:
      name = request.snap().camera();
      break;
    default:
      return errorReply(proto::Error::NOT_SUPPORTED, "request not supported by this server");
  }
  Camera* camera = find(name);
  if (!camera) return errorReply(proto::Error::UNKNOWN_CAMERA, "unknown camera '" + name + "'");

  switch (request.request_case()) {
    case R::kDescribeCamera: {
      const CameraStatus s = camera->status();
      auto* d = reply.mutable_describe_camera();
      fillSummary(s, d->mutable_summary());
      d->set_vendor(s.info.vendor);
      d->set_model(s.info.model);
      d->set_serial(s.info.serial);
      d->set_sensor_width(static_cast<uint32_t>(s.info.sensor_width));
      d->set_sensor_height(static_cast<uint32_t>(s.info.sensor_height));
      const cv::Rect roi = s.output.roi.empty()
                               ? cv::Rect(0, 0, s.info.sensor_width, s.info.sensor_height)
                               : s.output.roi;
      d->mutable_roi()->set_x(static_cast<uint32_t>(roi.x));
      d->mutable_roi()->set_y(static_cast<uint32_t>(roi.y));
      d->mutable_roi()->set_width(static_cast<uint32_t>(roi.width));
      d->mutable_roi()->set_height(static_cast<uint32_t>(roi.height));
      cv::Size out = s.output.size;
      if (out.empty()) {
        const double scale = s.output.scale > 0 ? s.output.scale : 1.0;
        out = cv::Size(static_cast<int>(std::lround(roi.width * scale)),
                       static_cast<int>(std::lround(roi.height * scale)));
      }
      d->set_output_width(static_cast<uint32_t>(out.width));
      d->set_output_height(static_cast<uint32_t>(out.height));
      d->set_pixel_format(s.output.format == OutputFormat::kBgr8 ? proto::BGR8 : proto::MONO8);
      d->set_fps(s.fps_setting);
      for (const auto& f : s.info.formats) d->add_source_formats(f);
      return reply;
    }
    case R::kSetRoi: {
      OutputSettings o = camera->output();
      const auto& r = request.set_roi().roi();
      o.roi = cv::Rect(static_cast<int>(r.x()), static_cast<int>(r.y()),
                       static_cast<int>(r.width()), static_cast<int>(r.height()));
      if (r.width() == 0 && r.height() == 0) o.roi = cv::Rect();  // back to the full sensor
      if (auto ok = camera->setOutput(o); !ok)
        return errorReply(proto::Error::OUT_OF_RANGE, ok.error().message);
      return reply;
    }
    case R::kSetSize: {
      OutputSettings o = camera->output();
      const auto& s = request.set_size();
      o.size = cv::Size(static_cast<int>(s.width()), static_cast<int>(s.height()));
      o.scale = s.scale();
      if (auto ok = camera->setOutput(o); !ok)
        return errorReply(proto::Error::OUT_OF_RANGE, ok.error().message);
      return reply;
    }
    case R::kSetFormat: {
      OutputSettings o = camera->output();
      const auto f = request.set_format().pixel_format();
      if (f != proto::MONO8 && f != proto::BGR8) {
        return errorReply(proto::Error::OUT_OF_RANGE, "pixel format must be mono8 or bgr8");
      }
      o.format = f == proto::BGR8 ? OutputFormat::kBgr8 : OutputFormat::kMono8;
      if (auto ok = camera->setOutput(o); !ok)
        return errorReply(proto::Error::OUT_OF_RANGE, ok.error().message);
      return reply;
    }
    case R::kSetMode: {
      const auto& m = request.set_mode();
      if (m.mode() != proto::FREERUN && m.mode() != proto::TRIGGER) {
        return errorReply(proto::Error::OUT_OF_RANGE, "mode must be freerun or trigger");
      }
      const AcquisitionMode mode =
          m.mode() == proto::TRIGGER ? AcquisitionMode::kTrigger : AcquisitionMode::kFreeRun;
      if (auto ok = camera->setMode(mode, m.fps()); !ok)
        return errorReply(proto::Error::OUT_OF_RANGE, ok.error().message);
      return reply;
    }
    case R::kTrigger: {
      const TriggerTicket t = camera->trigger();
      reply.mutable_trigger()->set_sequence(t.sequence);
      reply.mutable_trigger()->set_triggered(t.triggered);
      return reply;
    }
    case R::kListFeatures: {
      auto features = camera->features();
      if (!features) return sourceErrorReply(features.error());
      auto* list = reply.mutable_list_features();
      for (const auto& f : *features) fillFeature(f, list->add_features());
      return reply;
    }
    case R::kGetFeature: {
      auto f = camera->feature(request.get_feature().name());
      if (!f) return sourceErrorReply(f.error());
      fillFeature(*f, reply.mutable_feature()->mutable_feature());
      return reply;
    }
    case R::kSetFeature: {
      const auto& set = request.set_feature();
      auto f = camera->setFeature(set.name(), set.value());
      if (!f) return sourceErrorReply(f.error());
      fillFeature(*f, reply.mutable_feature()->mutable_feature());
      return reply;
    }
    case R::kOpenStream:
      camera->setOpen(true);
      return reply;
    case R::kCloseStream:
      camera->setOpen(false);
      return reply;
    case R::kSnap: {
      if (!camera->status().open_requested) {
        return errorReply(proto::Error::CAMERA_UNAVAILABLE, "camera '" + name + "' is closed");
      }
      const TriggerTicket t = camera->trigger();
      auto frame = camera->waitForFrame(t.sequence, kSnapTimeout);
      if (!frame) {
        return errorReply(proto::Error::TIMEOUT, "no frame from camera '" + name + "' within " +
                                                     std::to_string(kSnapTimeout.count()) + " ms");
      }
      auto* snap = reply.mutable_snap();
      *snap->mutable_header() = frameHeaderOf(*frame);
      const cv::Mat& img = frame->image;
      snap->set_pixels(reinterpret_cast<const char*>(img.data), img.total() * img.elemSize());
      return reply;
    }
    default:
      return errorReply(proto::Error::NOT_SUPPORTED, "request not supported by this server");
  }
}

}  // namespace picksight::video
