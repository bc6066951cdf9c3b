// Rendering of a synthetic scene: exact area coverage of polygon parts,
// uneven light, and cheap per-frame noise from a bank of noise fields.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "scene_internals.hpp"

namespace picksight::synthetic {
namespace detail {
namespace {

// Illumination: a linear gradient of +-15% across the half diagonal in a random
// direction, times a vignetting that darkens the corners by 8%.
constexpr double kLightGradient = 0.15;
constexpr double kVignetting = 0.08;

// Adds the exact area coverage of one directed polygon edge to an accumulation
// buffer (the signed-area method of font-rs): cell i of a row holds the change
// of coverage from pixel i-1 to pixel i, so a prefix sum along the row gives
// the winding-weighted area of each pixel covered by the polygon. Coordinates:
// tile pixel (i, j) covers [i, i+1] x [j, j+1]; each row has `stride` >= width
// + 2 cells; the edge must lie inside the tile.
void accumulateEdge(std::vector<double>& acc, int stride, int rows, cv::Point2d p0, cv::Point2d p1,
                    double weight) {
  if (p0.y == p1.y) {
    return;
  }
  double dir = weight;
  if (p0.y > p1.y) {
    std::swap(p0, p1);
    dir = -dir;
  }
  const double dxdy = (p1.x - p0.x) / (p1.y - p0.y);
  double x = p0.x;
  const int y_end = std::min(rows, static_cast<int>(std::ceil(p1.y)));
  for (int y = static_cast<int>(std::floor(p0.y)); y < y_end; ++y) {
    double* row = acc.data() + static_cast<std::ptrdiff_t>(y) * stride;
    const double dy = std::min(y + 1.0, p1.y) - std::max(static_cast<double>(y), p0.y);
    const double x_next = x + dxdy * dy;
    const double d = dy * dir;
    const double x0 = std::min(x, x_next);
    const double x1 = std::max(x, x_next);
    const double x0_floor = std::floor(x0);
    const int x0i = static_cast<int>(x0_floor);
    const double x1_ceil = std::ceil(x1);
    const int x1i = static_cast<int>(x1_ceil);
    if (x1i <= x0i + 1) {
      // Within one pixel: it gets the part right of the edge's mean x.
      const double xmf = 0.5 * (x + x_next) - x0_floor;
      row[x0i] += d - d * xmf;
      row[x0i + 1] += d * xmf;
    } else {
      const double s = 1.0 / (x1 - x0);
      const double x0f = x0 - x0_floor;
      const double a0 = 0.5 * s * (1 - x0f) * (1 - x0f);
      const double x1f = x1 - x1_ceil + 1;
      const double am = 0.5 * s * x1f * x1f;
      row[x0i] += d * a0;
      if (x1i == x0i + 2) {
        row[x0i + 1] += d * (1 - a0 - am);
      } else {
        const double a1 = s * (1.5 - x0f);
        row[x0i + 1] += d * (a1 - a0);
        for (int xi = x0i + 2; xi < x1i - 1; ++xi) {
          row[xi] += d * s;
        }
        const double a2 = a1 + (x1i - x0i - 3) * s;
        row[x1i - 1] += d * (1 - a2 - am);
      }
      row[x1i] += d * am;
    }
    x = x_next;
  }
}

}  // namespace

void drawPart(cv::Mat& image, const cv::Mat& light, const Shape& placed, double delta_level) {
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  for (const cv::Point2d& p : placed.loops.at(0)) {
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y);
    max_y = std::max(max_y, p.y);
  }
  // Pixel u covers [u - 0.5, u + 0.5], so the pixel holding coordinate x is
  // floor(x + 0.5) and tile coordinates are x + 0.5 - first column.
  const int x0 = static_cast<int>(std::floor(min_x + 0.5));
  const int y0 = static_cast<int>(std::floor(min_y + 0.5));
  const int width = static_cast<int>(std::floor(max_x + 0.5)) - x0 + 1;
  const int rows = static_cast<int>(std::floor(max_y + 0.5)) - y0 + 1;
  const int stride = width + 2;
  std::vector<double> acc(static_cast<std::size_t>(stride) * rows, 0.0);
  for (std::size_t k = 0; k < placed.loops.size(); ++k) {
    const Loop& loop = placed.loops[k];
    const double weight = loopWeight(placed, k);
    for (std::size_t i = 0, n = loop.size(); i < n; ++i) {
      const cv::Point2d& a = loop[i];
      const cv::Point2d& b = loop[(i + 1) % n];
      accumulateEdge(acc, stride, rows, {a.x + 0.5 - x0, a.y + 0.5 - y0},
                     {b.x + 0.5 - x0, b.y + 0.5 - y0}, weight);
    }
  }
  for (int j = 0; j < rows; ++j) {
    const int y = y0 + j;
    if (y < 0 || y >= image.rows) {
      continue;
    }
    float* out = image.ptr<float>(y);
    const float* lit = light.empty() ? nullptr : light.ptr<float>(y);
    const double* cells = acc.data() + static_cast<std::ptrdiff_t>(j) * stride;
    double sum = 0;
    for (int i = 0; i < width; ++i) {
      sum += cells[i];
      const int x = x0 + i;
      // Rounding leaves ~1e-16 where the coverage is 0 or 1.
      const double coverage = std::min(1.0, std::abs(sum));
      if (coverage < 1e-12 || x < 0 || x >= image.cols) {
        continue;
      }
      const double l = lit ? lit[x] : 1.0;
      out[x] = static_cast<float>(out[x] + coverage * delta_level * l);
    }
  }
}

cv::Mat illumination(int width, int height, uint64_t seed) {
  std::mt19937_64 rng(splitMix64(seed ^ kLightStream));
  const double dir = uniform(rng, 0, 2 * kPi);
  const double gx = std::cos(dir);
  const double gy = std::sin(dir);
  const double cx = 0.5 * (width - 1);
  const double cy = 0.5 * (height - 1);
  const double half_diag = 0.5 * std::hypot(width, height);
  cv::Mat light(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    float* row = light.ptr<float>(y);
    const double dy = (y - cy) / half_diag;
    for (int x = 0; x < width; ++x) {
      const double dx = (x - cx) / half_diag;
      const double gradient = 1 + kLightGradient * (gx * dx + gy * dy);
      const double vignette = 1 - kVignetting * (dx * dx + dy * dy);
      row[x] = static_cast<float>(gradient * vignette);
    }
  }
  return light;
}

void addNoiseRow(const uint8_t* clean, const int16_t* noise, uint8_t* out, int n) {
  int i = 0;
#if CV_SIMD128
  for (; i + 16 <= n; i += 16) {
    cv::v_uint16x8 c0, c1;
    cv::v_expand(cv::v_load(clean + i), c0, c1);
    const cv::v_int16x8 s0 = cv::v_reinterpret_as_s16(c0) + cv::v_load(noise + i);
    const cv::v_int16x8 s1 = cv::v_reinterpret_as_s16(c1) + cv::v_load(noise + i + 8);
    cv::v_store(out + i, cv::v_pack_u(s0, s1));
  }
#endif
  for (; i < n; ++i) {
    out[i] = cv::saturate_cast<uint8_t>(clean[i] + noise[i]);
  }
}

}  // namespace detail

using detail::addNoiseRow;
using detail::kFrameStream;
using detail::splitMix64;

cv::Mat SceneRenderer::render(uint64_t frame_index) const {
  cv::Mat out;
  renderInto(frame_index, out);
  return out;
}

void SceneRenderer::renderInto(uint64_t frame_index, cv::Mat& out) const {
  // A header sharing clean_'s pixels must not be written through.
  if (out.data == clean_.data) {
    out = cv::Mat();
  }
  if (noise_bank_.empty()) {
    clean_.copyTo(out);
    return;
  }
  out.create(clean_.size(), CV_8UC1);
  const uint64_t h = splitMix64(splitMix64(options_.seed ^ kFrameStream) + frame_index);
  const cv::Mat& noise = noise_bank_[h % noise_bank_.size()];
  const int w = clean_.cols;
  const int dx = static_cast<int>((h >> 16) % static_cast<uint64_t>(w));
  const int dy = static_cast<int>((h >> 40) % static_cast<uint64_t>(clean_.rows));
  for (int y = 0; y < clean_.rows; ++y) {
    const uint8_t* c = clean_.ptr<uint8_t>(y);
    const int16_t* n = noise.ptr<int16_t>((y + dy) % clean_.rows);
    uint8_t* o = out.ptr<uint8_t>(y);
    addNoiseRow(c, n + dx, o, w - dx);
    addNoiseRow(c + (w - dx), n, o + (w - dx), dx);
  }
}

}  // namespace picksight::synthetic
