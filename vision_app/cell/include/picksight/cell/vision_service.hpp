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
#include <string_view>
#include <vector>

#include "picksight/common/frame.hpp"
#include "picksight/common/result.hpp"
#include "picksight/link/camera_link.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::cell {

class ScaledModelCache;

// Why a request VisionService serves failed (besides the camera link's
// link::CameraErrc and training's vision::PartModelErrc). Its domain keeps the
// name "vision" it has always had in messages.
enum class VisionServiceErrc {
  kNoTarget = 1,             // STORE, CALCAM: no target in the frame
  kSeveralTargets,           // STORE, CALCAM: more than one
  kNotADisc,                 // CALCAM: the target is not a disc
  kUnknownType,              // no model for that type
  kStorageFailed,            // a model file could not be written or removed
  kOutsideFrame,             // LEARN AT: the rectangle holds no pixel of the frame
  kNoPartInRectangle,        // LEARN AT: no part inside the rectangle
  kSeveralPartsInRectangle,  // LEARN AT: more than one
  kViewRefused,              // LEARNVIEW: the view cannot refine the model
};
const char* errorName(VisionServiceErrc e);
PICKSIGHT_ERROR_DOMAIN(VisionServiceErrc, "vision")

struct LocatedPart {
  double x = 0;  // sensor pixels
  double y = 0;
  // Recognized part: rotation from the trained pose, the turn nearest it in
  // (-symmetry_deg / 2, symmetry_deg / 2] (vision::reportedTurnDeg).
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

// A region that passed every test of the asked type's model, left out of
// `LOCATE <type>` because it is clearly closer to another type's model.
struct ScreenedRegion {
  int region = -1;  // index into the scene's regions
  int closer_type = -1;
};

// What a location saw beyond the parts: the binary mask and the regions
// (frame pixels), for grasp clearance.
struct LocateScene {
  cv::Mat mask;  // CV_8UC1, non-zero = part
  std::vector<vision::Region> regions;
  SensorMapping mapping;
  std::shared_ptr<const store::ModelList> models;  // the models the parts refer to
  std::vector<ScreenedRegion> screened_out;
};

struct VisionOptions;

struct LocateOutcome {
  FrameInfo frame;
  std::vector<LocatedPart> parts;  // best (or largest) first
  LocateScene scene;
  // The vision settings it ran with (VisionService: the snapshot it read;
  // null from locateInFrame alone): what its record publishes, whatever
  // VISION changed since.
  std::shared_ptr<const VisionOptions> settings;
  // The frame itself (VisionService::locate; null from locateInFrame
  // alone), for the filmstrip: taken by the request, never kept with the
  // outcome (results::locateRecord releases it).
  std::shared_ptr<const Frame> pixels;
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
  // LOCATE's smallest region follows the trained models (speckAreaFor) when
  // the user did not set one: regions.min_area is then only its floor.
  bool min_area_follows_models = true;
  std::chrono::milliseconds frame_timeout{3000};
};

// The region options LOCATE finds regions with in a frame whose models
// (in frame pixels) are `models`: the cell's, each model's own smallest
// hole and region, and the speck area when the smallest region follows them.
vision::RegionOptions locateRegionOptions(const VisionOptions& options,
                                          const store::ModelList& models);

// The frame's image as 8-bit grey: the image itself, or a converted copy.
cv::Mat greyImage(const Frame& frame);

// The image the vision pass reads from a frame: a colour frame projected on
// the colour axes of the models taught in colour (vision/segmentation/colour_axis.hpp),
// or its grey levels when none was; a grey frame as it is.
cv::Mat visionImage(const Frame& frame, const store::ModelList& models);

// Frame pixels per sensor pixel along no particular axis (the geometric
// mean of the two scales), and whether that is a resize at all.
double frameScale(const SensorMapping& mapping);
bool isResized(const SensorMapping& mapping);

// Models are in sensor pixels; a resized frame sees them scaled. The same
// list when the frame is not resized, else a scaled copy (frame pixels),
// built anew on each call (ScaledModelCache keeps them).
std::shared_ptr<const store::ModelList> modelsForFrame(
    std::shared_ptr<const store::ModelList> models, const SensorMapping& mapping);

// The settings of one frame's vision pass on an `image` of that size: the
// cell's areas and adaptive window are in sensor pixels and follow a resize,
// and the window is at least wide enough for the largest of `frame_models`
// (frame pixels, see modelsForFrame), or that part's middle would break into
// phantom holes.
VisionOptions frameOptions(const VisionOptions& options, const SensorMapping& mapping,
                           cv::Size image, const store::ModelList& frame_models);

// A model trained by LEARN, in sensor pixels, and what looks suspicious
// about it (phrases for the reply, e.g. "12 holes smaller than 60 px").
struct LearnOutcome {
  vision::PartModel model;
  std::vector<std::string> warnings;
  // What LEARN left out and why (specks beside the part), for the reply.
  std::vector<std::string> notes;
};

// The teach image LEARN stores beside a model: the frame it was taught on,
// shrunk to fit kTeachImageMaxSide pixels each way (so that a model's image
// stays a few MB at most whatever the camera), as PNG bytes; nullopt if it
// cannot be encoded.
constexpr int kTeachImageMaxSide = 1024;
std::optional<std::string> teachImagePng(const cv::Mat& frame);

// A LEARN tried without storing (TRYLEARN): the model it would store, and
// LOCATE ALL on the same frame with that model in place of the type's.
struct TryLearnOutcome {
  LearnOutcome learned;
  LocateOutcome located;
  int found = 0;  // parts of the taught type among located.parts
};

// A further view of a taught part (LEARNVIEW): where the view read the
// part's centroid and the model with that reading added.
struct ViewOutcome {
  vision::PartModel model;  // sensor pixels, the origin moved (addViewReading)
  cv::Point2d reading;      // this view's centroid, teach image's frame, sensor px
  cv::Point2d moved;        // how far the origin moved with this view, sensor px
  // The median distance of every reading (the teach image's included) from
  // the new origin: what one view's light puts a centroid off by.
  double spread_px = 0;
  // The LOCATE of the type on the view's frame that found the part, for the
  // results stream (where the view was read).
  LocateOutcome located;
};

// LEARNVIEW on one frame: finds the one part of `type` (inside `at`, sensor
// pixels, when given) with the cell's models, as LOCATE does, and reads
// where its centroid lies in the model's frame (the model placed on the
// part's edges, the centroid measured on its grey levels): the teach
// image's light put the model's origin off by what that image read, and
// each view lying elsewhere reads it again. The part must lie apart
// (a part that touches another is placed by its outline alone). Errors:
// kUnknownType, kNoPart / kNoPartInRectangle, kSeveralParts /
// kSeveralPartsInRectangle, kViewRefused (a part with rotational symmetry,
// whose origin is its centre of symmetry; a part touching another; a
// reading further than vision::kMaxViewReadingPx from the teach image's;
// views full).
Result<ViewOutcome> viewInFrame(const Frame& frame, const VisionOptions& options,
                                std::shared_ptr<const store::ModelList> models, int type,
                                const std::optional<cv::Rect>& at,
                                ScaledModelCache* cache = nullptr);

// Adds `view`'s reading to the stored model of `type` (`change`: the
// request, for the undo history) and puts the model stored in view.model.
// Errors: kUnknownType, kViewRefused (the model would not be valid),
// kStorageFailed.
Result<void> storeView(store::ModelLibrary& library, int type, ViewOutcome& view,
                       std::string_view change);

// LEARN on one grey frame: binarizes the whole frame as LOCATE would (with
// `models`, sensor pixels, widening the window), then trains from the one
// part inside `at` (sensor pixels; none: the whole frame): the largest
// region there, ignoring specks far smaller than it (LearnOutcome::notes
// says how many), refusing when another region is a part's size. `image` is
// grey or BGR: in colour, the part is taught on its colour (the model keeps
// the colour axis) when that tells it from its surface better than grey
// levels do. Parts touching
// the frame border are taken only when there is no other. `cache` (may be
// null) keeps the models scaled for a resized frame.
Result<LearnOutcome> learnInImage(const cv::Mat& image, const SensorMapping& mapping,
                                  const VisionOptions& options,
                                  std::shared_ptr<const store::ModelList> models, int type,
                                  const std::string& name, const std::optional<cv::Rect>& at,
                                  ScaledModelCache* cache = nullptr);

// LEARN's warning where its part was taught on its colour (PartModel::colour)
// from a frame that went through lossy compression (FrameInfo::compressed: a
// stream, an MJPEG webcam, a JPEG file): such frames carry colour at half
// resolution and quantise it in blocks, and a part told from its surface by
// colour is then placed tenths of a pixel off. Added to `learned`'s
// warnings; nothing otherwise.
void warnOfCompressedColour(bool compressed, LearnOutcome* learned);

// LOCATE on one frame, as the robot server, the offline tool and the
// benchmarks run it: the parts of `type` (-1: all types) recognized with
// `models` (every region when there are none), with the scene kept for
// grasp selection. The outcome's frame info is the frame's. `cache` (may be
// null: the models are scaled anew) keeps the models scaled for a resized
// frame from one call to the next.
LocateOutcome locateInFrame(const Frame& frame, const VisionOptions& options,
                            std::shared_ptr<const store::ModelList> models, int type,
                            ScaledModelCache* cache = nullptr);

// Finds parts in a grey image: with `models` non-empty, the recognized parts
// of type `type` (-1: all types), best first, recognized with that type's
// models alone and screened against the others (LOCATE ALL: every model
// competes; see recognizeParts), each model counting holes with its own
// minimum hole area; with none, every region, largest first.
// With `scene`, also keeps the mask and regions there.
std::vector<LocatedPart> locateInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                       const VisionOptions& options, const store::ModelList& models,
                                       int type, LocateScene* scene = nullptr);

// The single region of a grey image as a calibration target.
Result<TargetOutcome> targetInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                    const VisionOptions& options);

// Blob features of every region of a grey image (skeleton left out).
std::vector<vision::BlobFeatures> blobsInImage(const cv::Mat& grey, const VisionOptions& options);

class VisionService {
 public:
  // `models` (borrowed, may be null: no recognition) outlives the service.
  VisionService(std::unique_ptr<link::CameraLink> camera, VisionOptions options,
                store::ModelLibrary* models = nullptr);
  ~VisionService();

  void start();
  void stop();

  // The parts of `type` (-1: of every trained type) in a frame taken after
  // this call (every region when no model exists; VisionServiceErrc::kUnknownType
  // when models exist but none of `type`).
  Result<LocateOutcome> locate(int type);
  // Trains type `type` from the single part in a fresh frame (inside `at`,
  // sensor pixels, when given; the camera's ROI is left alone) and stores it
  // (`change`: the request, for the undo history).
  Result<LearnOutcome> learn(int type, const std::string& name,
                             const std::optional<cv::Rect>& at = std::nullopt,
                             std::string_view change = {});
  // LEARN on a fresh frame without storing anything, then LOCATE ALL on that
  // frame with the new model in place of any model of `type`: what LEARN
  // would teach and what LOCATE would then find, for a person to judge first.
  Result<TryLearnOutcome> tryLearn(int type, const std::string& name,
                                   const std::optional<cv::Rect>& at = std::nullopt);
  // Adds a fresh frame's view of the part of `type` (viewInFrame) to its
  // model and stores it (`change`: the request, for the undo history).
  Result<ViewOutcome> learnView(int type, const std::optional<cv::Rect>& at = std::nullopt,
                                std::string_view change = {});
  // Blob features of every region in a fresh frame, sensor pixels.
  Result<std::vector<vision::BlobFeatures>> blobs();
  // The single calibration target in a fresh frame.
  Result<TargetOutcome> target();
  // A fresh frame's grey pixels (a copy the caller owns) and their mapping
  // to sensor pixels, for measurements that need the whole image (a grid of
  // calibration dots).
  Result<std::pair<cv::Mat, SensorMapping>> greyFrame();
  // Runs `fn(link::CameraLink&)` between requests (camera settings: they share
  // the link's control socket with the triggers) and returns its result.
  template <typename Fn>
  auto withCamera(Fn&& fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    return fn(*camera_);
  }
  uint64_t framesReceived() const { return camera_->framesReceived(); }
  store::ModelLibrary* models() const { return models_; }
  // The frame the last request worked on.
  std::optional<FrameInfo> lastFrame() const;
  // That frame itself (null before any), for the results stream's regions
  // of requests that keep none: kept until the next request.
  std::shared_ptr<const Frame> lastFramePixels() const;
  const std::string& camera() const { return camera_->camera(); }
  // The settings in force (a copy: VISION may change them at any time).
  VisionOptions options() const;

  // Run-time settings (VISION, vision_settings.hpp), stored in `path`. At
  // start: the file's settings replace the ones the service was made with,
  // except `keep` (keys set on the command line, which win); no file: they
  // stay. A damaged file is an error naming it, and every request that
  // binarizes (LOCATE, LEARN, TRYLEARN, BLOBS, STORE, CALCAM) and every
  // change is refused until it is repaired and the app restarted, or
  // resetSettings().
  Result<void> loadSettings(const std::string& path, const std::vector<std::string>& keep = {});
  // Applies (key, value) pairs: checked whole, written to the file
  // atomically, then in force for the next request (a request reads one
  // snapshot of them: none sees half a change). Returns the settings before
  // and after.
  Result<std::pair<VisionOptions, VisionOptions>> changeSettings(
      const std::vector<std::pair<std::string, std::string>>& pairs);
  // JOB LOAD: `options` in force, their file `staged` (written and synced
  // by the caller beside the settings file) renamed over it (the caller
  // syncs the directory); a damaged file's refusal is lifted.
  Result<void> adoptSettings(const VisionOptions& options, const std::string& staged);
  // The settings file's path (empty: changes are not stored).
  std::string settingsPath() const;
  // Writes the settings in force over a damaged file and lifts the refusal.
  Result<VisionOptions> resetSettings();
  // What is wrong with the settings file (nullopt: nothing).
  std::optional<std::string> settingsDamage() const;
  // The share of the last request's frame the settings in force binarize
  // as part (nullopt before any frame): over half, and the surface is
  // likely taken for the part (the polarity the wrong way round). A
  // binarization of that frame on the caller's thread; no request waits.
  std::optional<double> partShareOfLastFrame() const;

 private:
  // Call with mutex_ held.
  Result<std::shared_ptr<const Frame>> freshFrame();
  // The settings for one request; an error while the file is damaged.
  Result<std::shared_ptr<const VisionOptions>> requestSettings() const;
  Error settingsBlocked() const;  // call with settings_mutex_ held

  const std::unique_ptr<link::CameraLink> camera_;
  store::ModelLibrary* const models_;

  mutable std::mutex settings_mutex_;  // guards settings_, settings_damage_, settings_path_
  // Swapped whole by a change, never edited in place.
  std::shared_ptr<const VisionOptions> settings_;
  std::string settings_damage_;  // non-empty: the file is damaged (path: why)
  std::string settings_path_;    // empty: changes are not stored
  // Serializes changes: each writes the file, then swaps settings_, so the
  // file and the settings in force agree in the order the changes came.
  std::mutex change_mutex_;

  mutable std::mutex mutex_;  // serializes requests; guards camera_ calls and last_frame_
  std::optional<FrameInfo> last_frame_;
  std::shared_ptr<const Frame> last_pixels_;
  // The models scaled for the camera's current size (a resized camera).
  std::unique_ptr<ScaledModelCache> scaled_models_;
};

}  // namespace picksight::cell

PICKSIGHT_ERROR_ENUM(picksight::cell::VisionServiceErrc)
