// Vision service: fresh frame, then recognition (or blob location) in
// sensor pixels; training and blob features on the same frames.
#include "picksight/cell/vision_service.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "picksight/common/angles.hpp"

#include "picksight/vision/recognizer.hpp"

namespace picksight::app {

const char* errorName(VisionErrc e) {
  switch (e) {
    case VisionErrc::kNoTarget:
      return "no target";
    case VisionErrc::kSeveralTargets:
      return "several targets";
    case VisionErrc::kNotADisc:
      return "not a disc";
    case VisionErrc::kUnknownType:
      return "unknown type";
    case VisionErrc::kStorageFailed:
      return "storage failed";
  }
  return "unknown";
}

cv::Point2d FrameMapping::toSensor(cv::Point2d p) const {
  // Pixel centres are at integer coordinates in both frames.
  return {roi_x + (p.x + 0.5) / scale_x - 0.5, roi_y + (p.y + 0.5) / scale_y - 0.5};
}

double FrameMapping::directionToSensor(double deg) const {
  // A direction scales like a displacement: undo an anisotropic resize.
  const double a = deg * M_PI / 180.0;
  return normalizeDeg(std::atan2(std::sin(a) / scale_y, std::cos(a) / scale_x) * 180.0 / M_PI);
}

cv::Mat greyImage(const ReceivedFrame& frame) {
  cv::Mat grey = frame.image();
  if (grey.channels() == 3) {
    cv::Mat converted;
    cv::cvtColor(grey, converted, cv::COLOR_BGR2GRAY);
    grey = converted;
  }
  return grey;
}

FrameMapping frameMapping(const ReceivedFrame& frame) {
  const auto& h = frame.header;
  FrameMapping m;
  m.roi_x = h.roi_x();
  m.roi_y = h.roi_y();
  m.scale_x = h.scale_x() > 0 ? h.scale_x() : 1.0;
  m.scale_y = h.scale_y() > 0 ? h.scale_y() : 1.0;
  return m;
}

std::vector<LocatedPart> locateInImage(const cv::Mat& grey, const FrameMapping& mapping,
                                       const VisionOptions& options, const ModelList& models,
                                       int type, LocateScene* scene) {
  LocateScene local;
  LocateScene& s = scene ? *scene : local;
  s.mask = vision::binarize(grey, options.binarize);
  s.regions = vision::findRegions(s.mask, options.regions, grey);
  s.mapping = mapping;
  const auto& regions = s.regions;
  const double area_scale = 1.0 / (mapping.scale_x * mapping.scale_y);
  std::vector<LocatedPart> parts;
  if (models.empty()) {
    parts.reserve(regions.size());
    for (size_t i = 0; i < regions.size(); ++i) {
      const auto& r = regions[i];
      LocatedPart p;
      p.region = static_cast<int>(i);
      const cv::Point2d s = mapping.toSensor(r.centroid);
      p.x = s.x;
      p.y = s.y;
      p.angle_deg = mapping.directionToSensor(r.angle_deg);
      p.area = r.area * area_scale;
      p.holes = r.holes;
      parts.push_back(p);
    }
    return parts;
  }
  // Every model competes for every region, so that a part is reported as
  // the type that explains it best, then the requested type is kept.
  std::vector<const vision::PartModel*> list;
  for (const auto& m : models) list.push_back(&m);
  for (const auto& match : vision::recognize(regions, list)) {
    if (type >= 0 && match.model->type != type) continue;
    LocatedPart p;
    const cv::Point2d s = mapping.toSensor(match.centroid);
    p.x = s.x;
    p.y = s.y;
    p.angle_deg = match.angle_deg;
    p.area = regions[match.region].area * area_scale;
    p.holes = regions[match.region].holes;
    p.type = match.model->type;
    p.score = match.score;
    p.symmetry_deg = match.symmetry_deg;
    p.region = static_cast<int>(match.region);
    parts.push_back(p);
  }
  return parts;
}

std::vector<LocatedPart> locateParts(const ReceivedFrame& frame, const VisionOptions& options) {
  return locateInImage(greyImage(frame), frameMapping(frame), options, {}, -1);
}

std::vector<vision::BlobFeatures> blobsInImage(const cv::Mat& grey, const VisionOptions& options) {
  const auto regions =
      vision::findRegions(vision::binarize(grey, options.binarize), options.regions, grey);
  vision::FeatureOptions features;
  features.skeleton = false;
  std::vector<vision::BlobFeatures> out;
  out.reserve(regions.size());
  for (const auto& r : regions) out.push_back(vision::blobFeatures(r, features));
  return out;
}

Result<TargetOutcome> targetInImage(const cv::Mat& grey, const FrameMapping& mapping,
                                    const VisionOptions& options) {
  const auto regions =
      vision::findRegions(vision::binarize(grey, options.binarize), options.regions, grey);
  if (regions.empty()) return makeError(VisionErrc::kNoTarget, "no target found");
  if (regions.size() > 1) {
    return makeError(VisionErrc::kSeveralTargets,
                     "more than one target found (" + std::to_string(regions.size()) + " regions)");
  }
  const vision::Region& r = regions.front();
  TargetOutcome t;
  t.centroid = mapping.toSensor(r.centroid);
  // Moments in frame pixels to sensor pixels: x lengths grow by 1/scale_x.
  const double sx = mapping.scale_x, sy = mapping.scale_y;
  t.moments.m00 = r.moments.m00 / (sx * sy);
  t.moments.mu20 = r.moments.mu20 / (sx * sx * sx * sy);
  t.moments.mu02 = r.moments.mu02 / (sx * sy * sy * sy);
  t.moments.mu11 = r.moments.mu11 / (sx * sx * sy * sy);
  return t;
}

VisionService::VisionService(std::unique_ptr<CameraLink> camera, VisionOptions options,
                             ModelLibrary* models)
    : camera_(std::move(camera)), options_(std::move(options)), models_(models) {}

VisionService::VisionService(zmq::context_t& context, const std::string& frames_endpoint,
                             const std::string& control_endpoint, std::string camera,
                             VisionOptions options, ModelLibrary* models)
    : VisionService(std::make_unique<VideoServerCamera>(context, frames_endpoint, control_endpoint,
                                                        std::move(camera), options.frame_timeout),
                    options, models) {}

void VisionService::start() { camera_->start(); }
void VisionService::stop() { camera_->stop(); }

Result<std::shared_ptr<const ReceivedFrame>> VisionService::freshFrame() {
  auto fresh = camera_->freshFrame();
  if (!fresh) return fresh.error();
  const auto frame = *fresh;
  const auto& h = frame->header;
  last_frame_ = FrameInfo{h.camera(), h.sequence(), h.host_timestamp_ns(),
                          h.width(),  h.height(),   h.triggered()};
  return frame;
}

Result<LocateOutcome> VisionService::locate(int type) {
  const auto models = models_ ? models_->snapshot() : std::make_shared<const ModelList>();
  if (!models->empty()) {
    bool known = false;
    for (const auto& m : *models) known = known || m.type == type;
    if (!known)
      return makeError(VisionErrc::kUnknownType,
                       "no model for type " + std::to_string(type) + " (see MODELS)");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  LocateOutcome outcome;
  outcome.frame = *last_frame_;
  outcome.parts = locateInImage(greyImage(**frame), frameMapping(**frame), options_, *models, type,
                                &outcome.scene);
  outcome.scene.models = models;
  return outcome;
}

Result<vision::PartModel> VisionService::learn(int type, const std::string& name) {
  if (!models_) return makeError(VisionErrc::kStorageFailed, "no model library");
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  vision::TrainOptions train;
  train.binarize = options_.binarize;
  train.regions = options_.regions;
  auto trained = vision::trainModel(greyImage(**frame), type, name, train);
  if (!trained) return trained.error();
  auto stored = models_->store(*trained);
  if (!stored)
    return makeError(VisionErrc::kStorageFailed,
                     "cannot store the model: " + stored.error().message);
  return trained;
}

Result<std::vector<vision::BlobFeatures>> VisionService::blobs() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  const FrameMapping mapping = frameMapping(**frame);
  auto features = blobsInImage(greyImage(**frame), options_);
  const double linear = 1.0 / std::sqrt(mapping.scale_x * mapping.scale_y);
  for (auto& f : features) {
    f.centroid = mapping.toSensor(f.centroid);
    f.angle_deg = mapping.directionToSensor(f.angle_deg);
    f.area *= linear * linear;
    f.perimeter *= linear;
    const cv::Point2d tl = mapping.toSensor(cv::Point2d(f.bbox.x, f.bbox.y));
    f.bbox = cv::Rect(static_cast<int>(std::lround(tl.x)), static_cast<int>(std::lround(tl.y)),
                      static_cast<int>(std::lround(f.bbox.width / mapping.scale_x)),
                      static_cast<int>(std::lround(f.bbox.height / mapping.scale_y)));
  }
  return features;
}

Result<TargetOutcome> VisionService::target() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto outcome = targetInImage(greyImage(**frame), frameMapping(**frame), options_);
  if (outcome) outcome->frame = *last_frame_;
  return outcome;
}

Result<proto::ControlReply> VisionService::control(const proto::ControlRequest& request) {
  std::lock_guard<std::mutex> lock(mutex_);
  return camera_->control(request);
}

std::optional<FrameInfo> VisionService::lastFrame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_frame_;
}

}  // namespace picksight::app
