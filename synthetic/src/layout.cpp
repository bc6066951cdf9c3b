// Part layout of a synthetic scene: random sequential placement with clear
// gaps, and moving pairs of parts into contact for the touching-parts cases.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "scene_internals.hpp"

namespace picksight::synthetic::detail {
namespace {

constexpr int kTouchAttempts = 36;
constexpr double kContactPx = 0.01;

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

}  // namespace

bool tryLayout(const SceneOptions& o, const std::vector<const SizedPartType*>& parts,
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
  for (const SizedPartType* t : parts) {
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

bool moveIntoContact(const SceneOptions& o, const std::vector<const SizedPartType*>& parts,
                     std::size_t i, std::size_t anchor, std::mt19937_64& rng,
                     std::vector<Placement>& placed) {
  const SizedPartType& a = *parts[anchor];
  const SizedPartType& b = *parts[i];
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

}  // namespace picksight::synthetic::detail
