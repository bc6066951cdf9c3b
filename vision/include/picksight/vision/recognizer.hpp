// Recognition: which trained parts are in a set of regions, where and how
// turned; body features propose, the boundary model verifies.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/part_model.hpp"
#include "picksight/vision/regions.hpp"

namespace picksight::vision {

struct Match {
  const PartModel* model = nullptr;  // borrowed from the caller's list
  size_t region = 0;                 // index into the regions
  double score = 0;                  // verified fraction of the weighted boundary, 0..1
  cv::Point2d centroid;              // pixels
  // Rotation from the trained pose, in [0, symmetry) (or [0, 360)).
  double angle_deg = 0;
  double symmetry_deg = 360;  // the model's: 360 none, 180, 120..., 0 any turn
  double body_distance = 0;   // Hu distance (0 for a part found inside a merged blob)
  // Found inside a blob it shares with other parts (they touch), located
  // from its edges instead of the blob's moments.
  bool touching = false;
};

// Every part of the given models among the regions, best score first. A
// region that matches a model as a whole holds one part, the model that
// verifies best; a region that matches none is searched for parts that
// touch (one merged blob) with the boundary models (see locateInBlob).
// Regions are searched on OpenCV's worker threads (cv::setNumThreads); the
// result does not depend on their number.
std::vector<Match> recognize(const std::vector<Region>& regions,
                             const std::vector<const PartModel*>& models);

// The rotation candidates of a region for a model (before verification).
std::vector<double> rotationCandidates(const Region& region, const PartModel& model);

}  // namespace picksight::vision
