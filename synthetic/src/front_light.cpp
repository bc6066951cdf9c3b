// Front-lit silhouette scenes: surface textures, shading, cast shadows,
// glints and colour, each from its own seeded stream.
#include "picksight/synthetic/front_light.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "scene_internals.hpp"

namespace picksight::synthetic {
namespace {
constexpr uint64_t kTextureStream = 0x74657874ULL;
constexpr uint64_t kShadingStream = 0x7368616465ULL;
constexpr uint64_t kGlintStream = 0x676c696e74ULL;

// White noise at 1/`step` of the size, smoothed there and brought up to
// `size`: a field whose detail is about `step` pixels, for the cost of a
// small image. Zero mean, unit standard deviation.
cv::Mat lowResolutionNoise(cv::Size size, double step, std::mt19937_64& rng) {
  const int w = std::max(2, static_cast<int>(std::ceil(size.width / step)) + 2);
  const int h = std::max(2, static_cast<int>(std::ceil(size.height / step)) + 2);
  cv::Mat small(h, w, CV_32F);
  cv::RNG cv_rng(rng() | 1);
  cv_rng.fill(small, cv::RNG::NORMAL, 0, 1);
  cv::GaussianBlur(small, small, cv::Size(0, 0), 0.8);
  cv::Mat big;
  cv::resize(small, big, size, 0, 0, cv::INTER_CUBIC);
  cv::Scalar mean;
  cv::Scalar sd;
  cv::meanStdDev(big, mean, sd);
  big = (big - mean[0]) / std::max(1e-6, sd[0]);
  return big;
}

// `m` scaled to unit standard deviation (its mean kept).
cv::Mat unitSpread(const cv::Mat& m) {
  cv::Scalar mean;
  cv::Scalar sd;
  cv::meanStdDev(m, mean, sd);
  return m / std::max(1e-6, sd[0]);
}

cv::Mat whiteNoise(cv::Size size, double sigma, std::mt19937_64& rng) {
  cv::Mat n(size, CV_32F);
  cv::RNG cv_rng(rng() | 1);
  cv_rng.fill(n, cv::RNG::NORMAL, 0, sigma);
  return n;
}

// Where each part's glints lie: a few points well inside each connected
// part of `coverage`, each drawn as an elongated Gaussian spot (CV_32F,
// peak 1).
cv::Mat glintField(const cv::Mat& coverage, const FrontLight& f, uint64_t seed) {
  cv::Mat glints = cv::Mat::zeros(coverage.size(), CV_32F);
  if (f.glints_per_part <= 0 || f.glint_radius_px <= 0) return glints;
  cv::Mat inside;
  cv::threshold(coverage, inside, 0.99, 255, cv::THRESH_BINARY);
  inside.convertTo(inside, CV_8U);
  // Glints lie a glint's length inside the part, so that each is a
  // highlight on the part rather than a notch in its outline.
  const int margin = static_cast<int>(std::ceil(2.5 * f.glint_radius_px)) + 1;
  cv::erode(inside, inside,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  cv::Mat labels;
  const int n = cv::connectedComponents(inside, labels, 8, CV_32S);
  std::vector<std::vector<cv::Point>> pixels(static_cast<size_t>(std::max(0, n)));
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] > 0) pixels[static_cast<size_t>(l[x])].emplace_back(x, y);
    }
  }
  std::mt19937_64 rng(detail::splitMix64(seed ^ kGlintStream));
  const double r = f.glint_radius_px;
  const int reach = static_cast<int>(std::ceil(3 * 2 * r));
  for (const auto& part : pixels) {
    if (part.empty()) continue;
    for (int g = 0; g < f.glints_per_part; ++g) {
      const cv::Point c = part[static_cast<size_t>(rng() % part.size())];
      const double phi = detail::uniform(rng, 0, detail::kPi);
      const double cs = std::cos(phi);
      const double sn = std::sin(phi);
      for (int dy = -reach; dy <= reach; ++dy) {
        const int y = c.y + dy;
        if (y < 0 || y >= glints.rows) continue;
        float* row = glints.ptr<float>(y);
        for (int dx = -reach; dx <= reach; ++dx) {
          const int x = c.x + dx;
          if (x < 0 || x >= glints.cols) continue;
          const double along = (dx * cs + dy * sn) / (2 * r);
          const double across = (-dx * sn + dy * cs) / r;
          const double v = std::exp(-0.5 * (along * along + across * across) * 4);
          row[x] = std::max(row[x], static_cast<float>(v));
        }
      }
    }
  }
  return glints;
}
}  // namespace

const char* surfaceName(Surface s) {
  switch (s) {
    case Surface::kPlain:
      return "plain";
    case Surface::kBelt:
      return "belt";
    case Surface::kWood:
      return "wood";
    case Surface::kBrushedMetal:
      return "brushed metal";
    case Surface::kPhotographed:
      return "photographed";
  }
  return "?";
}

bool FrontLight::any() const {
  return texture > 0 || gradient != 0 || vignette != 0 || part_shading != 0 ||
         shadow_offset_px > 0 || glints_per_part > 0 || colour;
}

std::vector<std::string> frontLightConditionNames() {
  return {"clean", "textured", "shadow", "glossy", "low-contrast", "colour", "wood", "metal"};
}

bool frontLightCondition(const std::string& name, FrontLight* light, double* part_level,
                         double* background_level) {
  FrontLight f;
  double part = 45;
  double background = 200;
  // The textured belt every front-lit condition starts from.
  const auto textured = [&f] {
    f.surface = Surface::kBelt;
    f.texture = 0.06;
    f.gradient = 0.3;
    f.vignette = 0.3;
    f.part_shading = 0.15;
  };
  if (name == "clean") {
  } else if (name == "textured") {
    textured();
  } else if (name == "shadow") {
    textured();
    f.shadow_offset_px = 8;
    f.shadow_softness_px = 3;
    f.shadow_depth = 0.45;
  } else if (name == "glossy") {
    textured();
    f.glints_per_part = 2;
    f.glint_radius_px = 3;
    part = 85;
    background = 150;
  } else if (name == "low-contrast") {
    textured();
    f.texture = 0.04;
    part = 100;
    background = 130;
  } else if (name == "colour") {
    f.surface = Surface::kBelt;
    f.texture = 0.04;
    f.gradient = 0.2;
    f.vignette = 0.2;
    f.colour = true;
    // A green part on a grey surface of the same brightness: in grey the
    // two are one level.
    f.part_bgr = {60, 160, 70};
    f.background_bgr = {122, 122, 122};
    part = 122;
    background = 122;
  } else if (name == "wood") {
    f.surface = Surface::kWood;
    f.texture = 0.08;
    f.vignette = 0.3;
    f.part_shading = 0.1;
  } else if (name == "metal") {
    f.surface = Surface::kBrushedMetal;
    f.texture = 0.06;
    f.vignette = 0.3;
    f.part_shading = 0.1;
  } else {
    return false;
  }
  *light = f;
  *part_level = part;
  *background_level = background;
  return true;
}

std::vector<std::string> photographedConditionNames() { return {"brick", "gravel"}; }

bool photographedCondition(const std::string& name, const cv::Mat& photo, FrontLight* light,
                           double* part_level, double* background_level) {
  const auto names = photographedConditionNames();
  if (std::find(names.begin(), names.end(), name) == names.end() || photo.empty()) return false;
  CV_Assert(photo.type() == CV_8UC1);
  FrontLight f;
  double part = 0;
  double background = 0;
  frontLightCondition("low-contrast", &f, &part, &background);
  f.surface = Surface::kPhotographed;
  f.surface_photo = photo;
  *light = f;
  *part_level = part;
  *background_level = background;
  return true;
}

namespace detail {

cv::Mat smoothField(cv::Size size, double scale_px, uint64_t seed) {
  std::mt19937_64 rng(splitMix64(seed ^ kShadingStream));
  cv::Mat f = lowResolutionNoise(size, scale_px, rng);
  // Unit deviation to about [-1, 1].
  return cv::min(cv::max(f * 0.5, -1.0), 1.0);
}

cv::Mat surfaceTexture(cv::Size size, Surface surface, double amplitude, uint64_t seed,
                       const cv::Mat& photo) {
  cv::Mat t(size, CV_32F, cv::Scalar(1));
  if (surface == Surface::kPlain || amplitude <= 0) return t;
  std::mt19937_64 rng(splitMix64(seed ^ kTextureStream));
  cv::Mat dev;
  switch (surface) {
    case Surface::kBelt: {
      // Fine grain (a pixel or two), blotches (tens of pixels) and wear
      // (hundreds): a conveyor belt's rubber.
      cv::Mat grain = whiteNoise(size, 1, rng);
      cv::GaussianBlur(grain, grain, cv::Size(0, 0), 0.8);
      dev = 0.5 * unitSpread(grain) + 0.7 * lowResolutionNoise(size, 24, rng) +
            0.5 * lowResolutionNoise(size, 160, rng);
      break;
    }
    case Surface::kWood: {
      // Rings across y, wavering along x, with grain streaks along x.
      const cv::Mat waver = lowResolutionNoise(size, 120, rng);
      const double period = 23;
      dev = cv::Mat(size, CV_32F);
      for (int y = 0; y < size.height; ++y) {
        const float* w = waver.ptr<float>(y);
        float* d = dev.ptr<float>(y);
        for (int x = 0; x < size.width; ++x) {
          const double phase = 2 * kPi * (y + 12 * w[x]) / period;
          d[x] = static_cast<float>(std::pow(0.5 + 0.5 * std::sin(phase), 3) * 2 - 0.5);
        }
      }
      cv::Mat streaks = whiteNoise(size, 1, rng);
      cv::GaussianBlur(streaks, streaks, cv::Size(0, 0), 12, 0.7);
      dev = dev + 0.6 * unitSpread(streaks);
      break;
    }
    case Surface::kBrushedMetal: {
      // Long thin streaks along x, and a slow sheen.
      cv::Mat streaks = whiteNoise(size, 1, rng);
      cv::GaussianBlur(streaks, streaks, cv::Size(0, 0), 30, 0.6);
      dev = unitSpread(streaks) + 0.6 * lowResolutionNoise(size, 300, rng);
      break;
    }
    case Surface::kPhotographed: {
      // Mirrored at its borders as often as the frame needs, from an
      // offset within the photograph.
      CV_Assert(photo.type() == CV_8UC1 && !photo.empty());
      const int ox = static_cast<int>(rng() % static_cast<uint64_t>(photo.cols));
      const int oy = static_cast<int>(rng() % static_cast<uint64_t>(photo.rows));
      const auto mirrored = [](int i, int n) {
        const int k = i % (2 * n);
        return k < n ? k : 2 * n - 1 - k;
      };
      std::vector<int> xs(static_cast<size_t>(size.width));
      for (int x = 0; x < size.width; ++x)
        xs[static_cast<size_t>(x)] = mirrored(x + ox, photo.cols);
      dev = cv::Mat(size, CV_32F);
      for (int y = 0; y < size.height; ++y) {
        const uint8_t* in = photo.ptr<uint8_t>(mirrored(y + oy, photo.rows));
        float* d = dev.ptr<float>(y);
        for (int x = 0; x < size.width; ++x) d[x] = in[xs[static_cast<size_t>(x)]];
      }
      break;
    }
    case Surface::kPlain:
      break;
  }
  cv::Scalar m;
  cv::Scalar sd;
  cv::meanStdDev(dev, m, sd);
  t = 1.0 + (dev - m[0]) * (amplitude / std::max(1e-6, sd[0]));
  return cv::max(t, 0.05);
}

std::vector<cv::Mat> shadeFrontLit(const cv::Mat& coverage, const cv::Mat& light,
                                   const FrontLight& f, double part_level, double background_level,
                                   uint64_t seed) {
  const cv::Size size = coverage.size();
  // The light: the scene's own gain, a fall-off across x and y and a vignette.
  cv::Mat lamp = light.clone();
  if (f.gradient != 0 || f.vignette != 0) {
    std::mt19937_64 rng(splitMix64(seed ^ kLightStream ^ 0x66726f6e74ULL));
    const double dir = uniform(rng, 0, 2 * kPi);
    const double gx = f.gradient * std::cos(dir);
    const double gy = f.gradient * std::sin(dir);
    for (int y = 0; y < size.height; ++y) {
      float* l = lamp.ptr<float>(y);
      const double v = (y + 0.5) / size.height - 0.5;
      for (int x = 0; x < size.width; ++x) {
        const double u = (x + 0.5) / size.width - 0.5;
        l[x] *= static_cast<float>(1.0 + gx * u + gy * v - 2 * f.vignette * (u * u + v * v));
      }
    }
  }
  const cv::Mat surface = surfaceTexture(size, f.surface, f.texture, seed, f.surface_photo);
  cv::Mat shading(size, CV_32F, cv::Scalar(1));
  if (f.part_shading != 0) {
    shading = 1.0 + f.part_shading * smoothField(size, 150, seed);
  }
  // The shadow falls on the surface only (the part lies over it).
  cv::Mat shadow = cv::Mat::zeros(size, CV_32F);
  if (f.shadow_offset_px > 0) {
    const double a = f.shadow_angle_deg * kPi / 180.0;
    const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, f.shadow_offset_px * std::cos(a), 0, 1,
                           f.shadow_offset_px * std::sin(a));
    cv::warpAffine(coverage, shadow, shift, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                   cv::Scalar(0));
    if (f.shadow_softness_px > 0) {
      cv::GaussianBlur(shadow, shadow, cv::Size(0, 0), f.shadow_softness_px);
    }
  }
  const cv::Mat glints = glintField(coverage, f, seed);
  const int channels = f.colour ? 3 : 1;
  std::vector<cv::Mat> planes;
  for (int ch = 0; ch < channels; ++ch) {
    const double part = f.colour ? f.part_bgr[static_cast<size_t>(ch)] : part_level;
    const double back = f.colour ? f.background_bgr[static_cast<size_t>(ch)] : background_level;
    cv::Mat plane(size, CV_32F);
    for (int y = 0; y < size.height; ++y) {
      const float* c = coverage.ptr<float>(y);
      const float* l = lamp.ptr<float>(y);
      const float* t = surface.ptr<float>(y);
      const float* s = shading.ptr<float>(y);
      const float* sh = shadow.ptr<float>(y);
      const float* g = glints.ptr<float>(y);
      float* out = plane.ptr<float>(y);
      for (int x = 0; x < size.width; ++x) {
        const double under = back * t[x] * (1.0 - f.shadow_depth * std::min(1.0f, sh[x]));
        const double on = part * s[x];
        double v = l[x] * ((1.0 - c[x]) * under + c[x] * on);
        // A glint is the lamp's own reflection: as bright as the lamp makes
        // it, whatever the part's colour.
        v += g[x] * c[x] * std::max(0.0, f.glint_level - v);
        out[x] = static_cast<float>(v);
      }
    }
    planes.push_back(plane);
  }
  return planes;
}

}  // namespace detail
}  // namespace picksight::synthetic
