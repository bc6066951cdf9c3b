// Cast shadows joined to dark parts: found in a region's grey levels and cut
// off the part, so that its outline is the part's own edge and not its
// shadow's.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace picksight::vision {

// A front light casts each part's shadow beside it on the surface. Under a
// dark part the shadow is darker than the surface but lighter than the part,
// and often darker than the threshold between the two: it then joins the
// part in the mask, and moves the part's outline, area and centroid by
// pixels. What tells it from the edge's blur is its width: the blur between
// part and surface is a shell a pixel or two thick, a shadow a layer several
// pixels thick at one level of its own, on the part's outer boundary.
//
// For every region of `mask` (dark parts on a lighter surface in `grey`),
// the pixels lighter than the part by a quarter of the contrast around those
// more than 2 px deep in the mask, reaching the region's outline, are its
// shadow,
// when they lie at a level of their own well apart from the part's spread
// and from the surface. Near them the part is thresholded halfway between
// the part's level and the shadow's instead (its edge against the shadow),
// elsewhere it is left as it was.
struct ShadowCut {
  cv::Mat mask;  // the mask with shadows cut off (the input's own data when none)
  // 255 where the level just outside a part is its shadow's, not the
  // surface's (the shadow and a few pixels around it), over the whole frame;
  // empty when no shadow was cut.
  cv::Mat zone;
  int shadows = 0;  // regions a shadow was cut from
  // The lens's blur (a Gaussian's sigma, px) read at the edges of the
  // regions a shadow was cut from (their median): how far out the level
  // beside a part is read past its own edge's blur (outsideLevels).
  double blur_px = 0;
};

ShadowCut cutShadows(const cv::Mat& mask, const cv::Mat& grey,
                     const std::vector<std::vector<cv::Point>>& contours,
                     const std::vector<cv::Vec4i>& hierarchy, double min_area);

// The level just outside a part, where `where` is set (CV_32F over the
// part's box; -1 elsewhere): the levels of a ring 1 to 2 pixels out of
// `own` (past a sharp edge's blur, within a shadow; further out for a lens
// blurring by `blur_px`, a Gaussian's sigma) over `free` pixels (not
// another region's), averaged with Gaussian weights of 1.5 px (more
// further out), so that each stretch of edge is read against what lies
// beside it, a shadow whose level changes along the part with its width,
// or the lit surface.
cv::Mat outsideLevels(const cv::Mat& grey, const cv::Mat& own, const cv::Mat& free,
                      const cv::Mat& where, double blur_px);

// The median of `values` (reordered); 0 when empty.
double medianOf(std::vector<float>& values);

// The value `share` (0..1) of the way up `values` sorted, the lower of two
// when it falls between (reordered); 0 when empty.
double percentileOf(std::vector<float>& values, double share);

// The levels 3 px out (`out`) and in (`in`) of every 4th point of a
// region's outer boundary, along its normal, each where the mask says it
// is: what lies beside the part and just inside its edge.
void sideSamples(const cv::Mat& grey, const cv::Mat& mask, const std::vector<cv::Point>& outer,
                 std::vector<float>* out, std::vector<float>* in);

}  // namespace picksight::vision
