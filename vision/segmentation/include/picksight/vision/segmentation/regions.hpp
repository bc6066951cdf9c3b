// Connected regions of a binary image with their holes, and the features the
// locator needs from each: area, sub-pixel centroid, orientation.
#pragma once

#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "picksight/vision/segmentation/row_runs.hpp"

namespace picksight::vision {

struct Region {
  double area = 0;       // pixels (covered fraction summed, with a grey image)
  cv::Point2d centroid;  // sub-pixel, pixel centres at integer coordinates
  // Axis of least second moment, pointing along the longer path through the
  // region from its centroid; degrees in [0, 360), image axes (x right, y down).
  double angle_deg = 0;
  // 1 - (minor/major inertia): 0 for a disc or a square, where no axis exists.
  double elongation = 0;
  // Holes of the part, not counting pinholes (at most 2 x 2 pixels: a
  // defective pixel, dust), which are filled like glints.
  int holes = 0;
  // The pinholes filled: a region of the surface the threshold speckled
  // has them by the dozen (what LEARN tells a blotch by).
  int pinholes = 0;
  // Holes read as glints (lighter than the surface beside the part: the lamp
  // reflected, not the surface seen through it), filled and not counted.
  int glints = 0;
  cv::Rect bbox;
  bool touches_border = false;
  cv::Size image_size;  // of the image the region was found in
  // The rim was read against levels beside it rather than a plane through
  // them: the surface or the part departs from a plane there (blotches,
  // shading), or a cast shadow lies beside it. Its grey-level centroid is
  // then only as good as those levels, and its edges more trustworthy.
  bool uneven_light = false;
  // A cast shadow joined to a part was cut off it within the region's box
  // (shadows.hpp): its edge there was read against the shadow's level. Of
  // a part alone (LEARN's), its own shadow.
  bool beside_shadow = false;
  // Moments (grey-weighted with a grey image, else binary). Raw moments
  // (m00..m03) are about an origin near bbox.tl(); central and normalized
  // moments do not depend on the origin.
  cv::Moments moments;
  std::vector<cv::Point> outer;  // outer boundary, image coordinates
  std::vector<std::vector<cv::Point>> hole_boundaries;
  // The weight of every pixel in the moments (CV_32F, 0..1: grey-level
  // coverage, or 1 inside the mask without a grey image), over a box whose
  // top-left pixel is `coverage_origin`. Kept so that higher-order features
  // (complex moments for the rotation of symmetric parts) need no second pass.
  cv::Mat coverage;
  cv::Point coverage_origin;
  // The runs of `coverage` outside which it is 0 (same box; a superset of
  // its non-zero pixels), so that a pass over the coverage skips the rest
  // of the box: outside a curved or slender part, and its holes, that is
  // most of it. Empty (height 0) when not known: the whole box is read.
  RowRuns covered;
  // The grey image round the region (its box and kGreyMarginPx beyond,
  // clipped to the image), top-left pixel at `grey_origin`: where the mask
  // lost a faint stretch of a part (a thin limb at low contrast), the blob
  // search reads it here. Empty without a grey image. Shares the frame's
  // pixels when OpenCV counts their references, else a copy of the box.
  cv::Mat grey;
  cv::Point grey_origin;
};

// How far past its box a region keeps the grey image (Region::grey).
constexpr int kGreyMarginPx = 12;

struct RegionOptions {
  double min_area = 50;  // smaller regions are noise
  // Holes whose area (pixels, inside their boundary trace) is below this are
  // not counted: sensor noise or dust, never a feature a model may rely on
  // (the hole count must match exactly).
  double min_hole_area = 0;
  bool keep_border_regions = false;  // a part cut by the image edge cannot be located
  // Regions touching the image edge of at least this many pixels (> 0) are
  // kept all the same, for the parts they may hold whole: a part joined to
  // something that runs off the frame (a tray's wall, a streak of wood, a
  // shadow) is a blob of parts, like parts that touch. LOCATE sets it to
  // the smallest part its models may be; a smaller region holds none.
  double border_min_area = 0;
  // With a grey image, cast shadows joined to dark parts are cut off them
  // (see shadows.hpp), and each edge beside a shadow is read against the
  // shadow's level.
  bool cut_shadows = true;
};

// Regions of a CV_8UC1 mask (non-zero = part), 8-connected, largest first.
//
// With the grey image the mask came from, area, centroid, moments and angle
// are measured to sub-pixel accuracy from the grey levels: each pixel counts
// for the fraction of it the part covers, read from its grey level between
// the part's own level and the background's around it. A binary mask alone
// quantizes every edge pixel to 0 or 1, which biases the centroid by tenths
// of a pixel when edges run along a pixel diagonal.
//
// Regions are measured on OpenCV's worker threads (cv::setNumThreads); the
// result does not depend on their number.
std::vector<Region> findRegions(const cv::Mat& mask, const RegionOptions& options = {},
                                const cv::Mat& grey = cv::Mat());

// Where a region's outline meets something other than the part and its
// surface: the share of points along its outer boundary whose level a few
// pixels out is darker than the surface's (for dark parts; lighter for light
// ones) by a quarter of the contrast, or a few pixels in lighter than the
// part's by as much. A cast shadow beside the part, or joined to it, shows
// as such a share; an evenly lit part on its surface has next to none.
double unevenEdgeShare(const cv::Mat& grey, const cv::Mat& mask, const Region& region);

// Whether a region's outline is a step in grey level somewhere (at least
// `min_share` of it, by default a fifth, steps by 8 levels or more, read
// 3 px either side): a patch of the surface's own light that the threshold
// took in (a vignetted corner, a blotch of a textured belt) steps nowhere.
// True without the region's grey image, where nothing says otherwise.
constexpr double kMinOutlineSteppedShare = 0.2;
bool outlineSteps(const Region& r, double min_share = kMinOutlineSteppedShare);

// A step across a region's outline, as outlineSteps reads it: the levels
// kOutlineStepReachPx either side of it differ by kOutlineMinStep or more
// (a part's edge at 30 grey levels of contrast steps by 13 to 36, a patch
// of the surface's light by 2 to 4).
constexpr int kOutlineStepReachPx = 3;
constexpr int kOutlineMinStep = 8;

// How far `grey` steps across `outline` at its `i`th point: the difference
// of the levels `reach_px` either side of it, square to the outline there
// (its direction read 2 points either way); -1 where it has none or a side
// falls outside `grey`. `grey`'s top-left pixel is `grey_origin` in the
// outline's coordinates.
int stepAcrossOutline(const std::vector<cv::Point>& outline, int i, const cv::Mat& grey,
                      cv::Point grey_origin, int reach_px);

// Orientation of a region from its moments and outer boundary (see Region).
double orientationDeg(const cv::Moments& m, cv::Point2d centroid,
                      const std::vector<cv::Point>& outer);

}  // namespace picksight::vision
