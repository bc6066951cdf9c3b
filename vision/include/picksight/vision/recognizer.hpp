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
// region that passes every test of a model (judgeRegion) holds one part,
// of the model that verifies best; a region that is the whole of a part
// drawn other than trained (judgeRegion's kScale or kMirror for some model)
// holds none; any other is searched for parts that touch (one merged blob)
// with the boundary models (see locateInBlob). Holes are counted as the
// regions hold them: give the regions as the models see them
// (withHolesAtLeast with their min_hole_area).
// Regions are searched on OpenCV's worker threads (cv::setNumThreads); the
// result does not depend on their number.
std::vector<Match> recognize(const std::vector<Region>& regions,
                             const std::vector<const PartModel*>& models);

}  // namespace picksight::vision
