// The vision work behind robot requests: get a frame taken after the
// request from the camera link (a software trigger, or the next free-run
// frame), find the parts (recognize trained types, or every region when no
// model exists) or the calibration target, and express them in sensor pixels.
//
// Threading: every request method may be called from any connection thread;
// requests are served one at a time (they share the control socket and the CPU).
#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "picksight/camera_link/camera_link.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/common/result.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/vision/binarize.hpp"
#include "picksight/vision/blob_features.hpp"
#include "picksight/vision/part_model.hpp"
#include "picksight/vision/regions.hpp"

namespace picksight::app {

// Why a vision request failed (besides the camera link's CameraErrc and
// training's vision::PartModelErrc).
enum class VisionErrc {
  kNoTarget = 1,    // STORE, CALCAM: no target in the frame
  kSeveralTargets,  // STORE, CALCAM: more than one
  kNotADisc,        // CALCAM: the target is not a disc
  kUnknownType,     // no model for that type
  kStorageFailed,   // a model file could not be written or removed
};
const char* errorName(VisionErrc e);
PICKSIGHT_ERROR_DOMAIN(VisionErrc, "vision")

struct LocatedPart {
  double x = 0;  // sensor pixels
  double y = 0;
  // Recognized part: rotation from the trained pose, [0, symmetry_deg).
  // Region (no models): direction of its axis, [0, 360), image axes.
  double angle_deg = 0;
  double area = 0;  // sensor pixels
  int holes = 0;
  int type = -1;              // -1: a region, no model
  double score = 0;           // verified boundary fraction
  double symmetry_deg = 360;  // period of angle_deg (0: any)
  int region = -1;            // index into the scene's regions
  bool touching = false;      // found inside a blob shared with other parts
};

// What a location saw beyond the parts: the binary mask and the regions
// (frame pixels), for grasp clearance.
struct LocateScene {
  cv::Mat mask;  // CV_8UC1, non-zero = part
  std::vector<vision::Region> regions;
  SensorMapping mapping;
  std::shared_ptr<const ModelList> models;  // the models the parts refer to
};

struct LocateOutcome {
  FrameInfo frame;
  std::vector<LocatedPart> parts;  // best (or largest) first
  LocateScene scene;
};

// The single calibration target in a frame, in sensor pixels.
struct TargetOutcome {
  FrameInfo frame;
  cv::Point2d centroid;
  // Area and central second moments (m00, mu20, mu11, mu02), grey-level
  // weighted, in sensor pixels.
  cv::Moments moments;
  // A copy of the grey frame around it (its top-left at `image_origin` in
  // frame pixels), the region's centroid in that copy and its area, for
  // sub-pixel measurement of its edges.
  cv::Mat image;
  cv::Point image_origin;
  SensorMapping mapping;
  cv::Point2d image_centroid;
  double frame_area = 0;
};

struct VisionOptions {
  vision::BinarizeOptions binarize;
  vision::RegionOptions regions;
  std::chrono::milliseconds frame_timeout{3000};
};

// The frame's image as 8-bit grey: the image itself, or a converted copy.
cv::Mat greyImage(const Frame& frame);

// LOCATE on one frame, as the robot server, the offline tool and the
// benchmarks run it: the parts of `type` (-1: all types) recognized with
// `models` (every region when there are none), with the scene kept for
// grasp selection. The outcome's frame info is the frame's.
LocateOutcome locateInFrame(const Frame& frame, const VisionOptions& options,
                            std::shared_ptr<const ModelList> models, int type);

// Finds parts in a grey image: with `models` non-empty, the recognized parts
// of type `type` (-1: all types), best first, recognized with that type's
// models alone (LOCATE ALL: every model competes); with none, every region,
// largest first.
// With `scene`, also keeps the mask and regions there.
std::vector<LocatedPart> locateInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                       const VisionOptions& options, const ModelList& models,
                                       int type, LocateScene* scene = nullptr);

// The single region of a grey image as a calibration target.
Result<TargetOutcome> targetInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                    const VisionOptions& options);

// Blob features of every region of a grey image (skeleton left out).
std::vector<vision::BlobFeatures> blobsInImage(const cv::Mat& grey, const VisionOptions& options);

class VisionService {
 public:
  // `models` (borrowed, may be null: no recognition) outlives the service.
  VisionService(std::unique_ptr<CameraLink> camera, VisionOptions options,
                ModelLibrary* models = nullptr);

  void start();
  void stop();

  // The parts of `type` (-1: of every trained type) in a frame taken after
  // this call (every region when no model exists; VisionErrc::kUnknownType
  // when models exist but none of `type`).
  Result<LocateOutcome> locate(int type);
  // Trains type `type` from the single part in a fresh frame and stores it.
  Result<vision::PartModel> learn(int type, const std::string& name);
  // Blob features of every region in a fresh frame, sensor pixels.
  Result<std::vector<vision::BlobFeatures>> blobs();
  // The single calibration target in a fresh frame.
  Result<TargetOutcome> target();
  // A fresh frame's grey pixels (a copy the caller owns) and their mapping
  // to sensor pixels, for measurements that need the whole image (a grid of
  // calibration dots).
  Result<std::pair<cv::Mat, SensorMapping>> greyFrame();
  // Runs `fn(CameraLink&)` between requests (camera settings: they share
  // the link's control socket with the triggers) and returns its result.
  template <typename Fn>
  auto withCamera(Fn&& fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    return fn(*camera_);
  }
  uint64_t framesReceived() const { return camera_->framesReceived(); }
  ModelLibrary* models() const { return models_; }
  // The frame the last request worked on.
  std::optional<FrameInfo> lastFrame() const;
  // That frame itself (null before any), for the results stream's regions
  // of requests that keep none: kept until the next request.
  std::shared_ptr<const Frame> lastFramePixels() const;
  const std::string& camera() const { return camera_->camera(); }
  const VisionOptions& options() const { return options_; }

 private:
  // Call with mutex_ held.
  Result<std::shared_ptr<const Frame>> freshFrame();

  const std::unique_ptr<CameraLink> camera_;
  const VisionOptions options_;
  ModelLibrary* const models_;

  mutable std::mutex mutex_;  // serializes requests; guards camera_ calls and last_frame_
  std::optional<FrameInfo> last_frame_;
  std::shared_ptr<const Frame> last_pixels_;
};

}  // namespace picksight::app

PICKSIGHT_ERROR_ENUM(picksight::app::VisionErrc)
