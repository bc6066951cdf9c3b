// Synthetic scenes: exact polygon parts, exact area-coverage rendering, cheap per-frame noise.
#include "picksight/synthetic/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

namespace picksight::synthetic {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Largest distance between a true arc and its polygon, in pixels: well below
// what a camera resolves. The truth is the polygon itself, so this only decides
// how round curves look, not how exact the truth is.
constexpr double kMaxChordErrorPx = 0.05;
constexpr int kMinArcSegmentsPerTurn = 24;

// Inertia counts as isotropic when ((mu20 - mu02)^2 + 4 mu11^2) / (mu20 + mu02)^2
// is below this, i.e. eigenvalues within ~6% of each other. There a relative
// moment error of 1e-4 (pixelation of a 100 px part) already turns the axis by
// ~0.2 deg and it is meaningless; our isotropic part (gear) sits at ~1e-30, the
// least anisotropic directed one (disc_holes) at ~2e-2.
constexpr double kIsotropyRatio = 1e-3;
// The direction along the axis is ambiguous when the part's reaches from the
// centroid along it (forward and backward) differ by less than this fraction of
// its length along the axis: a vision app decides from pixels, so a few percent
// (3.6 px at 120 px) is the least it can tell reliably. l_shape: 10%,
// disc_holes: 6.5%, rectangle: 0.
constexpr double kDirectionTolerance = 0.03;

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

// Illumination: a linear gradient of +-15% across the half diagonal in a random
// direction, times a vignetting that darkens the corners by 8%.
constexpr double kLightGradient = 0.15;
constexpr double kVignetting = 0.08;

// Two full-frame noise fields, each read at a per-frame random 2D roll: about
// 2*W*H distinct frames, for 8 MB at 1920x1080 and no per-frame generation.
constexpr int kNoiseBankSize = 2;

// Independent random streams derived from the seed, so that e.g. turning the
// uneven light off leaves the layout unchanged.
constexpr uint64_t kLightStream = 0x6c69676874ULL;
constexpr uint64_t kNoiseStream = 0x6e6f697365ULL;
constexpr uint64_t kFrameStream = 0x6672616d65ULL;

uint64_t splitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// std::uniform_*_distribution differ between standard libraries; these do not,
// so a seed gives the same scene everywhere.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * uniform01(rng);
}

using Loop = std::vector<cv::Point2d>;

double signedArea(const Loop& loop) {
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
double loopWeight(const Shape& shape, std::size_t k) {
  const double s = signedArea(shape.loops[k]) >= 0 ? 1.0 : -1.0;
  return k == 0 ? s : -s;
}

int arcSegments(double radius, double sweep_rad) {
  const double step = 2.0 * std::acos(1.0 - std::min(kMaxChordErrorPx / radius, 1.0));
  const int by_error = static_cast<int>(std::ceil(sweep_rad / step));
  const int by_turn = static_cast<int>(std::ceil(sweep_rad / (2 * kPi) * kMinArcSegmentsPerTurn));
  return std::max({by_error, by_turn, 1});
}

// Points of an arc from a0 to a1 (radians), both ends included.
void appendArc(Loop& loop, cv::Point2d centre, double radius, double a0, double a1) {
  const int n = arcSegments(radius, std::abs(a1 - a0));
  for (int i = 0; i <= n; ++i) {
    const double a = a0 + (a1 - a0) * i / n;
    loop.emplace_back(centre.x + radius * std::cos(a), centre.y + radius * std::sin(a));
  }
}

Loop circleLoop(cv::Point2d centre, double radius) {
  Loop loop;
  // A multiple of 4 puts vertices on both ends of each axis: the polygon spans
  // the full diameter.
  const int n = (arcSegments(radius, 2 * kPi) + 3) / 4 * 4;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    loop.emplace_back(centre.x + radius * std::cos(a), centre.y + radius * std::sin(a));
  }
  return loop;
}

bool isIsotropic(const ShapeMoments& m) {
  const double d = m.mu20 - m.mu02;
  const double s = m.mu20 + m.mu02;
  return d * d + 4 * m.mu11 * m.mu11 < kIsotropyRatio * s * s;
}

double axisAngle(const ShapeMoments& m) { return 0.5 * std::atan2(2 * m.mu11, m.mu20 - m.mu02); }

// How far the outer boundary reaches from the centroid along the axis at
// `angle`, forward (first) and backward (second).
std::pair<double, double> axisReach(const Shape& shape, const ShapeMoments& m, double angle) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  double fwd = -1e300;
  double back = 1e300;
  for (const cv::Point2d& p : shape.loops.at(0)) {
    const double t = (p.x - m.cx) * c + (p.y - m.cy) * s;
    fwd = std::max(fwd, t);
    back = std::min(back, t);
  }
  return {fwd, -back};
}

void transformShape(Shape& shape, double tx, double ty, double angle_rad) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  for (Loop& loop : shape.loops) {
    for (cv::Point2d& p : loop) {
      p = {tx + p.x * c - p.y * s, ty + p.x * s + p.y * c};
    }
  }
}

// Outer loop positive (shoelace, image axes), holes negative: the renderer and
// users walking the loops see one winding convention.
void orientLoops(Shape& shape) {
  for (std::size_t k = 0; k < shape.loops.size(); ++k) {
    const bool positive = signedArea(shape.loops[k]) >= 0;
    if (positive != (k == 0)) {
      std::reverse(shape.loops[k].begin(), shape.loops[k].end());
    }
  }
}

// Centroid to the origin, axis of least second moment to +x, +x to the longer
// reach (SPEC section 3). Isotropic shapes have no axis: their design frame is
// kept (the gear has a tooth on +x), only centred.
Shape canonicalize(Shape shape) {
  const ShapeMoments m = shapeMoments(shape);
  transformShape(shape, -m.cx, -m.cy, 0.0);
  if (!isIsotropic(m)) {
    transformShape(shape, 0.0, 0.0, -axisAngle(m));
    ShapeMoments centred = m;
    centred.cx = centred.cy = 0;
    const auto [fwd, back] = axisReach(shape, centred, 0.0);
    if (back > fwd) {
      for (Loop& loop : shape.loops) {
        for (cv::Point2d& p : loop) {
          p = -p;  // exactly, where a rotation by pi would mix in sin(pi) ~ 1e-16
        }
      }
    }
  }
  orientLoops(shape);
  return shape;
}

// 2.1:1 rather than 2:1 keeps its area (0.476 size^2) >= 8% away from the gear's
// and disc_holes', so that area alone tells every type from the others (but a
// part from its mirror image).
Shape rectangleDesign(double size) {
  const double a = size / 2;
  const double b = size / 4.2;
  return Shape{{{{-a, -b}, {a, -b}, {a, b}, {-a, b}}}};
}

Shape lShapeDesign(double size) {
  const double leg = size;        // long leg, the longest side
  const double arm = 0.6 * size;  // short leg
  const double thick = 0.3 * size;
  return Shape{{{{0, 0}, {leg, 0}, {leg, thick}, {thick, thick}, {thick, arm}, {0, arm}}}};
}

// Two holes of different radius whose centres are not in line with the disc's:
// no mirror or rotational symmetry. Their placement (found by a search over
// radii, distances and angle with walls >= 0.1 R) maximizes the conditioning:
// anisotropy sqrt((mu20-mu02)^2+4mu11^2)/(mu20+mu02) ~ 0.15 and the two reaches
// along the axis differ by ~6.5% of the length. A disc with two holes cannot do
// much better: a hole shifts the centroid away from itself but removes spread
// along its own direction, turning the major axis away from that shift.
Shape discHolesDesign(double size) {
  const double r = size / 2;
  const double a2 = 145.0 * kPi / 180.0;
  Shape shape;
  shape.loops.push_back(circleLoop({0, 0}, r));
  shape.loops.push_back(circleLoop({0.45 * r, 0}, 0.45 * r));
  shape.loops.push_back(circleLoop({0.55 * r * std::cos(a2), 0.55 * r * std::sin(a2)}, 0.34 * r));
  return shape;
}

// 12 trapezoidal teeth and a bore (sized for an area 0.435 size^2, between
// l_shape's 0.39 and rectangle's 0.476). Every tooth is the same template turned by
// a multiple of 30 deg, so the inertia is isotropic to rounding.
Shape gearDesign(double size) {
  constexpr int kTeeth = 12;
  const double tip = size / 2;
  const double root = 0.78 * tip;
  const double deg = kPi / 180;
  Loop outer;
  for (int k = 0; k < kTeeth; ++k) {
    const double base = k * 360.0 / kTeeth;
    appendArc(outer, {0, 0}, tip, (base - 5) * deg, (base + 5) * deg);    // tip land
    appendArc(outer, {0, 0}, root, (base + 9) * deg, (base + 21) * deg);  // root, flanks between
  }
  Shape shape;
  shape.loops.push_back(std::move(outer));
  shape.loops.push_back(circleLoop({0, 0}, 0.48 * tip));
  return shape;
}

// Equilateral, side `size`: isotropic inertia, so its design frame is kept
// (a vertex on -y).
Shape triangleDesign(double size) {
  const double r = size / std::sqrt(3.0);
  Loop loop;
  for (int k = 0; k < 3; ++k) {
    const double a = (-90.0 + 120.0 * k) * kPi / 180;
    loop.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return Shape{{loop}};
}

// Hexagon `size` across corners with a bore: 6-fold, isotropic.
Shape hexNutDesign(double size) {
  Loop outer;
  for (int k = 0; k < 6; ++k) {
    const double a = 60.0 * k * kPi / 180;
    outer.emplace_back(0.5 * size * std::cos(a), 0.5 * size * std::sin(a));
  }
  Shape shape;
  shape.loops.push_back(std::move(outer));
  shape.loops.push_back(circleLoop({0, 0}, 0.22 * size));
  return shape;
}

// A T: mirror-symmetric about its stem, directed along it.
Shape tShapeDesign(double size) {
  const double s = size;
  return Shape{{{{-0.5 * s, 0},
                 {0.5 * s, 0},
                 {0.5 * s, 0.28 * s},
                 {0.14 * s, 0.28 * s},
                 {0.14 * s, 0.9 * s},
                 {-0.14 * s, 0.9 * s},
                 {-0.14 * s, 0.28 * s},
                 {-0.5 * s, 0.28 * s}}}};
}

// A stadium (two half circles joined by lines) with a bore towards one end.
Shape slotDesign(double size) {
  const double r = 0.2 * size;
  const double c = 0.5 * size - r;
  Loop outer;
  appendArc(outer, {c, 0}, r, -kPi / 2, kPi / 2);
  appendArc(outer, {-c, 0}, r, kPi / 2, 3 * kPi / 2);
  Shape shape;
  shape.loops.push_back(std::move(outer));
  shape.loops.push_back(circleLoop({0.25 * size, 0}, 0.1 * size));
  return shape;
}

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

// Darkens `image` (CV_32F, background already in) by the exact area coverage
// of `placed`: pixel += coverage * (part - background) * light.
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

struct TypeInfo {
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
bool tryLayout(const SceneOptions& o, const std::vector<const TypeInfo*>& parts,
               std::mt19937_64& rng, std::vector<Placement>& placed) {
  placed.assign(parts.size(), Placement{});
  for (std::size_t i = 0; i < parts.size(); ++i) {
    placed[i].angle_deg = uniform(rng, 0, 360);
  }

  // The image spans [-0.5, size - 0.5]. Larger parts first: they are the
  // hardest to fit in late.
  std::vector<std::size_t> order(parts.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    order[i] = i;
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return parts[a]->radius > parts[b]->radius;
  });

  double fill = 0;
  for (const TypeInfo* t : parts) {
    fill += kPi * (t->radius + kGapPx / 2) * (t->radius + kGapPx / 2);
  }
  const double usable = (o.width - 2 * kBorderMarginPx) * (o.height - 2 * kBorderMarginPx);
  if (fill > kMaxFill * usable) {
    return false;
  }

  std::vector<std::size_t> done;
  for (std::size_t i : order) {
    const double r = parts[i]->radius;
    const double lo_x = -0.5 + kBorderMarginPx + r;
    const double hi_x = o.width - 0.5 - kBorderMarginPx - r;
    const double lo_y = -0.5 + kBorderMarginPx + r;
    const double hi_y = o.height - 0.5 - kBorderMarginPx - r;
    if (lo_x > hi_x || lo_y > hi_y) {
      return false;
    }
    bool found = false;
    for (int attempt = 0; attempt < kAttemptsPerPart && !found; ++attempt) {
      const double x = uniform(rng, lo_x, hi_x);
      const double y = uniform(rng, lo_y, hi_y);
      found = std::all_of(done.begin(), done.end(), [&](std::size_t j) {
        const double min_d = r + parts[j]->radius + kGapPx;
        return std::hypot(x - placed[j].x, y - placed[j].y) >= min_d;
      });
      if (found) {
        placed[i].x = x;
        placed[i].y = y;
      }
    }
    if (!found) {
      return false;
    }
    done.push_back(i);
  }
  return true;
}

double pointSegmentDistance(cv::Point2d p, cv::Point2d a, cv::Point2d b) {
  const cv::Point2d d = b - a;
  const double len2 = d.dot(d);
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return cv::norm(p - (a + d * t));
}

// Smallest distance between two outlines that do not cross.
double clearance(const Loop& a, const Loop& b) {
  double best = 1e300;
  for (std::size_t i = 0, n = a.size(); i < n; ++i) {
    const cv::Point2d& a0 = a[i];
    const cv::Point2d& a1 = a[(i + 1) % n];
    for (std::size_t j = 0, m = b.size(); j < m; ++j) {
      const cv::Point2d& b0 = b[j];
      const cv::Point2d& b1 = b[(j + 1) % m];
      best = std::min({best, pointSegmentDistance(a0, b0, b1), pointSegmentDistance(b0, a0, a1)});
    }
  }
  return best;
}

// Moves part `i` against part `anchor` from a random side until their edges
// meet; false (leaving it alone) when no side gives a free spot.
constexpr int kTouchAttempts = 36;
constexpr double kContactPx = 0.01;
bool moveIntoContact(const SceneOptions& o, const std::vector<const TypeInfo*>& parts,
                     std::size_t i, std::size_t anchor, std::mt19937_64& rng,
                     std::vector<Placement>& placed) {
  const TypeInfo& a = *parts[anchor];
  const TypeInfo& b = *parts[i];
  const Loop outer_a =
      placedShape(a.shape, placed[anchor].x, placed[anchor].y, placed[anchor].angle_deg).loops[0];
  for (int attempt = 0; attempt < kTouchAttempts; ++attempt) {
    const double dir = uniform(rng, 0, 2 * kPi);
    const cv::Point2d u(std::cos(dir), std::sin(dir));
    double d = a.radius + b.radius + 1;
    cv::Point2d at;
    // Moving by less than the clearance can never make the parts overlap.
    for (int step = 0; step < 400; ++step) {
      at = cv::Point2d(placed[anchor].x, placed[anchor].y) + u * d;
      const double c =
          clearance(outer_a, placedShape(b.shape, at.x, at.y, placed[i].angle_deg).loops[0]);
      if (c < kContactPx) break;
      d -= c;
    }
    const double r = b.radius;
    if (at.x - r < -0.5 + kBorderMarginPx || at.x + r > o.width - 0.5 - kBorderMarginPx ||
        at.y - r < -0.5 + kBorderMarginPx || at.y + r > o.height - 0.5 - kBorderMarginPx) {
      continue;
    }
    bool free = true;
    for (std::size_t j = 0; j < parts.size() && free; ++j) {
      if (j == i || j == anchor) continue;
      free = std::hypot(at.x - placed[j].x, at.y - placed[j].y) >= r + parts[j]->radius + kGapPx;
    }
    if (!free) continue;
    placed[i].x = at.x;
    placed[i].y = at.y;
    return true;
  }
  return false;
}

}  // namespace

const std::vector<std::string>& partTypes() {
  static const std::vector<std::string> types{"rectangle", "l_shape", "l_shape_mirror",
                                              "disc_holes", "gear"};
  return types;
}

Shape partShape(const std::string& type, double size) {
  if (!(size > 0) || !std::isfinite(size)) {
    throw std::invalid_argument("partShape: size must be positive");
  }
  if (type == "rectangle") {
    return canonicalize(rectangleDesign(size));
  }
  if (type == "l_shape") {
    return canonicalize(lShapeDesign(size));
  }
  if (type == "l_shape_mirror") {
    Shape shape = partShape("l_shape", size);
    for (Loop& loop : shape.loops) {
      for (cv::Point2d& p : loop) {
        p.y = -p.y;
      }
    }
    return canonicalize(std::move(shape));
  }
  if (type == "disc_holes") {
    return canonicalize(discHolesDesign(size));
  }
  if (type == "gear") {
    return canonicalize(gearDesign(size));
  }
  if (type == "l_shape_small") {
    return partShape("l_shape", 0.75 * size);
  }
  if (type == "triangle") {
    return canonicalize(triangleDesign(size));
  }
  if (type == "hex_nut") {
    return canonicalize(hexNutDesign(size));
  }
  if (type == "t_shape") {
    return canonicalize(tShapeDesign(size));
  }
  if (type == "slot") {
    return canonicalize(slotDesign(size));
  }
  throw std::invalid_argument("partShape: unknown part type '" + type + "'");
}

const std::vector<std::string>& allPartTypes() {
  static const std::vector<std::string> types{
      "rectangle",     "l_shape",  "l_shape_mirror", "disc_holes", "gear",
      "l_shape_small", "triangle", "hex_nut",        "t_shape",    "slot"};
  return types;
}

ShapeMoments shapeMoments(const Shape& shape) {
  ShapeMoments m;
  if (shape.loops.empty() || shape.loops[0].size() < 3) {
    return m;
  }
  // Integrate about a vertex rather than the origin: parts placed far from the
  // origin would otherwise lose digits in mu = m2 - A c^2.
  const cv::Point2d ref = shape.loops[0][0];
  double a = 0, m10 = 0, m01 = 0, m20 = 0, m11 = 0, m02 = 0;
  for (std::size_t k = 0; k < shape.loops.size(); ++k) {
    const Loop& loop = shape.loops[k];
    const double w = loopWeight(shape, k);
    // Green's theorem over each edge (x0,y0)->(x1,y1), cross = x0 y1 - x1 y0.
    for (std::size_t i = 0, n = loop.size(); i < n; ++i) {
      const double x0 = loop[i].x - ref.x;
      const double y0 = loop[i].y - ref.y;
      const double x1 = loop[(i + 1) % n].x - ref.x;
      const double y1 = loop[(i + 1) % n].y - ref.y;
      const double cross = w * (x0 * y1 - x1 * y0);
      a += cross / 2;
      m10 += (x0 + x1) * cross / 6;
      m01 += (y0 + y1) * cross / 6;
      m20 += (x0 * x0 + x0 * x1 + x1 * x1) * cross / 12;
      m02 += (y0 * y0 + y0 * y1 + y1 * y1) * cross / 12;
      m11 += (x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross / 24;
    }
  }
  if (a == 0) {
    return m;
  }
  const double cx = m10 / a;
  const double cy = m01 / a;
  m.area = a;
  m.cx = ref.x + cx;
  m.cy = ref.y + cy;
  m.mu20 = m20 - a * cx * cx;
  m.mu11 = m11 - a * cx * cy;
  m.mu02 = m02 - a * cy * cy;
  return m;
}

double shapeArea(const Shape& shape) { return shapeMoments(shape).area; }

double angleSymmetryDeg(const Shape& shape) {
  const ShapeMoments m = shapeMoments(shape);
  if (isIsotropic(m)) {
    return 0;
  }
  const auto [fwd, back] = axisReach(shape, m, axisAngle(m));
  return std::abs(fwd - back) < kDirectionTolerance * (fwd + back) ? 180 : 360;
}

Shape placedShape(const Shape& shape, double x, double y, double angle_deg) {
  Shape placed = shape;
  transformShape(placed, x, y, angle_deg * kPi / 180);
  return placed;
}

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
  std::map<std::string, TypeInfo> infos;
  std::vector<Placement> placed;
  std::vector<bool> touching;
  double size = o.part_size;
  for (int round = 0;; ++round) {
    infos.clear();
    for (const std::string& type : types) {
      TypeInfo info;
      info.shape = partShape(type, size);
      for (const cv::Point2d& p : info.shape.loops[0]) {
        info.radius = std::max(info.radius, std::hypot(p.x, p.y));
      }
      info.area = shapeArea(info.shape);
      info.symmetry = angleSymmetryDeg(info.shape);
      infos[type] = std::move(info);
    }
    std::vector<const TypeInfo*> parts;
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

  const cv::Mat light = o.uneven_light ? illumination(o.width, o.height, o.seed) : cv::Mat();
  cv::Mat image(o.height, o.width, CV_32F, cv::Scalar(o.background_level));
  if (!light.empty()) {
    image = light * o.background_level;
  }
  truth_.reserve(part_types.size());
  for (std::size_t i = 0; i < part_types.size(); ++i) {
    const TypeInfo& info = infos.at(part_types[i]);
    const Placement& p = placed[i];
    drawPart(image, light, placedShape(info.shape, p.x, p.y, p.angle_deg),
             o.part_level - o.background_level);
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
  if (o.blur_sigma > 0) {
    // A symmetric kernel moves no centroid and keeps every area.
    cv::GaussianBlur(image, image, cv::Size(), o.blur_sigma, o.blur_sigma, cv::BORDER_REPLICATE);
  }
  image.convertTo(clean_, CV_8U);

  if (o.noise_sigma > 0) {
    cv::RNG noise_rng(splitMix64(o.seed ^ kNoiseStream) | 1);
    for (int k = 0; k < kNoiseBankSize; ++k) {
      cv::Mat field(o.height, o.width, CV_16SC1);
      noise_rng.fill(field, cv::RNG::NORMAL, 0.0, o.noise_sigma);
      noise_bank_.push_back(std::move(field));
    }
  }
}

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
