// Part shapes of synthetic scenes: exact polygon designs, put in a canonical
// pose (centroid at the origin, axis along +x), and their moments and symmetry.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>

#include "scene_internals.hpp"

namespace picksight::synthetic {
namespace {

using detail::kPi;
using detail::Loop;
using detail::loopWeight;
using detail::signedArea;

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
// reach. Isotropic shapes have no axis: their design frame is
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

}  // namespace picksight::synthetic
