// Vision service: fresh frame, then recognition (or blob location) in
// sensor pixels; training and blob features on the same frames.
#include "picksight/cell/vision_service.hpp"

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <optional>

#include "picksight/cell/scaled_model_cache.hpp"
#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"
#include "picksight/vision/recognition/recognition_pass.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/recognition/region_explanation.hpp"
#include "picksight/vision/segmentation/colour_axis.hpp"
#include "picksight/vision/segmentation/disc_morphology.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace picksight::cell {

using store::ModelLibrary;
using store::ModelList;

const char* errorName(VisionServiceErrc e) {
  switch (e) {
    case VisionServiceErrc::kNoTarget:
      return "no target";
    case VisionServiceErrc::kSeveralTargets:
      return "several targets";
    case VisionServiceErrc::kNotADisc:
      return "not a disc";
    case VisionServiceErrc::kUnknownType:
      return "unknown type";
    case VisionServiceErrc::kStorageFailed:
      return "storage failed";
    case VisionServiceErrc::kOutsideFrame:
      return "outside the frame";
    case VisionServiceErrc::kNoPartInRectangle:
      return "no part in the rectangle";
    case VisionServiceErrc::kSeveralPartsInRectangle:
      return "several parts in the rectangle";
    case VisionServiceErrc::kViewRefused:
      return "view refused";
  }
  return "unknown";
}

cv::Mat greyImage(const Frame& frame) {
  if (frame.image.channels() != 3) return frame.image;
  cv::Mat grey;
  cv::cvtColor(frame.image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

std::vector<vision::ColourAxis> colourAxes(const ModelList& models) {
  std::vector<vision::ColourAxis> axes;
  for (const auto& m : models) {
    if (m.colour) axes.push_back(*m.colour);
  }
  return axes;
}

cv::Mat visionImage(const Frame& frame, const ModelList& models) {
  if (frame.image.channels() != 3) return frame.image;
  const auto axes = colourAxes(models);
  return axes.empty() ? greyImage(frame) : vision::projectOnColourAxes(frame.image, axes);
}

vision::RegionOptions locateRegionOptions(const VisionOptions& options, const ModelList& models) {
  vision::RegionOptions region_options = vision::regionOptionsFor(options.regions, models);
  if (options.min_area_follows_models) {
    region_options.min_area = std::max(region_options.min_area, vision::speckAreaFor(models));
  }
  return region_options;
}

std::vector<LocatedPart> locateInImage(const cv::Mat& grey, const SensorMapping& mapping,
                                       const VisionOptions& options, const ModelList& models,
                                       int type, LocateScene* scene) {
  LocateScene local;
  LocateScene& s = scene ? *scene : local;
  s.mask = vision::binarize(grey, options.binarize);
  s.regions = vision::findRegions(s.mask, locateRegionOptions(options, models), grey);
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
  // LOCATE <type> costs the work of that type's models alone (and a cheap
  // screen across the others); LOCATE ALL lets every model compete for
  // every region, so that a part is reported as the type that explains it best.
  const vision::RecognitionPass pass = vision::recognizeParts(regions, models, type);
  for (const auto& out : pass.screened_out)
    s.screened_out.push_back({static_cast<int>(out.region), out.closer->type});
  for (const auto& match : pass.matches) {
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

double frameScale(const SensorMapping& mapping) {
  return std::sqrt(mapping.scale_x * mapping.scale_y);
}

bool isResized(const SensorMapping& mapping) {
  // Below this relative change a resize is none: the models are used as they are.
  constexpr double kSameScale = 1e-9;
  return std::abs(frameScale(mapping) - 1.0) >= kSameScale;
}

std::shared_ptr<const ModelList> modelsForFrame(std::shared_ptr<const ModelList> models,
                                                const SensorMapping& mapping) {
  if (!models) return std::make_shared<const ModelList>();
  const double scale = frameScale(mapping);
  if (!isResized(mapping) || models->empty()) return models;
  auto scaled = std::make_shared<ModelList>();
  scaled->reserve(models->size());
  for (const auto& m : *models) scaled->push_back(vision::scaledModel(m, scale));
  return scaled;
}

VisionOptions frameOptions(const VisionOptions& options, const SensorMapping& mapping,
                           cv::Size image, const ModelList& frame_models) {
  VisionOptions o = options;
  const double area = mapping.scale_x * mapping.scale_y;
  o.regions.min_area *= area;
  o.regions.min_hole_area *= area;
  if (o.binarize.adaptive_window > 0) {
    o.binarize.adaptive_window = std::max(
        8, static_cast<int>(std::lround(o.binarize.adaptive_window * frameScale(mapping))));
  }
  double radius = 0;
  for (const auto& m : frame_models) radius = std::max(radius, m.radius);
  // The automatic window is a share of the image, which a crop shrinks
  // below the parts it still shows.
  if (radius > 0) {
    o.binarize.adaptive_window =
        std::max(vision::adaptiveWindow(image, o.binarize), vision::windowForPart(radius));
  }
  return o;
}

LocateOutcome locateInFrame(const Frame& frame, const VisionOptions& options,
                            std::shared_ptr<const ModelList> models, int type,
                            ScaledModelCache* cache) {
  LocateOutcome outcome;
  outcome.frame = frame.info;
  outcome.scene.models = cache ? cache->forFrame(std::move(models), frame.mapping)
                               : modelsForFrame(std::move(models), frame.mapping);
  const cv::Mat grey = visionImage(frame, *outcome.scene.models);
  VisionOptions o = frameOptions(options, frame.mapping, grey.size(), *outcome.scene.models);
  // The colour projection makes every taught colour dark on its surface.
  if (frame.image.channels() == 3 && !colourAxes(*outcome.scene.models).empty()) {
    o.binarize.polarity = vision::Polarity::kDarkOnLight;
  }
  outcome.parts =
      locateInImage(grey, frame.mapping, o, *outcome.scene.models, type, &outcome.scene);
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
  if (regions.empty()) return makeError(VisionServiceErrc::kNoTarget, "no target found");
  if (regions.size() > 1) {
    return makeError(VisionServiceErrc::kSeveralTargets,
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

VisionService::VisionService(std::unique_ptr<link::CameraLink> camera, VisionOptions options,
                             ModelLibrary* models)
    : camera_(std::move(camera)),
      models_(models),
      settings_(std::make_shared<const VisionOptions>(std::move(options))),
      scaled_models_(std::make_unique<ScaledModelCache>()) {}

VisionService::~VisionService() = default;

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
      return makeError(VisionServiceErrc::kUnknownType,
                       "no model for type " + std::to_string(type) + " (see MODELS)");
  }
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto outcome = locateInFrame(**frame, **settings, models, type, scaled_models_.get());
  outcome.settings = *settings;
  outcome.pixels = *frame;
  return outcome;
}

Result<LearnOutcome> VisionService::learn(int type, const std::string& name,
                                          const std::optional<cv::Rect>& at,
                                          std::string_view change) {
  if (!models_) return makeError(VisionServiceErrc::kStorageFailed, "no model library");
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto learned = learnInImage((*frame)->image, (*frame)->mapping, **settings, models_->snapshot(),
                              type, name, at, scaled_models_.get());
  if (!learned) return learned.error();
  warnOfCompressedColour((*frame)->info.compressed, &*learned);
  auto stored = models_->store(learned->model, change, teachImagePng((*frame)->image));
  if (!stored)
    return makeError(VisionServiceErrc::kStorageFailed,
                     "cannot store the model: " + stored.error().message);
  return learned;
}

Result<ViewOutcome> VisionService::learnView(int type, const std::optional<cv::Rect>& at,
                                             std::string_view change) {
  if (!models_) return makeError(VisionServiceErrc::kUnknownType, "no model library");
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto view = viewInFrame(**frame, **settings, models_->snapshot(), type, at, scaled_models_.get());
  if (!view) return view.error();
  view->located.settings = *settings;
  auto stored = storeView(*models_, type, *view, change);
  if (!stored) return stored.error();
  return view;
}

Result<void> storeView(store::ModelLibrary& library, int type, ViewOutcome& view,
                       std::string_view change) {
  // The reading is added to the model as it is now (a TOLERANCE or GRASP
  // since the view was read kept), under the library's lock.
  auto stored = library.update(
      type, [&](vision::PartModel& m) { vision::addViewReading(m, view.reading); }, change);
  if (!stored) {
    if (stored.error().code == store::ModelErrc::kUnknownType)
      return makeError(VisionServiceErrc::kUnknownType, stored.error().message);
    if (stored.error().code == store::ModelErrc::kInvalidModel)
      return makeError(VisionServiceErrc::kViewRefused, stored.error().message);
    return makeError(VisionServiceErrc::kStorageFailed,
                     "cannot store the model: " + stored.error().message);
  }
  view.model = std::move(*stored);
  return {};
}

std::optional<std::string> teachImagePng(const cv::Mat& frame) {
  if (frame.empty()) return std::nullopt;
  cv::Mat image = frame;
  const double shrink =
      std::min(1.0, static_cast<double>(kTeachImageMaxSide) / std::max(frame.cols, frame.rows));
  if (shrink < 1.0) {
    const cv::Size size(std::max(1, static_cast<int>(frame.cols * shrink)),
                        std::max(1, static_cast<int>(frame.rows * shrink)));
    cv::resize(frame, image, size, 0, 0, cv::INTER_AREA);
  }
  std::vector<uchar> png;
  if (!picksight::codecs::imencode(".png", image, png)) return std::nullopt;
  return std::string(png.begin(), png.end());
}

Result<TryLearnOutcome> VisionService::tryLearn(int type, const std::string& name,
                                                const std::optional<cv::Rect>& at) {
  const auto stored = models_ ? models_->snapshot() : std::make_shared<const ModelList>();
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto learned = learnInImage((*frame)->image, (*frame)->mapping, **settings, stored, type, name,
                              at, scaled_models_.get());
  if (!learned) return learned.error();
  warnOfCompressedColour((*frame)->info.compressed, &*learned);
  auto models = std::make_shared<ModelList>();
  for (const auto& m : *stored) {
    if (m.type != type) models->push_back(m);
  }
  models->push_back(learned->model);
  std::sort(models->begin(), models->end(),
            [](const vision::PartModel& a, const vision::PartModel& b) { return a.type < b.type; });
  TryLearnOutcome out;
  // No cache: a list that is not the library's would evict the scaled models
  // LOCATE keeps.
  out.located = locateInFrame(**frame, **settings, std::move(models), -1, nullptr);
  out.located.settings = *settings;
  for (const auto& p : out.located.parts) out.found += p.type == type ? 1 : 0;
  out.learned = std::move(*learned);
  return out;
}

namespace {
// A region counts as inside LEARN's rectangle when this share of its box is.
constexpr double kInsideShare = 0.5;
// Holes below this share of the part's area look like noise or phantom holes.
constexpr double kSmallHoleShare = 0.005;
// A part under this many times the minimum region area is barely resolved.
constexpr double kSmallPartFactor = 10;
// Beside the largest region LEARN sees, regions under this share of its
// area are specks and stains (a textured belt's grain and blotches, dust,
// the rim of a glint), not parts: a person looking at the image sees one part
// there. A second part of the same type, or a half-size one, is far above
// it. (On a worn belt, stains reach 12 % of a 200 px part's area.)
constexpr double kSpeckShare = 0.15;
// ... and regions of any size whose level stands off the surface around them
// by under this share of the part's: a blotch of the belt that the adaptive
// threshold took (a glossy belt at 85 on 150 gave stains of 15 % of the
// part's area, a fifth as deep as it). A second part stands off as deep.
constexpr double kStainDepthShare = 0.4;
// ... or under this share when the threshold speckled it (kMinPinholes or
// more): a paving's darker bricks, at 30 grey levels of contrast, stand
// off the surface round them by 0.4 to 0.48 of a small part's depth, each
// with 10 to 36 holes and pinholes; a second part, solid, stands off
// about as deep as the part.
constexpr double kSpeckledDepthShare = 0.6;
// The ring around a region its surface level is read on (pixels out, past
// the edge's blur, and wide enough that a brick's joints are not the most
// of it).
constexpr int kRingInner = 2;
constexpr int kRingOuter = 20;
// An evenly lit part has next to none of its outline beside a shadow or
// uneven light (vision::unevenEdgeShare): under this share, on a plain or a
// textured belt, for the t-shaped part of the tests; a soft shadow 8 px
// beside it gave 15 %. It is named a shadow only where the region pass cut
// one off the part (vision::Region::beside_shadow): at 30 grey levels of
// contrast a belt's blotches, a paving's bricks and gravel's stones gave
// 2 to 23 % with no shadow at all (the front-light benchmark's teach
// frames), its cast shadows 17 to 25 %, each cut off its part.
constexpr double kShadowShare = 0.05;

// A region of the surface the threshold speckled has pinholes by the
// dozen; a part, a hole or two of its own. From this many, a faint region
// (or a stretch hung on the part, below) is the surface's.
constexpr int kMinPinholes = 3;

// The regions LEARN sees (indices): the one it will train on, the specks it
// ignores beside it, and the others, which are parts.
struct LearnRegions {
  size_t part = 0;
  std::vector<size_t> specks;
  std::vector<size_t> others;
};

// Region `r`'s level and its surface's: the mean of its pixels (an edge's
// blur left out) and the median of a ring a few pixels out, over pixels of
// no region of `mask`. None where either is not seen.
struct Levels {
  double region = 0;
  double surface = 0;
  // With `spread` only: the 5th and 95th percentiles of the region's own
  // pixels (of `mask`, its edge's blur left out), its faintest stretch in
  // either polarity (LEARN asks it of the part alone; sortForLearn reads
  // the depth of every speck, up to thousands on gravel).
  double region_low = 0;
  double region_high = 0;
};
std::optional<Levels> levelsOf(const vision::Region& r, const cv::Mat& grey, const cv::Mat& mask,
                               bool spread = false) {
  const cv::Rect box =
      (r.bbox + cv::Size(2 * kRingOuter, 2 * kRingOuter) - cv::Point(kRingOuter, kRingOuter)) &
      cv::Rect({0, 0}, grey.size());
  cv::Mat own = cv::Mat::zeros(box.size(), CV_8U);
  cv::drawContours(own, std::vector<std::vector<cv::Point>>{r.outer}, 0, cv::Scalar(255),
                   cv::FILLED, cv::LINE_8, cv::noArray(), INT_MAX, -box.tl());
  cv::Mat core, near, far;
  vision::erodeDisc(own, core, 1);
  vision::dilateDisc(own, near, kRingInner);
  vision::dilateDisc(own, far, kRingOuter);
  const cv::Mat ring = far & ~near & (mask(box) == 0);
  if (cv::countNonZero(core) == 0 || cv::countNonZero(ring) == 0) return std::nullopt;
  const cv::Mat surface = grey(box);
  // The grey levels of `surface` where `where` is set; the k-th of them,
  // and the one a `share` of the way up.
  std::vector<uint8_t> levels;
  const auto gather = [&](const cv::Mat& where) {
    levels.clear();
    for (int y = 0; y < where.rows; ++y) {
      const uint8_t* in = where.ptr<uint8_t>(y);
      const uint8_t* g = surface.ptr<uint8_t>(y);
      for (int x = 0; x < where.cols; ++x)
        if (in[x]) levels.push_back(g[x]);
    }
  };
  const auto nth = [&](size_t k) {
    std::nth_element(levels.begin(), levels.begin() + static_cast<std::ptrdiff_t>(k), levels.end());
    return static_cast<double>(levels[k]);
  };
  const auto at = [&](double share) {
    return nth(static_cast<size_t>(share * static_cast<double>(levels.size() - 1)));
  };
  // The surface's median level there: a region of the surface itself (a
  // brick of a paving, darker than the light joints round it) is ringed
  // by its lighter marks, and read against their mean stood off it as a
  // part does (three bricks inside LEARN AT beside a small part, at 30
  // grey levels of contrast).
  gather(ring);
  Levels out{cv::mean(surface, core)[0], nth(levels.size() / 2)};
  if (!spread) return out;
  gather(core & (mask(box) != 0));
  if (levels.empty()) return std::nullopt;
  out.region_low = at(0.05);
  out.region_high = at(0.95);
  return out;
}

// How far region `r`'s level stands off the surface around it (levelsOf);
// 0 where either is not seen.
double depthOf(const vision::Region& r, const cv::Mat& grey, const cv::Mat& mask) {
  const auto levels = levelsOf(r, grey, mask);
  return levels ? std::abs(levels->region - levels->surface) : 0.0;
}

// The level of the part's faintest stretch as a share of its surface's, as
// binarize reads it (vision::BinarizeOptions::part_level: light parts'
// levels inverted); 0 where not seen, or where the part is not the darker.
double partLevelOf(const vision::Region& r, const cv::Mat& grey, const cv::Mat& mask,
                   vision::Polarity polarity) {
  const auto levels = levelsOf(r, grey, mask, true);
  if (!levels) return 0;
  // Its faintest stretch's level (a part shaded lighter at one end): split
  // at its mean, that end fell to the surface, and the part's outline with
  // it (its origin 1.1 to 1.4 px off on gravel).
  const bool light = polarity == vision::Polarity::kLightOnDark;
  const double part = light ? 255 - levels->region_low : levels->region_high;
  const double surface = light ? 255 - levels->surface : levels->surface;
  if (surface <= 0 || part >= surface) return 0;
  return part / surface;
}

LearnRegions sortForLearn(const std::vector<vision::Region>& regions,
                          const std::vector<size_t>& inside, const cv::Mat& grey,
                          const cv::Mat& mask) {
  LearnRegions out;
  // The part: the largest region that is no stain beside the deepest of
  // those of a part's size. A blotch of a textured belt that the threshold
  // took in whole can be larger than the part (beside a glossy part, 15800
  // px of speckle against the part's 13400): taken as the part, it made the
  // part a second one.
  double largest = 0;
  for (const size_t i : inside) largest = std::max(largest, regions[i].area);
  std::vector<std::pair<size_t, double>> sized;  // regions of a part's size, their depth
  double deepest = 0;
  for (const size_t i : inside) {
    if (regions[i].area < kSpeckShare * largest) continue;
    sized.emplace_back(i, depthOf(regions[i], grey, mask));
    deepest = std::max(deepest, sized.back().second);
  }
  // Passed over only when faint and speckled (pinholes): a lighter part of
  // the user's beside a small dark thing is still the part (and the thing a
  // second one, refused).
  out.part = sized.front().first;
  double part_area = -1;
  for (const auto& [i, depth] : sized) {
    const bool blotch = depth < kStainDepthShare * deepest &&
                        regions[i].holes + regions[i].pinholes >= kMinPinholes;
    if (!blotch && regions[i].area > part_area) {
      out.part = i;
      part_area = regions[i].area;
    }
  }
  const double part_depth = depthOf(regions[out.part], grey, mask);
  for (const size_t i : inside) {
    if (i == out.part) continue;
    const double depth = depthOf(regions[i], grey, mask);
    const bool speckled = regions[i].holes + regions[i].pinholes >= kMinPinholes;
    const bool speck = regions[i].area < kSpeckShare * regions[out.part].area ||
                       depth < (speckled ? kSpeckledDepthShare : kStainDepthShare) * part_depth;
    (speck ? out.specks : out.others).push_back(i);
  }
  return out;
}

// Under a front light at low contrast, a stretch of the surface as dark as
// the part (a blotch of the belt, the shade of a fold) can join the part by
// a few speckled pixels, and the threshold leaves it full of pinholes: a
// model taught with it counts its holes (never seen again) and turns its
// moments, and found no other copy of the part. Such an appendage hangs on
// by a neck under kNeckPx across and has holes, and is either mostly
// thinner than that itself (a mesh of specks) or riddled with pinholes
// (kMinPinholes or more under kNeckPx squared); a part's own pin has no
// holes, and a lobe with a hole of its own (a ring on a thin stem) is solid
// round a hole or two.
constexpr int kNeckPx = 5;
constexpr double kMaxAppendageShare = 0.2;
constexpr double kMinSolidShare = 0.5;
// A stretch of the surface can also lie against the part along a wider
// neck: a blotch of the belt beside a limb, taught in a dim spot at 30 grey
// levels (800 px on a 13400 px part, 6 to 10 px across, one pinhole: the
// model's origin came out 4.5 px off and its copies went unfound when
// touching). Such a stretch tells itself by its outline: away from the
// part, nowhere a step, where the part's own limbs step along theirs (on
// the front-light benchmark's teach frames, read by 8 grey levels, limbs
// along 86 to 100 %, the blotch 29 to 32 %). Necks up to kWideNeckPx are
// tried, a piece being dropped when under kMaxSurfaceSteppedShare of its
// free outline steps.
constexpr int kWideNeckPx = 15;
constexpr double kMaxSurfaceSteppedShare = 0.5;
// Steps are read as vision::outlineSteps reads them
// (vision::kOutlineStepReachPx either side), at least kMinReads times
// along the free outline. A step is half the part's own (the median across
// its whole outline) or vision::kOutlineMinStep grey levels, whichever is
// more: a blotch darker than the noise's reach still falls off over many
// pixels (a dip of two thirds of the contrast, blurred by 6 px, stepped 0
// to 22 levels where the part's edge stepped 15 across the same reach).
constexpr int kMinReads = 8;
// A piece whose free outline steps too seldom is still the part's own when
// it lies as deep as the part: its level, against the levels round it within
// kNearPiecePx (the body's, and the surface's beyond the piece), reaches
// kMinOwnDepth of the way from the surface to the part. A limb lying over a
// darker stretch of the surface steps by little along its edge (a dog's
// tail over a blotch at 30 grey levels of contrast: 18 to 36 % of its free
// outline stepped, and LEARN cut it off and placed the model's origin 2 px
// off) but lies as deep as the body. Read over the front-light benchmark's
// teach frames at 30 grey levels (four teachings, 14 types) and the test's
// blotch against a limb (four seeds), at every neck tried: the limbs and
// tips that stepped too seldom lay 0.82 to 1.25 deep, the blotches 0.35 to
// 0.80 (one of 830 px beside a dog's paw: 0.80, 0.77 and 0.67 at necks of
// 11, 13 and 15 px). A piece is dropped where, at any neck, it steps too
// seldom and lies under this depth: a blotch need show itself at one neck,
// a limb must hold at all of them, hence a bound nearer the blotches.
constexpr int kNearPiecePx = 10;
constexpr double kMinOwnDepth = 0.75;

// The pieces of `own` (a region's pixels, CV_8U) beyond its body: what
// survives an opening by a disc `neck_px` across, its largest piece, and
// the pixels of `own` within kNeckPx / 2 of that.
struct Appendages {
  cv::Mat opened;  // own opened by the neck
  cv::Mat kept;    // the body, with own's pixels beside it
  cv::Mat pieces;  // CV_32S labels of own & ~kept, 1..count
  int count = 0;
};

std::optional<Appendages> appendagesOf(const cv::Mat& own, int neck_px) {
  Appendages a;
  const cv::Mat neck = cv::getStructuringElement(cv::MORPH_ELLIPSE, {neck_px, neck_px});
  cv::morphologyEx(own, a.opened, cv::MORPH_OPEN, neck);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(a.opened, labels, stats, centroids, 8);
  if (n < 2) return std::nullopt;
  int body = 1;
  for (int k = 2; k < n; ++k) {
    if (stats.at<int>(k, cv::CC_STAT_AREA) > stats.at<int>(body, cv::CC_STAT_AREA)) body = k;
  }
  // Grown back by the narrow neck only: grown by a wide one, the body took
  // back the stretch of surface lying against it that far (the blotch's
  // remnant held a model's origin 0.3 px off).
  cv::dilate(labels == body, a.kept,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, {kNeckPx, kNeckPx}));
  a.kept &= own;
  a.count = cv::connectedComponents(own & ~a.kept, a.pieces, 8) - 1;
  return a;
}

// The part's own step across its edge: the median over `outline` (most of
// which is the part's edge, whatever hangs on it).
int medianStep(const std::vector<cv::Point>& outline, const cv::Mat& grey) {
  std::vector<int> steps;
  for (int i = 0; i < static_cast<int>(outline.size()); i += 2) {
    const int step =
        vision::stepAcrossOutline(outline, i, grey, {0, 0}, vision::kOutlineStepReachPx);
    if (step >= 0) steps.push_back(step);
  }
  if (steps.empty()) return 0;
  const auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), mid, steps.end());
  return *mid;
}

// The share of `piece`'s outline away from `kept` (more than a pixel off
// it) that is a step of `min_step` or more in `grey` (same box); -1 when
// read too few times.
double freeSteppedShare(const cv::Mat& piece, const cv::Mat& kept, const cv::Mat& grey,
                        int min_step) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(piece.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  cv::Mat near;
  cv::dilate(kept, near, cv::getStructuringElement(cv::MORPH_RECT, {3, 3}));
  int read = 0;
  int stepped = 0;
  for (const auto& c : contours) {
    for (int i = 0; i < static_cast<int>(c.size()); i += 2) {
      if (near.at<uint8_t>(c[static_cast<size_t>(i)]) != 0) continue;
      const int step = vision::stepAcrossOutline(c, i, grey, {0, 0}, vision::kOutlineStepReachPx);
      if (step < 0) continue;
      ++read;
      stepped += step >= min_step ? 1 : 0;
    }
  }
  return read < kMinReads ? -1.0 : static_cast<double>(stepped) / read;
}

// How deep `piece` lies (see kMinOwnDepth): its level's share of the way
// from the surface's level beside it to the body's, both read within
// kNearPiecePx of it (`own`: the region's pixels, `grey` the same box);
// 0 where either has too few pixels or they are level. Each level is the
// mean of the middle half of the levels read: a median moves by whole
// grey levels, a tenth of the depth at 30 levels of contrast (a tip read
// 0.82 deep at one neck, 0.91 and 1.00 at the others).
double pieceDepth(const cv::Mat& piece, const cv::Mat& own, const cv::Mat& grey) {
  cv::Mat near;
  cv::dilate(
      piece, near,
      cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * kNearPiecePx + 1, 2 * kNearPiecePx + 1}));
  const auto middleMean = [&](const cv::Mat& where, double* level) {
    std::vector<uint8_t> values;
    for (int y = 0; y < where.rows; ++y) {
      const uint8_t* w = where.ptr<uint8_t>(y);
      const uint8_t* g = grey.ptr<uint8_t>(y);
      for (int x = 0; x < where.cols; ++x) {
        if (w[x] != 0) values.push_back(g[x]);
      }
    }
    if (values.size() < static_cast<size_t>(kMinReads)) return false;
    std::sort(values.begin(), values.end());
    const size_t from = values.size() / 4;
    const size_t to = values.size() - values.size() / 4;
    double sum = 0;
    for (size_t k = from; k < to; ++k) sum += values[k];
    *level = sum / static_cast<double>(to - from);
    return true;
  };
  double level = 0;
  double body = 0;
  double surface = 0;
  if (!middleMean(piece, &level) || !middleMean(near & own & ~piece, &body) ||
      !middleMean(near & ~own, &surface) || body == surface) {
    return 0;
  }
  return (surface - level) / (surface - body);
}

// What cutAppendages took off (pixels): speckle on a narrow neck, and
// stretches of the surface without an edge on a wider one.
struct AppendageCut {
  int speckled_px = 0;
  int surface_px = 0;
};

// Takes such appendages off region `r` in `mask` (frame pixels, in place;
// `grey` the frame it was binarized from).
AppendageCut cutAppendages(const vision::Region& r, cv::Mat& mask, const cv::Mat& grey) {
  const int margin = kWideNeckPx;
  const cv::Rect box = (r.bbox + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                       cv::Rect({0, 0}, mask.size());
  cv::Mat filled = cv::Mat::zeros(box.size(), CV_8U);
  cv::drawContours(filled, std::vector<std::vector<cv::Point>>{r.outer}, 0, cv::Scalar(255),
                   cv::FILLED, cv::LINE_8, cv::noArray(), INT_MAX, -box.tl());
  const cv::Mat own = filled & (mask(box) != 0);
  const double own_area = cv::countNonZero(own);
  cv::Mat dropped = cv::Mat::zeros(box.size(), CV_8U);
  // A speckled appendage on a narrow neck: what hangs on beyond the body,
  // piece by piece, dropped when holed and small.
  std::vector<int> crumbs;  // pieces too small to be a pin: the speckle's crumbs
  const auto narrow = r.holes > 0 ? appendagesOf(own, kNeckPx) : std::nullopt;
  for (int k = 1; narrow && k <= narrow->count; ++k) {
    const cv::Mat piece = narrow->pieces == k;
    const int area = cv::countNonZero(piece);
    if (area > kMaxAppendageShare * own_area) continue;
    if (area < kNeckPx * kNeckPx) crumbs.push_back(k);
    std::vector<std::vector<cv::Point>> contours;
    std::vector<cv::Vec4i> hierarchy;
    cv::findContours(piece.clone(), contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
    int holes = 0;
    int pinholes = 0;
    for (size_t i = 0; i < contours.size(); ++i) {
      if (hierarchy[i][3] < 0) continue;
      ++holes;
      if (cv::contourArea(contours[i]) < kNeckPx * kNeckPx) ++pinholes;
    }
    // Mostly thinner than the neck too (a mesh of specks), or riddled with
    // pinholes (a blotch the threshold speckled); a lobe of the part's own
    // (a ring on a thin stem) is solid round a hole or two.
    const bool solid = cv::countNonZero(piece & narrow->opened) >= kMinSolidShare * area;
    if (holes > 0 && (!solid || pinholes >= kMinPinholes)) dropped.setTo(255, piece);
  }
  AppendageCut out;
  if (cv::countNonZero(dropped) > 0) {
    for (const int k : crumbs) dropped.setTo(255, narrow->pieces == k);
    out.speckled_px = cv::countNonZero(dropped);
  }
  // Then a stretch of the surface on a wider neck, its outline no step.
  const cv::Mat surface = grey(box);
  std::vector<cv::Point> outline(r.outer.size());
  std::transform(r.outer.begin(), r.outer.end(), outline.begin(),
                 [&](const cv::Point& p) { return p - box.tl(); });
  const int min_step = std::max(vision::kOutlineMinStep, medianStep(outline, surface) / 2);
  for (int neck = kNeckPx + 2; neck <= kWideNeckPx; neck += 2) {
    const cv::Mat left = own & ~dropped;
    const auto wide = appendagesOf(left, neck);
    for (int k = 1; wide && k <= wide->count; ++k) {
      const cv::Mat piece = wide->pieces == k;
      const int area = cv::countNonZero(piece);
      if (area > kMaxAppendageShare * own_area || area < kNeckPx * kNeckPx) continue;
      const double share = freeSteppedShare(piece, wide->kept, surface, min_step);
      if (share >= 0 && share < kMaxSurfaceSteppedShare &&
          pieceDepth(piece, own, surface) < kMinOwnDepth) {
        dropped.setTo(255, piece);
      }
    }
  }
  out.surface_px = cv::countNonZero(dropped) - out.speckled_px;
  if (out.speckled_px + out.surface_px == 0) return out;
  mask(box).setTo(0, dropped);
  // Pinholes the appendage closed against the part at its neck: the
  // surface between specks, not a hole of the part.
  cv::Mat zone;
  cv::dilate(dropped, zone,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * kNeckPx + 1, 2 * kNeckPx + 1}));
  const cv::Mat left = own & ~dropped;
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(left.clone(), contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  for (size_t i = 0; i < contours.size(); ++i) {
    if (hierarchy[i][3] < 0 || cv::contourArea(contours[i]) >= kNeckPx * kNeckPx) continue;
    const bool at_neck = std::any_of(contours[i].begin(), contours[i].end(),
                                     [&](const cv::Point& q) { return zone.at<uint8_t>(q) != 0; });
    if (at_neck) {
      cv::drawContours(mask(box), contours, static_cast<int>(i), cv::Scalar(255), cv::FILLED);
    }
  }
  return out;
}

// What LEARN left out, for its reply (sensor pixels).
std::string specksNote(const std::vector<vision::Region>& regions,
                       const std::vector<size_t>& specks, const SensorMapping& mapping) {
  double largest = 0;
  for (const size_t i : specks) largest = std::max(largest, regions[i].area);
  return "ignored " + std::to_string(specks.size()) + (specks.size() == 1 ? " speck" : " specks") +
         " of up to " + std::to_string(std::lround(mapping.areaToSensor(largest))) +
         " px beside the part";
}

// A rectangle of sensor pixels as the frame pixels it covers, clipped to
// the image (empty when it covers none).
cv::Rect frameRect(const cv::Rect& sensor, const SensorMapping& m, cv::Size image) {
  // Pixel edges: sensor edge x - 0.5 is frame edge (x - roi_x) * scale - 0.5.
  const auto lo = [](double v) { return static_cast<int>(std::floor(v + 1e-9)); };
  const auto hi = [](double v) { return static_cast<int>(std::ceil(v - 1e-9)); };
  const int u0 = lo((sensor.x - m.roi_x) * m.scale_x);
  const int v0 = lo((sensor.y - m.roi_y) * m.scale_y);
  const int u1 = hi((sensor.x + sensor.width - m.roi_x) * m.scale_x);
  const int v1 = hi((sensor.y + sensor.height - m.roi_y) * m.scale_y);
  return cv::Rect(u0, v0, u1 - u0, v1 - v0) & cv::Rect(cv::Point(0, 0), image);
}

// The regions (indices) inside `rect`: those clear of the frame border, or
// when there are none, those touching it.
std::vector<size_t> regionsInside(const std::vector<vision::Region>& regions,
                                  const cv::Rect& rect) {
  std::vector<size_t> clear;
  std::vector<size_t> border;
  for (size_t i = 0; i < regions.size(); ++i) {
    const cv::Rect& box = regions[i].bbox;
    if ((box & rect).area() < kInsideShare * box.area()) continue;
    (regions[i].touches_border ? border : clear).push_back(i);
  }
  return clear.empty() ? border : clear;
}

double farthestBoundary(const vision::Region& r) {
  double reach = 0;
  for (const auto& p : r.outer)
    reach = std::max(reach, std::hypot(p.x - r.centroid.x, p.y - r.centroid.y));
  return reach;
}

std::string sensorRectText(const cv::Rect& r) {
  return std::to_string(r.x) + " " + std::to_string(r.y) + " " + std::to_string(r.width) + " " +
         std::to_string(r.height);
}

// What looks wrong with a part about to be learned (sensor pixels in the text).
std::vector<std::string> learnWarnings(const vision::Region& r, const cv::Mat& grey,
                                       const cv::Mat& mask, const SensorMapping& mapping,
                                       const VisionOptions& options) {
  std::vector<std::string> warnings;
  if (r.glints > 0) {
    warnings.push_back(std::to_string(r.glints) + (r.glints == 1 ? " reflection" : " reflections") +
                       " inside the part read as part (lighter than the surface: a glossy part "
                       "under a direct light)");
  }
  const double uneven = vision::unevenEdgeShare(grey, mask, r);
  if (uneven > kShadowShare) {
    const std::string along =
        " along " + std::to_string(std::lround(100 * uneven)) + " % of the outline";
    if (r.beside_shadow) {
      warnings.push_back("a shadow beside the part" + along +
                         " (cut off the part, which may still be placed half a pixel off: light "
                         "the cell along the camera's axis, a ring light or a dome)");
    } else {
      warnings.push_back(
          "an uneven surface beside the part" + along +
          " (a quarter of the contrast off the surface's or the part's level there: blotches, "
          "grain or stones of the surface, the part's shading, a faint shadow; the part may be "
          "placed a tenth of a pixel off: teach it on a plainer stretch, or add views of it "
          "lying elsewhere with LEARNVIEW, eight at 30 grey levels of contrast)");
    }
  }
  const double small_hole = kSmallHoleShare * r.area;
  int small = 0;
  double largest_small = 0;
  for (const auto& hole : r.hole_boundaries) {
    const double area = cv::contourArea(hole);
    if (area >= small_hole) continue;
    ++small;
    largest_small = std::max(largest_small, area);
  }
  if (small > 0) {
    // The setting that leaves them all out (holes under it are not counted),
    // named so the reader need not measure them: the relief of a coin gave
    // 26 such holes, and every other coin was refused on its hole count.
    const long leave_out = static_cast<long>(std::floor(mapping.areaToSensor(largest_small))) + 1;
    warnings.push_back(
        std::to_string(small) + (small == 1 ? " hole" : " holes") + " smaller than " +
        std::to_string(std::lround(mapping.areaToSensor(small_hole))) +
        " px (noise or uneven light? every LOCATE needs the same count; " +
        "VISION min_hole_area " + std::to_string(leave_out) + " and LEARN again leaves them out)");
  }
  if (r.touches_border) warnings.push_back("the part touches the frame border");
  const double area = mapping.areaToSensor(r.area);
  if (area < kSmallPartFactor * std::max(1.0, options.regions.min_area)) {
    warnings.push_back("area " + std::to_string(std::lround(area)) + " px is under " +
                       formatFixed(kSmallPartFactor, 0) + " times the minimum region area");
  }
  return warnings;
}
}  // namespace

namespace {
// The warning of LEARN when the part it teaches as `type` is one another
// type's model already recognizes (frame pixels).
std::optional<std::string> lookAlikeWarning(const vision::Region& region,
                                            const ModelList& frame_models, int type) {
  std::vector<const vision::PartModel*> others;
  for (const auto& m : frame_models) {
    if (m.type != type) others.push_back(&m);
  }
  // The recognizer's own tests (holes, area, Hu distance, boundary
  // verification, mirror) on the part being taught: one that passes them
  // all for another type is a part LOCATE ALL would give either type, at
  // the same score, by which fits a few edge pixels better.
  const auto seen = vision::explainRegion(region, others);
  if (!seen.nearest || seen.test != vision::RegionTest::kPasses) return std::nullopt;
  const std::string other = std::to_string(seen.nearest->type);
  return "looks like type " + other + " (" + seen.nearest->name +
         "): this part passes every test of that model (boundary " + formatFixed(seen.measured, 1) +
         " % verified), so LOCATE ALL would split parts of this " + "shape between types " + other +
         " and " + std::to_string(type) + " (teach it as type " + other + ", or UNDO)";
}
}  // namespace

Result<ViewOutcome> viewInFrame(const Frame& frame, const VisionOptions& options,
                                std::shared_ptr<const ModelList> models, int type,
                                const std::optional<cv::Rect>& at, ScaledModelCache* cache) {
  const vision::PartModel* model = nullptr;
  for (const auto& m : *models) {
    if (m.type == type) model = &m;
  }
  if (!model) {
    return makeError(VisionServiceErrc::kUnknownType,
                     "no model for type " + std::to_string(type) + ": LEARN it first");
  }
  const std::string word = at ? "LEARNVIEW AT " + sensorRectText(*at) : "LEARNVIEW";
  const auto refuse = [&](const std::string& why) {
    return makeError(VisionServiceErrc::kViewRefused, word + ": " + why);
  };
  if (model->symmetry_order != 1) {
    return refuse("type " + std::to_string(type) + " looks alike turned (symmetry order " +
                  std::to_string(model->symmetry_order) +
                  "): its origin is its centre of symmetry, which views do not move");
  }
  if (model->views.size() >= vision::kMaxModelViews) {
    return refuse("type " + std::to_string(type) + " has " +
                  std::to_string(model->views.size() + 1) + " views already (at most " +
                  std::to_string(vision::kMaxModelViews + 1) + "; LEARN it again to start over)");
  }
  LocateOutcome located = locateInFrame(frame, options, models, type, cache);
  std::vector<const LocatedPart*> parts;
  for (const auto& p : located.parts) {
    if (p.type == type && (!at || cv::Rect2d(*at).contains({p.x, p.y}))) parts.push_back(&p);
  }
  if (parts.empty()) {
    const std::string what = "no part of type " + std::to_string(type);
    if (!at) return makeError(vision::PartModelErrc::kNoPart, what + " in the frame");
    return makeError(VisionServiceErrc::kNoPartInRectangle, what + " inside " + word);
  }
  if (parts.size() > 1) {
    const std::string what =
        std::to_string(parts.size()) + " parts of type " + std::to_string(type);
    if (!at) {
      return makeError(vision::PartModelErrc::kSeveralParts,
                       what + " in the frame, LEARNVIEW reads one (or LEARNVIEW " +
                           std::to_string(type) + " AT <x> <y> <w> <h> around one)");
    }
    return makeError(VisionServiceErrc::kSeveralPartsInRectangle,
                     what + " inside " + word + ", it reads one");
  }
  const LocatedPart& part = *parts.front();
  if (part.touching || part.region < 0) {
    return refuse("the part of type " + std::to_string(type) +
                  " touches another part: a view is read on a part lying apart");
  }
  const SensorMapping& mapping = located.scene.mapping;
  // The point the origin stands for, read as LEARN read it: the model (as
  // this frame sees it) placed where the part was found.
  const vision::Region& region = located.scene.regions[static_cast<size_t>(part.region)];
  cv::Point2d seen = region.centroid;
  const double turn = part.angle_deg * kRadPerDeg;  // sensor axes; into the frame's
  const double frame_deg =
      std::atan2(std::sin(turn) * mapping.scale_y, std::cos(turn) * mapping.scale_x) / kRadPerDeg;
  for (const auto& m : *located.scene.models) {
    if (m.type != type) continue;
    seen = vision::referencePoint(m, region, {mapping.toFrame({part.x, part.y}), frame_deg});
  }
  const cv::Point2d centroid = mapping.toSensor(seen);
  // Into the model's frame: back by the part's turn, then about the teach
  // image's centroid rather than the current origin.
  const double back = -part.angle_deg * kRadPerDeg;
  const cv::Point2d d = centroid - cv::Point2d(part.x, part.y);
  ViewOutcome out;
  out.reading = cv::Point2d(d.x * std::cos(back) - d.y * std::sin(back),
                            d.x * std::sin(back) + d.y * std::cos(back)) +
                model->origin_shift;
  if (std::hypot(out.reading.x, out.reading.y) > vision::kMaxViewReadingPx) {
    return refuse("this view read the part's centroid " +
                  formatFixed(std::hypot(out.reading.x, out.reading.y), 2) +
                  " px from the teach image's (at most " +
                  formatFixed(vision::kMaxViewReadingPx, 1) +
                  "): a part of another shape, or a shadow or glint joined to it");
  }
  out.model = *model;
  vision::addViewReading(out.model, out.reading);
  out.moved = out.model.origin_shift - model->origin_shift;
  out.spread_px = vision::viewSpread(out.model);
  if (auto valid = vision::validateModel(out.model); !valid) return refuse(valid.error().message);
  out.located = std::move(located);
  return out;
}

Result<LearnOutcome> learnInImage(const cv::Mat& image, const SensorMapping& mapping,
                                  const VisionOptions& options,
                                  std::shared_ptr<const ModelList> models, int type,
                                  const std::string& name, const std::optional<cv::Rect>& at,
                                  ScaledModelCache* cache) {
  const cv::Rect rect = at ? frameRect(*at, mapping, image.size()) : cv::Rect({0, 0}, image.size());
  // A colour frame is read in colour when the part's colour tells it from
  // its surface clearly better than its grey level does.
  std::optional<vision::ColourAxis> colour;
  cv::Mat grey = image;
  if (image.channels() == 3) {
    if (!rect.empty()) colour = vision::colourAxisIn(image, rect);
    if (colour && !vision::colourSeparatesBetter(*colour)) colour.reset();
    if (colour) {
      grey = vision::projectOnColourAxes(image, {*colour});
    } else {
      cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    }
  }
  if (rect.empty()) {
    return makeError(VisionServiceErrc::kOutsideFrame,
                     "LEARN AT " + sensorRectText(*at) +
                         ": the rectangle holds no pixel of the frame (sensor " +
                         sensorRectText(mapping.boxToSensor(cv::Rect({0, 0}, grey.size()))) + ")");
  }
  const auto frame_models = cache ? cache->forFrame(std::move(models), mapping)
                                  : modelsForFrame(std::move(models), mapping);
  VisionOptions o = frameOptions(options, mapping, grey.size(), *frame_models);
  o.regions.keep_border_regions = true;
  if (colour) o.binarize.polarity = vision::Polarity::kDarkOnLight;
  // The first pass reads the part with the frame's own window; a second
  // with one wide enough for it (below). When the part had no hole in the
  // first, the second has nothing to mend, and where it loses the part
  // (the wider window joined a wood grain's darker streaks to a tulip on a
  // long stem: four parts inside LEARN AT, 71 in the frame) the first
  // pass's reading is taken again rather than refused.
  const int own_window = o.binarize.adaptive_window;
  bool first_whole = false;
  const auto readAgainNarrow = [&](int pass) {
    if (pass != 1 || !first_whole) return false;
    o.binarize.adaptive_window = own_window;
    return true;
  };
  // Then once more at the part's own level against its surface's
  // (vision::BinarizeOptions::part_level). A frame that is surface but for
  // the part is no two populations of levels: on gravel the first reading
  // split the stones' own shades, took a third of the part's contrast for
  // it, and the part's outline took in the crevices beside it (bumps of up
  // to 8 px, the outline half a pixel out), where LOCATE, reading a frame
  // of many parts, finds the parts' own contrast. Where that reading loses
  // the part, the one before is taken again.
  bool level_read = false;
  bool level_pass = false;
  const auto readAgainWithoutLevel = [&]() {
    if (!level_pass) return false;
    o.binarize.part_level = 0;
    level_pass = false;
    return true;
  };
  for (int pass = 0;; ++pass) {
    cv::Mat mask = vision::binarize(grey, o.binarize);
    auto regions = vision::findRegions(mask, o.regions, grey);
    auto inside = regionsInside(regions, rect);
    if (inside.empty() && readAgainWithoutLevel()) continue;
    if (inside.empty() && readAgainNarrow(pass)) continue;
    if (inside.empty()) {
      if (!at) return makeError(vision::PartModelErrc::kNoPart, "no part in the frame");
      return makeError(VisionServiceErrc::kNoPartInRectangle,
                       "no part inside LEARN AT " + sensorRectText(*at));
    }
    LearnRegions seen = sortForLearn(regions, inside, grey, mask);
    AppendageCut appendages;
    if (seen.others.empty() && !inside.empty()) {
      cv::Mat cut = mask.clone();
      appendages = cutAppendages(regions[seen.part], cut, grey);
      const bool any = appendages.speckled_px + appendages.surface_px > 0;
      auto cut_regions =
          any ? vision::findRegions(cut, o.regions, grey) : std::vector<vision::Region>{};
      auto cut_inside = regionsInside(cut_regions, rect);
      if (cut_inside.empty()) {
        appendages = {};  // nothing cut, or nothing left: the region as it was
      } else {
        mask = cut;
        regions = std::move(cut_regions);
        inside = std::move(cut_inside);
        seen = sortForLearn(regions, inside, grey, mask);
      }
    }
    if (!seen.others.empty() && readAgainWithoutLevel()) continue;
    if (!seen.others.empty() && readAgainNarrow(pass)) continue;
    if (!seen.others.empty()) {
      const std::string count = std::to_string(seen.others.size() + 1) + " parts";
      if (!at) {
        return makeError(
            vision::PartModelErrc::kSeveralParts,
            count +
                " in the frame, LEARN needs exactly one (or LEARN ... AT <x> <y> <w> <h> "
                "around one; offline: learn --at <x> <y> <w> <h>)");
      }
      return makeError(
          VisionServiceErrc::kSeveralPartsInRectangle,
          count + " inside LEARN AT " + sensorRectText(*at) + ", it needs exactly one");
    }
    const vision::Region& r = regions[seen.part];
    // A region whose outline is nowhere a step in grey level is the
    // surface's own light taken in by the threshold (a blotch, a vignetted
    // corner), not a part: such a model would match nothing a robot should
    // pick. (A green part on a grey belt of its brightness, read in grey,
    // left one such patch in the frame.)
    if (!vision::outlineSteps(r) && readAgainWithoutLevel()) continue;
    if (!vision::outlineSteps(r)) {
      const std::string what = "the largest region (" +
                               formatFixed(mapping.areaToSensor(r.area), 0) +
                               " px) has no edge along its outline: the surface's own light";
      if (!at) {
        // On a colour camera, a part as grey as its surface shows only in
        // its colour, which LEARN reads around the part.
        const std::string colour_hint =
            image.channels() == 3 && !colour
                ? " (LEARN ... AT <x> <y> <w> <h> around the part reads its colour)"
                : "";
        return makeError(vision::PartModelErrc::kNoPart,
                         "no part in the frame: " + what + colour_hint);
      }
      return makeError(VisionServiceErrc::kNoPartInRectangle,
                       "no part inside LEARN AT " + sensorRectText(*at) + ": " + what);
    }
    // A window narrower than the part (a tight crop, a small image) breaks
    // its middle into phantom holes: binarize again with one that fits it,
    // as LOCATE will once the model exists.
    const int needed = vision::windowForPart(farthestBoundary(r));
    if (pass == 0 && o.binarize.method == vision::ThresholdMethod::kAdaptive &&
        vision::adaptiveWindow(grey.size(), o.binarize) < needed) {
      first_whole = r.holes == 0;
      o.binarize.adaptive_window = needed;
      continue;
    }
    if (o.binarize.method == vision::ThresholdMethod::kAdaptive && !level_read) {
      level_read = true;
      const double level = partLevelOf(r, grey, mask, o.binarize.polarity);
      if (level > 0) {
        level_pass = true;
        o.binarize.part_level = level;
        continue;
      }
    }
    vision::TrainOptions train;
    train.binarize = o.binarize;
    train.regions = o.regions;
    auto trained = vision::trainModelFromRegion(grey, r, type, name, train);
    if (!trained) return trained.error();
    // Where the origin lies in the teach image (the grey centroid, or under
    // uneven light the edges' one: vision::referencePoint).
    const cv::Point2d origin = trained->trained_centroid;
    LearnOutcome out;
    out.model = !isResized(mapping) ? std::move(*trained)
                                    : vision::scaledModel(*trained, 1.0 / frameScale(mapping));
    out.model.trained_centroid = mapping.toSensor(origin);
    out.model.trained_angle_deg = mapping.directionToSensor(r.angle_deg);
    out.model.min_region_area = options.regions.min_area;
    out.model.min_hole_area = options.regions.min_hole_area;
    out.model.taught_polarity = options.binarize.polarity;
    out.model.colour = colour;
    out.warnings = learnWarnings(r, grey, mask, mapping, options);
    if (auto alike = lookAlikeWarning(r, *frame_models, type)) out.warnings.push_back(*alike);
    if (!seen.specks.empty()) out.notes.push_back(specksNote(regions, seen.specks, mapping));
    if (appendages.speckled_px > 0) {
      out.notes.push_back(
          "left out " + std::to_string(std::lround(mapping.areaToSensor(appendages.speckled_px))) +
          " px of speckled surface joined to the part by a neck under " + std::to_string(kNeckPx) +
          " px (its pinholes are not the part's)");
    }
    if (appendages.surface_px > 0) {
      out.notes.push_back(
          "left out " + std::to_string(std::lround(mapping.areaToSensor(appendages.surface_px))) +
          " px of surface joined to the part by a neck under " + std::to_string(kWideNeckPx) +
          " px, its outline no edge (a stretch of the surface as dark as the part)");
    }
    return out;
  }
}

void warnOfCompressedColour(bool compressed, LearnOutcome* learned) {
  if (!compressed || !learned->model.colour) return;
  // Front-light benchmark, a green part on a grey belt of its brightness,
  // 14 types, separated, position RMS: 0.032 px from lossless frames, 0.047
  // through JPEG at quality 95, 0.074 at 90, 0.23 at 75 (one type's teach
  // image 0.5 px off). Parts taught on their grey levels are not warned of:
  // their edges lie in the brightness, which JPEG keeps at full resolution
  // (at 30 grey levels of contrast 0.051 px lossless, 0.056 to 0.070
  // through JPEG at 75 to 95).
  // The remedy named is not a webcam's YUYV: it keeps colour at half the
  // width too (without JPEG's blocks).
  learned->warnings.push_back(
      "the part is told from its surface by its colour, and this frame came compressed (a "
      "stream, MJPEG or JPEG), which keeps colour at half resolution: expect it placed a tenth "
      "to a few tenths of a pixel off (JPEG quality 75: 0.2 px; raw frames: 0.03); for "
      "sub-pixel work use raw frames (a GigE or USB3 Vision camera) or a surface of another "
      "brightness");
}

Result<std::vector<vision::BlobFeatures>> VisionService::blobs() {
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  const SensorMapping& mapping = (*frame)->mapping;
  auto features = blobsInImage(greyImage(**frame), **settings);
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
  const auto settings = requestSettings();
  if (!settings) return settings.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  auto outcome = targetInImage(greyImage(**frame), (*frame)->mapping, **settings);
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

VisionOptions VisionService::options() const {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  return *settings_;
}

Error VisionService::settingsBlocked() const {
  return makeError(VisionSettingsErrc::kDamaged, "the vision settings file is damaged (" +
                                                     settings_damage_.substr(0, 200) +
                                                     "): repair it and restart, or VISION RESET");
}

Result<std::shared_ptr<const VisionOptions>> VisionService::requestSettings() const {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  if (!settings_damage_.empty()) return settingsBlocked();
  return settings_;
}

std::optional<std::string> VisionService::settingsDamage() const {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  if (settings_damage_.empty()) return std::nullopt;
  return settings_damage_;
}

Result<void> VisionService::loadSettings(const std::string& path,
                                         const std::vector<std::string>& keep) {
  std::lock_guard<std::mutex> change(change_mutex_);
  std::lock_guard<std::mutex> lock(settings_mutex_);
  settings_path_ = path;
  settings_damage_.clear();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) && !ec) return {};
  auto text = readFile(path);
  auto read =
      text ? parseVisionSettingsJson(*text, *settings_, keep) : Result<VisionOptions>(text.error());
  if (!read) {
    settings_damage_ = path + ": " + read.error().message;
    return makeError(VisionSettingsErrc::kDamaged, settings_damage_);
  }
  settings_ = std::make_shared<const VisionOptions>(std::move(*read));
  return {};
}

Result<std::pair<VisionOptions, VisionOptions>> VisionService::changeSettings(
    const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::lock_guard<std::mutex> change(change_mutex_);
  std::shared_ptr<const VisionOptions> before;
  std::string path;
  {
    std::lock_guard<std::mutex> lock(settings_mutex_);
    if (!settings_damage_.empty()) return settingsBlocked();
    before = settings_;
    path = settings_path_;
  }
  auto after = applyVisionSettings(*before, pairs);
  if (!after) return after.error();
  // Written before it is used: a change the file does not hold is not made,
  // and a restart starts with what the cell last ran with.
  if (!path.empty()) {
    if (auto written = writeFileAtomically(path, visionSettingsJson(*after)); !written) {
      return makeError(VisionSettingsErrc::kStorage,
                       "cannot write " + path + ": " + written.error().message);
    }
  }
  {
    std::lock_guard<std::mutex> lock(settings_mutex_);
    settings_ = std::make_shared<const VisionOptions>(*after);
  }
  return std::make_pair(*before, std::move(*after));
}

Result<void> VisionService::adoptSettings(const VisionOptions& options, const std::string& staged) {
  std::lock_guard<std::mutex> change(change_mutex_);
  std::string path;
  {
    std::lock_guard<std::mutex> lock(settings_mutex_);
    path = settings_path_;
  }
  std::error_code ec;
  if (!path.empty()) {
    std::filesystem::rename(staged, path, ec);
    if (ec)
      return makeError(VisionSettingsErrc::kStorage, "cannot write " + path + ": " + ec.message());
  } else {
    std::filesystem::remove(staged, ec);
  }
  std::lock_guard<std::mutex> lock(settings_mutex_);
  settings_ = std::make_shared<const VisionOptions>(options);
  settings_damage_.clear();
  return {};
}

std::string VisionService::settingsPath() const {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  return settings_path_;
}

Result<VisionOptions> VisionService::resetSettings() {
  std::lock_guard<std::mutex> change(change_mutex_);
  std::shared_ptr<const VisionOptions> current;
  std::string path;
  {
    std::lock_guard<std::mutex> lock(settings_mutex_);
    current = settings_;
    path = settings_path_;
  }
  if (!path.empty()) {
    if (auto written = writeFileAtomically(path, visionSettingsJson(*current)); !written) {
      return makeError(VisionSettingsErrc::kStorage,
                       "cannot write " + path + ": " + written.error().message);
    }
  }
  std::lock_guard<std::mutex> lock(settings_mutex_);
  settings_damage_.clear();
  return *current;
}

std::optional<double> VisionService::partShareOfLastFrame() const {
  const auto frame = lastFramePixels();
  if (!frame || frame->image.empty()) return std::nullopt;
  const VisionOptions o = options();
  const cv::Mat grey = greyImage(*frame);
  VisionOptions scaled = frameOptions(o, frame->mapping, grey.size(), ModelList());
  const cv::Mat mask = vision::binarize(grey, scaled.binarize);
  return static_cast<double>(cv::countNonZero(mask)) / static_cast<double>(mask.total());
}

std::shared_ptr<const Frame> VisionService::lastFramePixels() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_pixels_;
}

}  // namespace picksight::cell
