// SceneRenderer: lays out a scene's parts, renders its clean image once and
// adds per-frame noise on request. Shapes, layout and rendering are in
// shapes.cpp, layout.cpp and rendering.cpp.
#include "picksight/synthetic/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "scene_internals.hpp"

namespace picksight::synthetic {

using namespace detail;

SceneRenderer::SceneRenderer(SceneOptions options) : options_(std::move(options)) {
  const SceneOptions& o = options_;
  if (o.width < 16 || o.height < 16) {
    throw std::invalid_argument("SceneRenderer: image too small");
  }
  if (o.parts < 0) {
    throw std::invalid_argument("SceneRenderer: negative part count");
  }
  if (!(o.part_size > 0)) {
    throw std::invalid_argument("SceneRenderer: part_size must be positive");
  }
  if (!(o.noise_sigma >= 0)) {
    throw std::invalid_argument("SceneRenderer: negative noise_sigma");
  }
  const std::vector<std::string>& types = o.types.empty() ? partTypes() : o.types;

  // Every type gets its share of the parts, in random order.
  std::mt19937_64 rng(o.seed);
  std::vector<std::string> part_types(static_cast<std::size_t>(o.parts));
  for (std::size_t i = 0; i < part_types.size(); ++i) {
    part_types[i] = types[i % types.size()];
  }
  for (std::size_t i = part_types.size(); i > 1; --i) {
    std::swap(part_types[i - 1], part_types[rng() % i]);
  }

  // Crowded scenes shrink the parts until they fit; options_.part_size then
  // reports the size used.
  std::map<std::string, SizedPartType> infos;
  std::vector<Placement> placed;
  std::vector<bool> touching;
  double size = o.part_size;
  for (int round = 0;; ++round) {
    infos.clear();
    for (const std::string& type : types) {
      SizedPartType info;
      info.shape = partShape(type, size);
      for (const cv::Point2d& p : info.shape.loops[0]) {
        info.radius = std::max(info.radius, std::hypot(p.x, p.y));
      }
      info.area = shapeArea(info.shape);
      info.symmetry = angleSymmetryDeg(info.shape);
      infos[type] = std::move(info);
    }
    std::vector<const SizedPartType*> parts;
    parts.reserve(part_types.size());
    for (const std::string& type : part_types) {
      parts.push_back(&infos.at(type));
    }
    if (tryLayout(o, parts, rng, placed)) {
      touching.assign(parts.size(), false);
      if (o.touching) {
        for (std::size_t i = 1; i < parts.size(); i += 2) {
          if (moveIntoContact(o, parts, i, i - 1, rng, placed)) {
            touching[i] = touching[i - 1] = true;
          }
        }
      }
      break;
    }
    size *= kShrinkFactor;
    if (round + 1 >= kMaxShrinkRounds || size < kMinPartSizePx) {
      throw std::invalid_argument("SceneRenderer: " + std::to_string(o.parts) +
                                  " parts do not fit in the image");
    }
  }
  options_.part_size = size;

  light_ = o.uneven_light ? illumination(o.width, o.height, o.seed) : cv::Mat();
  base_ = cv::Mat(o.height, o.width, CV_32F, cv::Scalar(o.background_level));
  if (!light_.empty()) {
    base_ = light_ * o.background_level;
  }
  // Under a front light the parts are drawn as coverage first, then lit with
  // the surface's texture, their shading, shadows and glints.
  const bool front = o.front.any();
  if (front && o.front.colour) {
    throw std::invalid_argument("SceneRenderer: a colour front light is not rendered in grey");
  }
  cv::Mat coverage = front ? cv::Mat::zeros(o.height, o.width, CV_32F) : cv::Mat();
  truth_.reserve(part_types.size());
  for (std::size_t i = 0; i < part_types.size(); ++i) {
    const SizedPartType& info = infos.at(part_types[i]);
    const Placement& p = placed[i];
    if (front) {
      drawPart(coverage, cv::Mat(), placedShape(info.shape, p.x, p.y, p.angle_deg), 1.0);
    } else {
      drawPart(base_, light_, placedShape(info.shape, p.x, p.y, p.angle_deg),
               o.part_level - o.background_level);
    }
    PartTruth t;
    t.type = part_types[i];
    t.x = p.x;
    t.y = p.y;
    t.angle_deg = p.angle_deg;
    t.symmetry_deg = info.symmetry;
    t.area_px = info.area;
    t.touching = touching[i];
    truth_.push_back(std::move(t));
  }
  if (front) {
    cv::min(coverage, 1.0, coverage);
    const cv::Mat lamp =
        light_.empty() ? cv::Mat(o.height, o.width, CV_32F, cv::Scalar(1)) : light_;
    base_ = detail::shadeFrontLit(coverage, lamp, o.front, o.part_level, o.background_level, o.seed)
                .front();
  }
  renderClean(nullptr, nullptr, std::nullopt);

  if (o.noise_sigma > 0) {
    cv::RNG noise_rng(splitMix64(o.seed ^ kNoiseStream) | 1);
    for (int k = 0; k < kNoiseBankSize; ++k) {
      cv::Mat field(o.height, o.width, CV_16SC1);
      noise_rng.fill(field, cv::RNG::NORMAL, 0.0, o.noise_sigma);
      noise_bank_.push_back(std::move(field));
    }
  }
}

void SceneRenderer::setTarget(const RobotCamera& camera, const CalibrationTarget& target,
                              std::optional<cv::Point2d> at_mm) {
  renderClean(&camera, &target, at_mm);
}

void SceneRenderer::renderClean(const RobotCamera* camera, const CalibrationTarget* target,
                                std::optional<cv::Point2d> at_mm) {
  const SceneOptions& o = options_;
  target_truth_.clear();
  cv::Mat image = base_;
  if (camera && target && at_mm) {
    image = base_.clone();
    target_truth_ = drawTarget(image, light_, RobotCameraModel(*camera, o.width, o.height), *target,
                               *at_mm, o.part_level);
  }
  if (o.blur_sigma > 0) {
    // A symmetric kernel moves no centroid and keeps every area.
    cv::Mat blurred;
    cv::GaussianBlur(image, blurred, cv::Size(), o.blur_sigma, o.blur_sigma, cv::BORDER_REPLICATE);
    image = blurred;
  }
  image.convertTo(clean_, CV_8U);
}

}  // namespace picksight::synthetic
