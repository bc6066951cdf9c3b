// Recognition: which trained parts are in a set of regions, where and how
// turned; body features propose, the boundary model verifies.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/models/match.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

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

// Whether a region is one whole copy of a type that no model takes for a
// part, as recognize() judges a lone region, but only a larger one: some
// model finds it its mirror image or a copy larger than the part
// (judgeRegion's kMirror, kScale above the scales the model allows), none
// passes it and none finds it smaller than its part. `models` share one
// minimum hole area (the region's holes are counted with it). What the
// parts found in a blob leave is asked this (see locateInBlob): such a copy
// holds no part to search for, while one smaller than some model's part
// may be that part less what the parts beside it took off.
bool isWholeCopy(const Region& region, const std::vector<const PartModel*>& models,
                 double max_edge_tolerance);

// A region read as recognize() reads a lone region: one part where some
// model passes it (the best by ranksAbove, with its turn), else one whole
// copy where isWholeCopy says so, else neither.
LoneReading readLoneRegion(const Region& region, const std::vector<const PartModel*>& models,
                           double max_edge_tolerance);

// recognize() with each model judging holes with its own minimum hole area
// (the one it was trained with; byMinHoleArea): one recognize() per setting
// on the regions as it sees them (withHolesAtLeast). Where several settings
// found parts in one region, the setting whose best part there scores
// highest keeps the region. Best score first.
std::vector<Match> recognizeEachHoleSetting(const std::vector<Region>& regions,
                                            const std::vector<const PartModel*>& models);

}  // namespace picksight::vision
