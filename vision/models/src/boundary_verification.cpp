// Pose verification: the edge distance map (exact up to a reach, by
// stamping a disc of distances at every boundary pixel) and the verified
// share of a model's boundary samples placed at a pose.
#include "picksight/vision/models/boundary_verification.hpp"

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "picksight/common/angles.hpp"

namespace picksight::vision {

EdgeDistance::EdgeDistance(const std::vector<std::vector<cv::Point>>& contours, cv::Rect roi,
                           double max_distance)
    : origin_(roi.tl()) {
  if (max_distance > 0) {
    // Every boundary pixel stamps the exact squared distances of a disc of
    // radius max_distance around it: a few dozen pixels per boundary pixel
    // instead of a transform of every pixel of the box. The disc is stamped
    // a row at a time, eight at once. Squared distances are whole numbers,
    // held in 16 bits (half the memory of the floats they replace, twice as
    // many stamped at once): at() gives the same float root of each, and
    // "within a tolerance?" compares whole numbers. A LOCATE of touching
    // and overlapping parts on a textured belt: 3 % less time, every pose
    // the same.
    max_distance = std::min(max_distance, kMaxReach);
    const int reach = static_cast<int>(std::floor(max_distance));
    struct DiscRow {
      int dy;
      int half;          // the row spans dx in [-half, half]
      size_t first = 0;  // its squared distances in `row_squares`
    };
    std::vector<DiscRow> rows;
    std::vector<uint16_t> row_squares;
    for (int dy = -reach; dy <= reach; ++dy) {
      DiscRow row{dy, -1, row_squares.size()};
      for (int dx = -reach; dx <= reach; ++dx) {
        const int d2 = dx * dx + dy * dy;
        if (d2 <= max_distance * max_distance) {
          row_squares.push_back(static_cast<uint16_t>(d2));
          row.half = std::max(row.half, dx);
        }
      }
      if (row.half >= 0) rows.push_back(row);
    }
    squared_ = true;
    distance_.create(roi.size(), CV_16UC1);
    distance_.setTo(kFarSquared);
    const auto stamp = [](uint16_t* to, const uint16_t* d, int n) {
      int k = 0;
#if CV_SIMD128
      for (; k + 8 <= n; k += 8)
        cv::v_store(to + k, cv::v_min(cv::v_load(to + k), cv::v_load(d + k)));
#endif
      for (; k < n; ++k) to[k] = std::min(to[k], d[k]);
    };
    const cv::Rect inside(reach, reach, roi.width - 2 * reach, roi.height - 2 * reach);
    for (const auto& c : contours) {
      for (const auto& p : c) {
        const cv::Point q = p - origin_;
        if (inside.contains(q)) {
          for (const DiscRow& row : rows) {
            stamp(distance_.ptr<uint16_t>(q.y + row.dy) + (q.x - row.half),
                  row_squares.data() + row.first, 2 * row.half + 1);
          }
          continue;
        }
        // Near the box's edge (or outside it): each row clipped to the box.
        // Kept apart from the path above, which most boundary pixels take:
        // clipping every row there cost 1.6 % of recognize().
        for (const DiscRow& row : rows) {
          const int y = q.y + row.dy;
          const int from = std::max(q.x - row.half, 0);
          const int last = std::min(q.x + row.half, roi.width - 1);
          if (y < 0 || y >= roi.height || from > last) continue;
          stamp(distance_.ptr<uint16_t>(y) + from,
                row_squares.data() + row.first + (from - (q.x - row.half)), last - from + 1);
        }
      }
    }
    keepBounds();
    return;
  }
  cv::Mat free(roi.size(), CV_8UC1, cv::Scalar(255));
  for (const auto& c : contours) {
    for (const auto& p : c) {
      const cv::Point q = p - origin_;
      if (q.x >= 0 && q.y >= 0 && q.x < free.cols && q.y < free.rows) free.at<uint8_t>(q) = 0;
    }
  }
  cv::distanceTransform(free, distance_, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  keepBounds();
}

void EdgeDistance::keepBounds() {
  low_ = cv::Point2d(origin_.x - 0.5, origin_.y - 0.5);
  high_ = cv::Point2d(origin_.x + distance_.cols - 0.5, origin_.y + distance_.rows - 0.5);
  data_ = distance_.data;
  row_elements_ = distance_.empty() ? 0 : static_cast<int>(distance_.step1());
}

EdgeDistance::Within EdgeDistance::withinOf(double tolerance) const {
  // The verification asks it once a pose, of a few tolerances in turn: the
  // last answer is kept (per thread: the searches run on several).
  thread_local double last_tolerance = std::numeric_limits<double>::quiet_NaN();
  thread_local Within last;
  if (tolerance == last_tolerance) return last;
  Within w;
  w.tolerance = static_cast<float>(tolerance);
  // The exact test is float distance <= double tolerance; the float kept
  // for the unsquared map must answer alike: the largest float not above
  // the tolerance.
  if (static_cast<double>(w.tolerance) > tolerance)
    w.tolerance = std::nextafter(w.tolerance, -std::numeric_limits<float>::infinity());
  // The whole squared distances whose float roots are within: a prefix
  // (the root grows with its argument), found about tolerance^2.
  if (!(tolerance >= 0)) return w;
  const auto in = [&](int k) { return std::sqrt(static_cast<float>(k)) <= tolerance; };
  int k = static_cast<int>(std::min(std::floor(tolerance * tolerance), kFarSquared - 1.0));
  while (k < kFarSquared - 1 && in(k + 1)) ++k;
  while (k >= 0 && !in(k)) --k;
  w.squared = k;
  last_tolerance = tolerance;
  last = w;
  return w;
}

namespace {
// A sample's weight when it lies within the tolerance of an edge, else 0,
// without a branch: whether a placed sample meets an edge is a coin toss
// to the processor, and the mispredicted branch's landing was the hottest
// spot of the test (the hypothesis search asks it millions of times a
// frame). Adding 0 leaves a sum as it was: every score and answer is the
// branch's. A LOCATE of touching and overlapping parts on a textured belt,
// the two ways timed in turn in one process: 3 % less time.
// (Masked as an integer: the compiler turns a product with the comparison
// back into a branch.)
inline double onEdge(double weight, bool within) {
  uint64_t bits;
  std::memcpy(&bits, &weight, sizeof bits);
  bits &= -static_cast<uint64_t>(within);
  double kept;
  std::memcpy(&kept, &bits, sizeof kept);
  return kept;
}

// Calls f(weight, image point) for every placed sample.
template <typename F>
void forPlaced(const std::vector<BoundarySample>& samples, cv::Point2d centre, double angle_deg,
               bool mirrored, F&& f) {
  const double c = std::cos(angle_deg * kRadPerDeg);
  const double s = std::sin(angle_deg * kRadPerDeg);
  const double flip = mirrored ? -1.0 : 1.0;
  for (const auto& sample : samples) {
    const double x = sample.point.x;
    const double y = flip * sample.point.y;
    f(sample.weight, cv::Point2d(centre.x + c * x - s * y, centre.y + s * x + c * y));
  }
}
}  // namespace

double verifyScore(const std::vector<BoundarySample>& samples, cv::Point2d centre, double angle_deg,
                   const EdgeDistance& edges, double tolerance, bool mirrored) {
  const EdgeDistance::Within within = edges.withinOf(tolerance);
  double on = 0;
  double total = 0;
  forPlaced(samples, centre, angle_deg, mirrored, [&](double w, cv::Point2d p) {
    total += w;
    on += onEdge(w, edges.isWithin(p, within));
  });
  return total > 0 ? on / total : 0;
}

bool verifiesAtLeast(const std::vector<BoundarySample>& samples, double total, cv::Point2d centre,
                     double c, double s, double flip, const EdgeDistance& edges, double tolerance,
                     double needed) {
  const EdgeDistance::Within within = edges.withinOf(tolerance);
  const double goal = needed * total;
  double on = 0;
  double left = total;
  for (const auto& sample : samples) {
    const double x = sample.point.x;
    const double y = flip * sample.point.y;
    on += onEdge(sample.weight,
                 edges.isWithin({centre.x + c * x - s * y, centre.y + s * x + c * y}, within));
    if (on >= goal) return true;
    left -= sample.weight;
    if (on + left < goal) return false;
  }
  return on >= goal;
}

double meanEdgeDistance(const std::vector<BoundarySample>& samples, cv::Point2d centre,
                        double angle_deg, const EdgeDistance& edges, double clip, bool mirrored) {
  double sum = 0;
  double total = 0;
  forPlaced(samples, centre, angle_deg, mirrored, [&](double w, cv::Point2d p) {
    total += w;
    sum += w * std::min<double>(edges.at(p), clip);
  });
  return total > 0 ? sum / total : clip;
}

}  // namespace picksight::vision
