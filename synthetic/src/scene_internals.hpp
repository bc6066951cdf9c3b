// What the synthetic scene's source files share: the seeded random streams,
// the part layout (layout.cpp) and the rasterizer and noise (rendering.cpp).
// Not installed: only the library's own files include it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/synthetic/scene.hpp"

namespace picksight::synthetic::detail {

constexpr double kPi = 3.14159265358979323846;

using Loop = std::vector<cv::Point2d>;

// Shoelace area; its sign gives the winding (positive: outer loops here).
inline double signedArea(const Loop& loop) {
  double twice = 0;
  for (std::size_t i = 0, n = loop.size(); i < n; ++i) {
    const cv::Point2d& a = loop[i];
    const cv::Point2d& b = loop[(i + 1) % n];
    twice += a.x * b.y - b.x * a.y;
  }
  return 0.5 * twice;
}

// +1 for the outer loop and -1 for holes when walked with outer-positive
// winding; multiplies a loop's signed integrals whatever its actual winding.
inline double loopWeight(const Shape& shape, std::size_t k) {
  const double s = signedArea(shape.loops[k]) >= 0 ? 1.0 : -1.0;
  return k == 0 ? s : -s;
}

// Independent random streams derived from the seed, so that e.g. turning the
// uneven light off leaves the layout unchanged.
constexpr uint64_t kLightStream = 0x6c69676874ULL;
constexpr uint64_t kNoiseStream = 0x6e6f697365ULL;
constexpr uint64_t kFrameStream = 0x6672616d65ULL;

inline uint64_t splitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// std::uniform_*_distribution differ between standard libraries; these do not,
// so a seed gives the same scene everywhere.
inline double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * uniform01(rng);
}

// --- Layout (layout.cpp)

// Layout: parts keep this many pixels from the image border and their bounding
// circles this many pixels from each other, so no part touches the border and
// a part's neighbourhood (bounding circle + a few px) holds no other part.
constexpr double kBorderMarginPx = 4.0;
constexpr double kGapPx = 8.0;
constexpr int kAttemptsPerPart = 2000;
// Random sequential placement of discs jams near 55% coverage; past 40% the
// attempts mostly fail, so such layouts shrink the parts without trying.
constexpr double kMaxFill = 0.40;
constexpr double kShrinkFactor = 0.9;
constexpr int kMaxShrinkRounds = 80;
constexpr double kMinPartSizePx = 8.0;

// A part type drawn at the scene's part size, with what layout and truth need.
struct SizedPartType {
  Shape shape;
  double radius = 0;  // bounding circle about the centroid
  double area = 0;
  double symmetry = 360;
};

struct Placement {
  double x = 0;
  double y = 0;
  double angle_deg = 0;
};

// Random sequential placement; false when a part finds no free spot.
bool tryLayout(const SceneOptions& o, const std::vector<const SizedPartType*>& parts,
               std::mt19937_64& rng, std::vector<Placement>& placed);
// Moves part `i` against part `anchor` from a random side until their edges
// meet; false (leaving it alone) when no side gives a free spot.
bool moveIntoContact(const SceneOptions& o, const std::vector<const SizedPartType*>& parts,
                     std::size_t i, std::size_t anchor, std::mt19937_64& rng,
                     std::vector<Placement>& placed);

// --- Rendering (rendering.cpp)

// Two full-frame noise fields, each read at a per-frame random 2D roll: about
// 2*W*H distinct frames, for 8 MB at 1920x1080 and no per-frame generation.
constexpr int kNoiseBankSize = 2;

// Darkens `image` (CV_32F, background already in) by the exact area coverage
// of `placed`: pixel += coverage * (part - background) * light.
void drawPart(cv::Mat& image, const cv::Mat& light, const Shape& placed, double delta_level);
// Uneven light: a gain per pixel, from the seed's light stream.
cv::Mat illumination(int width, int height, uint64_t seed);
// out[i] = saturate(clean[i] + noise[i]) for n pixels.
void addNoiseRow(const uint8_t* clean, const int16_t* noise, uint8_t* out, int n);

}  // namespace picksight::synthetic::detail
