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
    // Every boundary pixel stamps the exact distances of a disc of radius
    // max_distance around it: a few dozen pixels per boundary pixel instead
    // of a transform of every pixel of the box. The disc is stamped a row at
    // a time, four floats at once.
    const int reach = static_cast<int>(std::floor(max_distance));
    struct DiscRow {
      int dy;
      int half;          // the row spans dx in [-half, half]
      size_t first = 0;  // its distances in `row_distances`
    };
    std::vector<DiscRow> rows;
    std::vector<float> row_distances;
    for (int dy = -reach; dy <= reach; ++dy) {
      DiscRow row{dy, -1, row_distances.size()};
      for (int dx = -reach; dx <= reach; ++dx) {
        const int d2 = dx * dx + dy * dy;
        if (d2 <= max_distance * max_distance) {
          row_distances.push_back(std::sqrt(static_cast<float>(d2)));
          row.half = std::max(row.half, dx);
        }
      }
      if (row.half >= 0) rows.push_back(row);
    }
    distance_.create(roi.size(), CV_32F);
    distance_.setTo(1e9f);
    const auto stamp = [](float* to, const float* d, int n) {
      int k = 0;
#if CV_SIMD128
      for (; k + 4 <= n; k += 4)
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
            stamp(distance_.ptr<float>(q.y + row.dy) + (q.x - row.half),
                  row_distances.data() + row.first, 2 * row.half + 1);
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
          stamp(distance_.ptr<float>(y) + from,
                row_distances.data() + row.first + (from - (q.x - row.half)), last - from + 1);
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
  step_ = distance_.step[0];
}

namespace {
// A sample's weight when it lies within the tolerance of an edge, else 0,
// without a branch: whether a placed sample meets an edge is a coin toss
// to the processor, and its mispredictions cost more than the rest of the
// test (the hypothesis search asks it millions of times a frame). Adding 0
// leaves a sum as it was: every score and answer is the branch's. Front-light
// benchmark, touching / overlapping, 3 scenes, LOCATE median: clean 10.7 /
// 11.3 -> 9.8 / 10.5 ms, textured 13.7 / 14.5 -> 13.1 / 13.8 ms.
// (Masked as an integer: the compiler turns a product with the comparison
// back into a branch.)
inline double onEdge(double weight, float distance, double tolerance) {
  uint64_t bits;
  std::memcpy(&bits, &weight, sizeof bits);
  bits &= -static_cast<uint64_t>(distance <= tolerance);
  double kept;
  std::memcpy(&kept, &bits, sizeof kept);
  return kept;
}

// Calls f(weight, distance to the nearest edge) for every placed sample.
template <typename F>
void forPlaced(const std::vector<BoundarySample>& samples, cv::Point2d centre, double angle_deg,
               const EdgeDistance& edges, bool mirrored, F&& f) {
  const double c = std::cos(angle_deg * kRadPerDeg);
  const double s = std::sin(angle_deg * kRadPerDeg);
  const double flip = mirrored ? -1.0 : 1.0;
  for (const auto& sample : samples) {
    const double x = sample.point.x;
    const double y = flip * sample.point.y;
    f(sample.weight, edges.at({centre.x + c * x - s * y, centre.y + s * x + c * y}));
  }
}
}  // namespace

double verifyScore(const std::vector<BoundarySample>& samples, cv::Point2d centre, double angle_deg,
                   const EdgeDistance& edges, double tolerance, bool mirrored) {
  double on = 0;
  double total = 0;
  forPlaced(samples, centre, angle_deg, edges, mirrored, [&](double w, double d) {
    total += w;
    on += onEdge(w, d, tolerance);
  });
  return total > 0 ? on / total : 0;
}

bool verifiesAtLeast(const std::vector<BoundarySample>& samples, double total, cv::Point2d centre,
                     double c, double s, double flip, const EdgeDistance& edges, double tolerance,
                     double needed) {
  const double goal = needed * total;
  double on = 0;
  double left = total;
  for (const auto& sample : samples) {
    const double x = sample.point.x;
    const double y = flip * sample.point.y;
    on += onEdge(sample.weight, edges.at({centre.x + c * x - s * y, centre.y + s * x + c * y}),
                 tolerance);
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
  forPlaced(samples, centre, angle_deg, edges, mirrored, [&](double w, double d) {
    total += w;
    sum += w * std::min<double>(d, clip);
  });
  return total > 0 ? sum / total : clip;
}

}  // namespace picksight::vision
