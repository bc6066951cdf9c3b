// A part found in an image: which model, where and how turned, how well it
// verified. What recognition (recognition/) and the search of merged blobs
// (blob_search/) both report.
#pragma once

#include <cstddef>

#include <opencv2/core.hpp>

#include "picksight/vision/models/part_model.hpp"

namespace picksight::vision {

struct Match {
  const PartModel* model = nullptr;  // borrowed from the caller's list
  size_t region = 0;                 // index into the regions
  double score = 0;                  // verified fraction of the weighted boundary, 0..1
  cv::Point2d centroid;              // pixels
  // Rotation from the trained pose (image axes, degrees): the turn nearest
  // the taught pose, in (-symmetry / 2, symmetry / 2] (reportedTurnDeg).
  double angle_deg = 0;
  double symmetry_deg = 360;  // the model's: 360 none, 180, 120..., 0 any turn
  double body_distance = 0;   // Hu distance (0 for a part found inside a merged blob)
  // Found by the search inside a blob (no model explained the region
  // whole), located from its edges instead of the region's moments.
  bool from_edges = false;
  // Found inside a blob it shares with other parts, or with pixels it does
  // not explain: it touches something. A part the search found alone,
  // explaining its blob whole, touches nothing (its region is its own).
  bool touching = false;
};

}  // namespace picksight::vision
