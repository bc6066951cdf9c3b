// The light of a front-lit cell for silhouette scenes: a textured surface
// (belt, wood, brushed metal, or a photograph of a real one), a stronger gradient and vignetting,
// shaded parts, a soft cast shadow beside each part, specular glints on the parts, and colour.
// Everything is off by default (the back-lit look the scenes had before); the truth is always the
// part's drawn mask, never its shadow.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace picksight::synthetic {

enum class Surface { kPlain, kBelt, kWood, kBrushedMetal, kPhotographed };
const char* surfaceName(Surface s);

struct FrontLight {
  Surface surface = Surface::kPlain;
  // The surface's texture, as a fraction of its grey level: the standard
  // deviation of fine grain plus large blotches (belt), grain and rings
  // (wood), or streaks along x (brushed metal); a photographed surface's
  // own pattern (its shape kept) takes this deviation too.
  double texture = 0;
  // kPhotographed: the photograph of a real surface (CV_8UC1), mirrored
  // across the frame from an offset the seed picks: a texture nobody here
  // drew, with the sharp steps, straight lines and clutter of real ones.
  cv::Mat surface_photo;
  // Light across the frame beyond the scenes' own uneven light: a linear
  // fall-off (fraction of the level from one side to the other) and a
  // vignette (fraction lost in the corners).
  double gradient = 0;
  double vignette = 0;
  // Parts not flat: their level varies by this fraction over a few part
  // widths (a curved or tilted face under a lamp).
  double part_shading = 0;
  // Cast shadow: the part's silhouette moved `shadow_offset_px` along
  // `shadow_angle_deg` (image axes, from x towards y), blurred by
  // `shadow_softness_px`, taking `shadow_depth` of the surface's light.
  double shadow_offset_px = 0;
  double shadow_angle_deg = 45;
  double shadow_softness_px = 2;
  double shadow_depth = 0.4;
  // Specular glints on each part: small elongated highlights at this grey
  // level (saturating), `glint_radius_px` across.
  int glints_per_part = 0;
  double glint_radius_px = 3;
  double glint_level = 255;
  // Colour (the scene renders BGR when set): the part and the surface as
  // BGR levels under full light. Grey scenes use part_level and
  // background_level instead.
  bool colour = false;
  std::array<double, 3> part_bgr = {60, 160, 70};
  std::array<double, 3> background_bgr = {150, 150, 150};

  bool any() const;
};

// Named conditions for benchmarks and tests: "clean" (no front light),
// "textured" (belt texture, vignetting, gradient, shaded parts), "shadow"
// (textured plus a soft cast shadow), "glossy" (textured plus glints, parts
// at 85 on a surface at 150), "low-contrast" (textured, 30 grey levels
// between part and surface), "colour" (a green part on a grey surface of the
// same brightness), "wood", "metal" (other surfaces). Each sets the light and
// the grey levels (`part_level`, `background_level`). False for an unknown name.
bool frontLightCondition(const std::string& name, FrontLight* light, double* part_level,
                         double* background_level);
std::vector<std::string> frontLightConditionNames();

// Conditions on a photographed surface (the caller loads the photograph,
// `surfaces/<name>.png` of the test data): "brick" (paving bricks: straight
// light joints, each brick its own shade) and "gravel" (sharp stones and
// dark gaps), both under the light of "low-contrast" (30 grey levels between
// part and surface, the surface's pattern 4 % of its level). False for an
// unknown name or an empty photograph.
bool photographedCondition(const std::string& name, const cv::Mat& photo, FrontLight* light,
                           double* part_level, double* background_level);
std::vector<std::string> photographedConditionNames();

namespace detail {
// The surface's reflectance around 1 (CV_32F), from the seed (and, for
// kPhotographed, `photo`).
cv::Mat surfaceTexture(cv::Size size, Surface surface, double amplitude, uint64_t seed,
                       const cv::Mat& photo = cv::Mat());
// A smooth field in [-1, 1] varying over about `scale_px` (CV_32F).
cv::Mat smoothField(cv::Size size, double scale_px, uint64_t seed);
// Shades `coverage` (CV_32F, 1 on the part) under the front light into one
// CV_32F plane per channel (one for grey, three for colour, BGR), before blur
// and noise. `light` is the scene's own gain per pixel (CV_32F).
std::vector<cv::Mat> shadeFrontLit(const cv::Mat& coverage, const cv::Mat& light,
                                   const FrontLight& f, double part_level, double background_level,
                                   uint64_t seed);
}  // namespace detail

}  // namespace picksight::synthetic
