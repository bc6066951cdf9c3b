// Making a part model ready for recognition: training one from an image of
// the part, preparing the derived data of a trained or loaded one (boundary
// samples, the model-frame distance map, the blob search's data) and
// scaling one to another camera resolution. A stage above the blob search
// because preparing a model builds that search's side of it.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"

#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

struct TrainOptions {
  BinarizeOptions binarize;
  RegionOptions regions;
  double conformity = 1.0;
  double verify_percent = 80;
  double area_tolerance = 0.1;
};

// Trains from a grey image holding exactly one part. Errors: PartModelErrc.
Result<PartModel> trainModel(const cv::Mat& grey, int type, const std::string& name,
                             const TrainOptions& options = {});

// Trains from one region of a grey image, found by findRegions on the whole
// image with `options` (the way recognition will see the part): the other
// regions are left out. Errors as trainModel's, except kNoPart and
// kSeveralParts.
Result<PartModel> trainModelFromRegion(const cv::Mat& grey, const Region& region, int type,
                                       const std::string& name, const TrainOptions& options = {});

// Turns the model's boundary by `turn_deg` about its origin, then moves it
// by `shift` (model frame), and prepares it again.
void moveBoundary(PartModel& model, double turn_deg, cv::Point2d shift);

// Where on region `r` lies the point a model's origin stands for (image
// pixels), the model's boundary placed at `pose` on the region's edges: the
// centroid of its grey levels, or where its rim was read against uneven
// levels (Region::uneven_light) the centroid of the area its edges enclose
// (outlineCentroid), unless that lies over a pixel from the grey one.
// Training puts the origin there; each view reads it (addViewReading).
cv::Point2d referencePoint(const PartModel& model, const Region& r, const ImagePose& pose);

// Adds a view's reading of the part's centroid (the teach image's frame,
// see PartModel::views) and moves the origin to the median of them all:
// the boundary is moved the other way, so that a part is found where it
// was and reported at the new origin.
void addViewReading(PartModel& model, cv::Point2d reading);

// Fills the derived members; call after training or loading.
void prepareModel(PartModel& model);

// The model as an image `scale` times the size of its own sees it (frame
// pixels of a resized camera from sensor pixels, and back with 1 / scale):
// lengths, areas and boundary scaled, prepared. The edge tolerance and the
// conformity stay in pixels of the new image: edges are found there to the
// same fraction of a pixel whatever the scale.
PartModel scaledModel(const PartModel& model, double scale);

}  // namespace picksight::vision
