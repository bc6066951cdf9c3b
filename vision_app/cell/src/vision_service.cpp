// Vision service: fresh frame, then recognition (or blob location) in
// sensor pixels; training and blob features on the same frames.
#include "picksight/cell/vision_service.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

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

cv::Mat greyImage(const Frame& frame) {
  if (frame.image.channels() != 3) return frame.image;
  cv::Mat grey;
  cv::cvtColor(frame.image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

std::vector<LocatedPart> locateInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                       const VisionOptions& options, const ModelList& models,
                                       int type, LocateScene* scene) {
  LocateScene local;
  LocateScene& s = scene ? *scene : local;
  s.mask = vision::binarize(grey, options.binarize);
  s.regions = vision::findRegions(s.mask, options.regions, grey);
  s.mapping = mapping;
  const auto& regions = s.regions;
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
      p.area = mapping.areaToSensor(r.area);
      p.holes = r.holes;
      parts.push_back(p);
    }
    return parts;
  }
  // LOCATE <type> costs the work of that type's models alone; LOCATE ALL
  // lets every model compete for every region, so that a part is reported
  // as the type that explains it best.
  std::vector<const vision::PartModel*> list;
  for (const auto& m : models)
    if (type < 0 || m.type == type) list.push_back(&m);
  for (const auto& match : vision::recognize(regions, list)) {
    LocatedPart p;
    const cv::Point2d s = mapping.toSensor(match.centroid);
    p.x = s.x;
    p.y = s.y;
    p.angle_deg = match.angle_deg;
    p.area = mapping.areaToSensor(regions[match.region].area);
    p.holes = regions[match.region].holes;
    p.type = match.model->type;
    p.score = match.score;
    p.symmetry_deg = match.symmetry_deg;
    p.region = static_cast<int>(match.region);
    p.touching = match.touching;
    parts.push_back(p);
  }
  return parts;
}

LocateOutcome locateInFrame(const Frame& frame, const VisionOptions& options,
                            std::shared_ptr<const ModelList> models, int type) {
  LocateOutcome outcome;
  outcome.frame = frame.info;
  outcome.scene.models = models ? std::move(models) : std::make_shared<const ModelList>();
  outcome.parts = locateInImage(greyImage(frame), frame.mapping, options, *outcome.scene.models,
                                type, &outcome.scene);
  return outcome;
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

Result<TargetOutcome> targetInImage(const cv::Mat& grey, const SensorMapping& mapping,
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
  t.moments = mapping.momentsToSensor(r.moments);
  const int margin = std::max(r.bbox.width, r.bbox.height) / 2 + 24;
  const cv::Rect around = (r.bbox + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                          cv::Rect(0, 0, grey.cols, grey.rows);
  t.image = grey(around).clone();  // the frame's pixels go with the frame
  t.image_origin = around.tl();
  t.mapping = mapping;
  t.image_centroid = r.centroid - cv::Point2d(around.tl());
  t.frame_area = r.area;
  return t;
}

VisionService::VisionService(std::unique_ptr<CameraLink> camera, VisionOptions options,
                             ModelLibrary* models)
    : camera_(std::move(camera)), options_(std::move(options)), models_(models) {}

void VisionService::start() { camera_->start(); }
void VisionService::stop() { camera_->stop(); }

Result<std::shared_ptr<const Frame>> VisionService::freshFrame() {
  auto fresh = camera_->freshFrame();
  if (fresh) {
    last_frame_ = (*fresh)->info;
    last_pixels_ = *fresh;
  }
  return fresh;
}

Result<LocateOutcome> VisionService::locate(int type) {
  const auto models = models_ ? models_->snapshot() : std::make_shared<const ModelList>();
  if (type >= 0 && !models->empty()) {
    bool known = false;
    for (const auto& m : *models) known = known || m.type == type;
    if (!known)
      return makeError(VisionErrc::kUnknownType,
                       "no model for type " + std::to_string(type) + " (see MODELS)");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  return locateInFrame(**frame, options_, models, type);
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
  const SensorMapping& mapping = (*frame)->mapping;
  auto features = blobsInImage(greyImage(**frame), options_);
  for (auto& f : features) {
    f.centroid = mapping.toSensor(f.centroid);
    f.angle_deg = mapping.directionToSensor(f.angle_deg);
    f.area = mapping.areaToSensor(f.area);
    f.perimeter = mapping.lengthToSensor(f.perimeter);
    f.bbox = mapping.boxToSensor(f.bbox);
  }
  return features;
}

Result<TargetOutcome> VisionService::target() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto outcome = targetInImage(greyImage(**frame), (*frame)->mapping, options_);
  if (outcome) outcome->frame = *last_frame_;
  return outcome;
}

Result<std::pair<cv::Mat, SensorMapping>> VisionService::greyFrame() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  return std::make_pair(greyImage(**frame).clone(), (*frame)->mapping);
}

std::optional<FrameInfo> VisionService::lastFrame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_frame_;
}

std::shared_ptr<const Frame> VisionService::lastFramePixels() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_pixels_;
}

}  // namespace picksight::app
