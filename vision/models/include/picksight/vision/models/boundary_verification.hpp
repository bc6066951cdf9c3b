// Verification of a pose against the edges of an image: the distance from
// each pixel near a region to its nearest boundary pixel, and the share of a
// model's boundary samples that land within a tolerance of an edge.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/models/boundary_model.hpp"

namespace picksight::vision {

// Distance to the nearest boundary pixel of a set of contours, over a region
// of interest; the image edges a pose is verified against.
class EdgeDistance {
 public:
  EdgeDistance() = default;
  // `max_distance` > 0: distances are exact up to it (at most kMaxReach)
  // and a large value beyond, for callers that only ask "within a
  // tolerance?" or clip there; much cheaper than the exact transform of
  // the whole region of interest.
  EdgeDistance(const std::vector<std::vector<cv::Point>>& contours, cv::Rect roi,
               double max_distance = 0);
  // Pixels; a large value outside the region of interest. Inline: the
  // hypothesis search asks it millions of times a frame.
  float at(cv::Point2d p) const {
    const int offset = offsetOf(p);
    if (offset < 0) return kFar;
    if (squared_) {
      const uint16_t d2 = reinterpret_cast<const uint16_t*>(data_)[offset];
      return d2 == kFarSquared ? kFar : std::sqrt(static_cast<float>(d2));
    }
    return reinterpret_cast<const float*>(data_)[offset];
  }
  // Whether at(p) <= tolerance, given within = withinOf(tolerance): on a
  // map with a reach, one comparison of whole squared distances.
  struct Within {
    float tolerance = 0;
    int squared = -1;  // the largest whole d^2 whose distance is within
  };
  Within withinOf(double tolerance) const;
  bool isWithin(cv::Point2d p, const Within& within) const {
    const int offset = offsetOf(p);
    if (offset < 0) return kFar <= within.tolerance;
    if (squared_) return reinterpret_cast<const uint16_t*>(data_)[offset] <= within.squared;
    return reinterpret_cast<const float*>(data_)[offset] <= within.tolerance;
  }
  bool empty() const { return distance_.empty(); }

  // The largest reach a map holds (its squared distances in 16 bits).
  static constexpr double kMaxReach = 255;

 private:
  static constexpr float kFar = 1e9f;
  static constexpr uint16_t kFarSquared = 0xFFFF;
  // The map's element p rounds to, or -1 outside the map (in doubles
  // first: a pose from degenerate geometry can put a point at infinity or
  // NaN, which no integer holds). Inside, the rounded point is a pixel of
  // the map.
  int offsetOf(cv::Point2d p) const {
    if (!(p.x > low_.x && p.y > low_.y && p.x < high_.x && p.y < high_.y)) return -1;
    return (cvRound(p.y) - origin_.y) * row_elements_ + (cvRound(p.x) - origin_.x);
  }
  // The bounds and rows at() reads, kept beside the map.
  void keepBounds();

  // With a reach, each pixel's squared distance to the nearest boundary
  // pixel (a whole number; kFarSquared beyond the reach): half the memory
  // of floats, and "within a tolerance?" a comparison of integers. Without
  // one, the exact transform's distances (CV_32F).
  bool squared_ = false;
  cv::Mat distance_;
  cv::Point origin_;
  // Pixel centres are at origin_ + (i, j): a point rounds into the map when
  // strictly between low_ and high_.
  cv::Point2d low_;
  cv::Point2d high_;
  const uchar* data_ = nullptr;
  int row_elements_ = 0;
};

// The fraction (0..1) of the samples' weight that lies within `tolerance`
// pixels of an edge once turned by `angle_deg` about the model origin and
// moved to `centre`. `mirrored` reflects the samples (y -> -y) first.
double verifyScore(const std::vector<BoundarySample>& samples, cv::Point2d centre, double angle_deg,
                   const EdgeDistance& edges, double tolerance, bool mirrored = false);

// Whether at least `needed` (a fraction) of the samples' weight (`total`,
// their sum) lies within `tolerance` of an edge at the pose: centre, turned
// by the angle of cosine c and sine s, mirrored when flip is -1 (as
// verifyScore says, to the rounding). Stops as soon as the rest cannot
// decide otherwise, which a wrong pose shows within a few samples: for a
// yes or no at a threshold, far cheaper than the score.
bool verifiesAtLeast(const std::vector<BoundarySample>& samples, double total, cv::Point2d centre,
                     double c, double s, double flip, const EdgeDistance& edges, double tolerance,
                     double needed);

// The weighted mean of the samples' edge distances, each clipped at `clip`,
// at the same pose as verifyScore: unlike the verified fraction it changes
// smoothly with the pose, for searching the best one.
double meanEdgeDistance(const std::vector<BoundarySample>& samples, cv::Point2d centre,
                        double angle_deg, const EdgeDistance& edges, double clip,
                        bool mirrored = false);

}  // namespace picksight::vision
