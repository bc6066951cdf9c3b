// Silhouette scenes: posing drawings at 4x, laying them out separated, in
// touching pairs or overlapping pairs, and shading them as a camera would.
#include "picksight/synthetic/silhouette_scene.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "picksight/synthetic/front_light.hpp"
#include "scene_internals.hpp"

namespace picksight::synthetic {
namespace {
constexpr int kS = kSilhouetteSupersample;
constexpr int kAttempts = 400;
// Directions tried for the second part of a pair before the pair's spot is
// given up.
constexpr int kPairDirections = 24;
// A part touching its partner lies this close to it (supersampled pixels):
// within half an image pixel, so that the blurred edges merge into one blob.
constexpr int kContactReach = 2;

using detail::uniform;

// A drawing posed: turned, mirrored, scaled, on a square patch.
struct Posed {
  cv::Mat mask;                    // CV_8UC1 0/255, supersampled
  cv::Point2d centroid;            // within the patch, supersampled px
  double radius = 0;               // of the ink about the centroid
  std::vector<cv::Point> outline;  // every contour pixel (outer and holes)
  // Footprints grown by the scene's gap, by placement offset modulo kS:
  // placing a part tries up to kAttempts spots, and findNonZero over the
  // supersampled patch at each made scene building the slowest part of the
  // tests that draw many scenes (minutes under AddressSanitizer).
  mutable std::vector<cv::Mat> footprints = std::vector<cv::Mat>(kS * kS);
};

Posed pose(const cv::Mat& type_mask, double deg, bool mirrored, double scale) {
  cv::Mat src = type_mask;
  if (mirrored) {
    // Into a new buffer: src shares the type's pixels, and flipping it in
    // place would mirror the type itself for every later part (and scene).
    cv::Mat flipped;
    cv::flip(type_mask, flipped, 1);
    src = flipped;
  }
  const int side = static_cast<int>(std::ceil(std::hypot(src.cols, src.rows) * scale)) + 8;
  cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(0.5f * src.cols, 0.5f * src.rows), -deg, scale);
  m.at<double>(0, 2) += 0.5 * side - 0.5 * src.cols;
  m.at<double>(1, 2) += 0.5 * side - 0.5 * src.rows;
  Posed p;
  cv::warpAffine(src, p.mask, m, cv::Size(side, side), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(0));
  cv::threshold(p.mask, p.mask, 127, 255, cv::THRESH_BINARY);
  const cv::Moments mm = cv::moments(p.mask, true);
  p.centroid = mm.m00 > 0 ? cv::Point2d(mm.m10 / mm.m00, mm.m01 / mm.m00)
                          : cv::Point2d(0.5 * side, 0.5 * side);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(p.mask.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  for (const auto& c : contours) p.outline.insert(p.outline.end(), c.begin(), c.end());
  for (const auto& q : p.outline)
    p.radius = std::max(p.radius, std::hypot(q.x - p.centroid.x, q.y - p.centroid.y));
  return p;
}

// Fraction of `a`'s outline (placed at `at_a`) inside `b`'s mask (at `at_b`).
double hiddenOutline(const Posed& a, cv::Point at_a, const Posed& b, cv::Point at_b) {
  if (a.outline.empty()) return 0;
  size_t inside = 0;
  const cv::Point shift = at_a - at_b;
  for (const auto& p : a.outline) {
    const cv::Point q = p + shift;
    if (q.x >= 0 && q.y >= 0 && q.x < b.mask.cols && q.y < b.mask.rows && b.mask.at<uchar>(q))
      ++inside;
  }
  return static_cast<double>(inside) / static_cast<double>(a.outline.size());
}

// The part's footprint in image pixels (any ink), grown by `gap`, as a mask
// at `origin` (image px) for collision tests.
struct Footprint {
  cv::Mat mask;
  cv::Point origin;
};

Footprint footprintOf(const Posed& p, cv::Point at, double gap) {
  const int g = static_cast<int>(std::ceil(gap)) + 1;
  const cv::Point origin(static_cast<int>(std::floor(static_cast<double>(at.x) / kS)) - g,
                         static_cast<int>(std::floor(static_cast<double>(at.y) / kS)) - g);
  // Below zero the footprint lies off the image and isFree refuses it
  // whatever its mask, so the offset's floor modulo is all that matters.
  const int ox = ((at.x % kS) + kS) % kS;
  const int oy = ((at.y % kS) + kS) % kS;
  cv::Mat& mask = p.footprints[static_cast<size_t>(oy * kS + ox)];
  if (mask.empty()) {
    const int w = (p.mask.cols + kS - 1) / kS + 2 * g + 2;
    const int h = (p.mask.rows + kS - 1) / kS + 2 * g + 2;
    // Any ink in a pixel's kS x kS cell marks it: the cells' means, which
    // are above zero wherever one supersampled pixel is inked (255 / kS^2
    // rounds to more than 0).
    cv::Mat cells = cv::Mat::zeros(h * kS, w * kS, CV_8UC1);
    p.mask.copyTo(cells(cv::Rect(g * kS + ox, g * kS + oy, p.mask.cols, p.mask.rows)));
    cv::resize(cells, mask, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    cv::threshold(mask, mask, 0, 255, cv::THRESH_BINARY);
    const cv::Mat k = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * g - 1, 2 * g - 1));
    cv::dilate(mask, mask, k);
  }
  return Footprint{mask, origin};
}

// Whether the footprint lies inside the image and clear of `occupied`.
bool isFree(const Footprint& f, const cv::Mat& occupied) {
  const cv::Rect box(f.origin, f.mask.size());
  if ((box & cv::Rect(0, 0, occupied.cols, occupied.rows)) != box) return false;
  cv::Mat both;
  cv::bitwise_and(occupied(box), f.mask, both);
  return cv::countNonZero(both) == 0;
}

void occupy(const Footprint& f, cv::Mat& occupied) {
  cv::Mat dst = occupied(cv::Rect(f.origin, f.mask.size()));
  cv::bitwise_or(dst, f.mask, dst);
}

void stamp(const Posed& p, cv::Point at, cv::Mat& canvas) {
  const cv::Rect box = cv::Rect(at, p.mask.size()) & cv::Rect(0, 0, canvas.cols, canvas.rows);
  cv::Mat dst = canvas(box);
  cv::max(dst, p.mask(box - at), dst);
}

cv::Point2d imageCentre(const Posed& p, cv::Point at) {
  return {(at.x + p.centroid.x + 0.5) / kS - 0.5, (at.y + p.centroid.y + 0.5) / kS - 0.5};
}

// Grey levels (or BGR levels, for a colour front light) of a supersampled ink
// canvas: averaged down, lit, blurred.
cv::Mat shade(const cv::Mat& canvas, const SilhouetteSceneOptions& o, uint64_t seed) {
  cv::Mat coverage;
  cv::resize(canvas, coverage, cv::Size(canvas.cols / kS, canvas.rows / kS), 0, 0, cv::INTER_AREA);
  coverage.convertTo(coverage, CV_32F, 1.0 / 255);
  std::mt19937_64 rng(detail::splitMix64(seed ^ detail::kLightStream));
  const double gx = o.uneven_light ? uniform(rng, -0.15, 0.15) : 0;
  const double gy = o.uneven_light ? uniform(rng, -0.15, 0.15) : 0;
  const double vignette = o.uneven_light ? 0.15 : 0;
  cv::Mat grey(coverage.size(), CV_32F);
  for (int y = 0; y < grey.rows; ++y) {
    const float* c = coverage.ptr<float>(y);
    float* g = grey.ptr<float>(y);
    const double v = (y + 0.5) / grey.rows - 0.5;
    for (int x = 0; x < grey.cols; ++x) {
      const double u = (x + 0.5) / grey.cols - 0.5;
      const double light = 1.0 + gx * u + gy * v - vignette * (u * u + v * v);
      // Under the front light the plane holds the light alone; the surface,
      // the part and their shading are laid on it below.
      g[x] = o.front.any()
                 ? static_cast<float>(light)
                 : static_cast<float>(
                       light * (o.background_level - (o.background_level - o.part_level) * c[x]));
    }
  }
  if (o.front.any()) {
    const auto planes =
        detail::shadeFrontLit(coverage, grey, o.front, o.part_level, o.background_level, seed);
    cv::merge(planes, grey);
  }
  if (o.blur_sigma > 0) cv::GaussianBlur(grey, grey, cv::Size(0, 0), o.blur_sigma);
  return grey;
}

cv::Mat addNoise(const cv::Mat& clean, double sigma, uint64_t seed) {
  cv::Mat noisy = clean.clone();
  if (sigma > 0) {
    cv::Mat noise(clean.size(), clean.type());  // a plane of noise per channel
    cv::RNG rng(detail::splitMix64(seed ^ detail::kNoiseStream) | 1);
    rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
    noisy += noise;
  }
  cv::Mat out;
  noisy.convertTo(out, CV_8U);
  return out;
}
// Whether any outline pixel of `b` placed at `at_b` lies on `a` placed at
// `at_a` grown by kContactReach (supersampled pixels).
bool withinReach(const Posed& a, cv::Point at_a, const Posed& b, cv::Point at_b) {
  const cv::Point shift = at_b - at_a;
  for (const auto& p : b.outline) {
    const cv::Point q = p + shift;
    for (int dy = -kContactReach; dy <= kContactReach; ++dy) {
      for (int dx = -kContactReach; dx <= kContactReach; ++dx) {
        const cv::Point r(q.x + dx, q.y + dy);
        if (r.x >= 0 && r.y >= 0 && r.x < a.mask.cols && r.y < a.mask.rows &&
            a.mask.at<uchar>(r) != 0) {
          return true;
        }
      }
    }
  }
  return false;
}

}  // namespace

SilhouetteType silhouetteFromDrawing(const std::string& name, const cv::Mat& drawing,
                                     double size_px) {
  SilhouetteType t;
  t.name = name;
  cv::Mat ink;
  cv::threshold(drawing, ink, 127, 255, cv::THRESH_BINARY);
  const cv::Rect box = cv::boundingRect(ink);
  if (box.area() == 0) return t;
  cv::Mat padded;
  cv::copyMakeBorder(ink(box), padded, 3, 3, 3, 3, cv::BORDER_CONSTANT, cv::Scalar(0));
  padded.convertTo(padded, CV_32F, 1.0 / 255);
  // The drawing's pixel steps smoothed away: outlines become curves.
  cv::GaussianBlur(padded, padded, cv::Size(0, 0), 0.5);
  const double f = size_px * kS / std::max(box.width, box.height);
  cv::Mat big;
  cv::resize(padded, big, cv::Size(), f, f, cv::INTER_LINEAR);
  cv::threshold(big, big, 0.5, 255, cv::THRESH_BINARY);
  big.convertTo(t.mask, CV_8U);
  return t;
}

SilhouetteType silhouetteFromPartType(const std::string& type, double size_px) {
  const Shape shape = partShape(type, size_px * kS);
  cv::Point2d lo(1e300, 1e300);
  cv::Point2d hi(-1e300, -1e300);
  for (const auto& loop : shape.loops) {
    for (const auto& p : loop) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
    }
  }
  const cv::Rect2d box(lo, hi);
  constexpr int kPad = 8;
  constexpr int kShift = 4;  // fixed-point bits of fillPoly: sub-pixel vertices
  SilhouetteType t;
  t.name = type;
  t.mask = cv::Mat::zeros(static_cast<int>(std::ceil(box.height)) + 2 * kPad,
                          static_cast<int>(std::ceil(box.width)) + 2 * kPad, CV_8UC1);
  std::vector<std::vector<cv::Point>> polys;
  for (const auto& loop : shape.loops) {
    std::vector<cv::Point> poly;
    for (const auto& p : loop) {
      poly.emplace_back(static_cast<int>(std::lround((p.x - box.x + kPad) * (1 << kShift))),
                        static_cast<int>(std::lround((p.y - box.y + kPad) * (1 << kShift))));
    }
    polys.push_back(std::move(poly));
  }
  cv::fillPoly(t.mask, polys, cv::Scalar(255), cv::LINE_8, kShift);
  return t;
}

const char* arrangementName(Arrangement a) {
  switch (a) {
    case Arrangement::kSeparated:
      return "separated";
    case Arrangement::kTouching:
      return "touching";
    case Arrangement::kOverlapping:
      return "overlapping";
  }
  return "?";
}

// One pass over the random stream, part after part: the order of its draws
// is what makes a seed the same scene (the benchmarks' scenes, and the
// digests the tests keep of them), so the placing steps stay in this one
// constructor (the geometry is in the helpers above: pose, footprintOf,
// withinReach, hiddenOutline, stamp).
SilhouetteScene::SilhouetteScene(const std::vector<SilhouetteType>& types,
                                 const std::vector<bool>& chiral,
                                 const SilhouetteSceneOptions& options)
    : options_(options) {
  const SilhouetteSceneOptions& o = options_;
  std::mt19937_64 rng(detail::splitMix64(o.seed));
  cv::Mat canvas = cv::Mat::zeros(o.height * kS, o.width * kS, CV_8UC1);
  cv::Mat occupied = cv::Mat::zeros(o.height, o.width, CV_8UC1);
  // Every type in turn from a random start, so that each appears.
  const size_t offset = types.empty() ? 0 : static_cast<size_t>(rng() % types.size());
  const auto pick = [&](int k, SilhouettePart* part, double* scale, bool* mirrored) {
    part->type = (offset + static_cast<size_t>(k)) % types.size();
    part->angle_deg = uniform(rng, 0, 360);
    *scale = 1.0;
    *mirrored = false;
    if (detail::uniform01(rng) >= o.distractor_share) return;
    const int kinds = chiral[part->type] ? 3 : 2;
    const int which = static_cast<int>(rng() % static_cast<uint64_t>(kinds));
    part->kind = which == 0   ? PartKind::kSmaller
                 : which == 1 ? PartKind::kLarger
                              : PartKind::kMirrored;
    *scale = which == 0 ? o.smaller_scale : which == 1 ? o.larger_scale : 1.0;
    *mirrored = which == 2;
  };
  const auto randomAt = [&](const Posed& p) {
    return cv::Point(static_cast<int>(uniform(rng, 0, o.width * kS - p.mask.cols)),
                     static_cast<int>(uniform(rng, 0, o.height * kS - p.mask.rows)));
  };
  const bool pairs = o.arrangement != Arrangement::kSeparated;
  for (int k = 0; types.size() > 0 && k < o.parts; k += pairs ? 2 : 1) {
    SilhouettePart a;
    double scale_a = 1;
    bool mirror_a = false;
    pick(k, &a, &scale_a, &mirror_a);
    const Posed pa = pose(types[a.type].mask, a.angle_deg, mirror_a, scale_a);
    if (!pairs) {
      for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const cv::Point at = randomAt(pa);
        const Footprint f = footprintOf(pa, at, o.gap_px);
        if (!isFree(f, occupied)) continue;
        occupy(f, occupied);
        stamp(pa, at, canvas);
        a.centre = imageCentre(pa, at);
        truth_.push_back(a);
        break;
      }
      continue;
    }
    SilhouettePart b;
    double scale_b = 1;
    bool mirror_b = false;
    pick(k + 1, &b, &scale_b, &mirror_b);
    const Posed pb = pose(types[b.type].mask, b.angle_deg, mirror_b, scale_b);
    const double target = uniform(rng, o.min_hidden, o.max_hidden);
    bool done = false;
    for (int attempt = 0; attempt < kAttempts / kPairDirections && !done; ++attempt) {
      const cv::Point at_a = randomAt(pa);
      const Footprint fa = footprintOf(pa, at_a, o.gap_px);
      if (!isFree(fa, occupied)) continue;
      for (int d = 0; d < kPairDirections && !done; ++d) {
        const double phi = uniform(rng, 0, 2 * detail::kPi);
        const cv::Point2d u(std::cos(phi), std::sin(phi));
        const cv::Point2d ca = cv::Point2d(at_a) + pa.centroid;
        // From clear of each other, inwards until they meet (or overlap
        // enough); a step of one supersampled pixel near contact.
        double dist = pa.radius + pb.radius + 2 * kContactReach;
        cv::Point at_b;
        bool met = false;
        double hidden_a = 0;
        double hidden_b = 0;
        for (double step = o.arrangement == Arrangement::kTouching ? 8 : 2; dist > 0 && !met;) {
          const cv::Point2d cb = ca + u * dist;
          at_b = cv::Point(static_cast<int>(std::lround(cb.x - pb.centroid.x)),
                           static_cast<int>(std::lround(cb.y - pb.centroid.y)));
          if (o.arrangement == Arrangement::kTouching) {
            const bool near = withinReach(pa, at_a, pb, at_b);
            if (near && step > 1) {
              dist += step;
              step = 1;
            } else if (near) {
              met = hiddenOutline(pb, at_b, pa, at_a) == 0;
              if (!met) break;
            }
          } else {
            hidden_a = hiddenOutline(pa, at_a, pb, at_b);
            hidden_b = hiddenOutline(pb, at_b, pa, at_a);
            met = std::max(hidden_a, hidden_b) >= target;
          }
          if (!met) dist -= step;
        }
        if (!met || std::max(hidden_a, hidden_b) > o.max_hidden) continue;
        const Footprint fb = footprintOf(pb, at_b, o.gap_px);
        if (!isFree(fb, occupied)) continue;
        occupy(fa, occupied);
        occupy(fb, occupied);
        stamp(pa, at_a, canvas);
        stamp(pb, at_b, canvas);
        a.centre = imageCentre(pa, at_a);
        b.centre = imageCentre(pb, at_b);
        a.touching = b.touching = true;
        a.hidden = hidden_a;
        b.hidden = hidden_b;
        a.partner = static_cast<int>(truth_.size()) + 1;
        b.partner = static_cast<int>(truth_.size());
        truth_.push_back(a);
        truth_.push_back(b);
        done = true;
      }
    }
  }
  clean_ = shade(canvas, o, o.seed);
}

cv::Mat SilhouetteScene::render(uint64_t frame_index) const {
  return addNoise(clean_, options_.noise_sigma,
                  detail::splitMix64(options_.seed ^ detail::kFrameStream) + frame_index);
}

cv::Mat renderSilhouetteAlone(const SilhouetteType& type, int side,
                              const SilhouetteSceneOptions& look, uint64_t seed,
                              cv::Point2d* centre, double angle_deg) {
  const Posed p = pose(type.mask, angle_deg, false, 1.0);
  cv::Mat canvas = cv::Mat::zeros(side * kS, side * kS, CV_8UC1);
  const cv::Point at(static_cast<int>(std::lround(0.5 * side * kS - p.centroid.x)),
                     static_cast<int>(std::lround(0.5 * side * kS - p.centroid.y)));
  stamp(p, at, canvas);
  if (centre) *centre = imageCentre(p, at);
  return addNoise(shade(canvas, look, seed), look.noise_sigma, seed);
}

cv::Mat renderSilhouetteInFrame(const SilhouetteType& type, const SilhouetteSceneOptions& look,
                                uint64_t seed, cv::Point2d where, cv::Point2d* centre,
                                double angle_deg) {
  const Posed p = pose(type.mask, angle_deg, false, 1.0);
  cv::Mat canvas = cv::Mat::zeros(look.height * kS, look.width * kS, CV_8UC1);
  // The drawn centroid at `where` (imageCentre's inverse), to the nearest
  // supersampled pixel.
  const cv::Point at(static_cast<int>(std::lround((where.x + 0.5) * kS - 0.5 - p.centroid.x)),
                     static_cast<int>(std::lround((where.y + 0.5) * kS - 0.5 - p.centroid.y)));
  stamp(p, at, canvas);
  if (centre) *centre = imageCentre(p, at);
  return addNoise(shade(canvas, look, seed), look.noise_sigma, seed);
}

}  // namespace picksight::synthetic
