// Blob analysis: the features of one region, for unknown
// regions and as the body part of trained part models.
#pragma once

#include <array>
#include <complex>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

using HuArray = std::array<double, 7>;

struct BlobFeatures {
  double area = 0;       // pixels (grey-level coverage when measured with a grey image)
  double perimeter = 0;  // length of the outer boundary, pixels
  double roundness = 0;  // 4 pi area / perimeter^2: 1 for a disc
  int holes = 0;
  // Of the ellipse with the same second moments: 0 for a disc or a square,
  // sqrt(3)/2 for a 2:1 rectangle, towards 1 for a bar.
  double eccentricity = 0;
  cv::Rect bbox;
  cv::Point2d centroid;
  double angle_deg = 0;  // orientation, as Region::angle_deg
  // Raw moments about the image origin (pixel centres at integer
  // coordinates), central and normalized central moments.
  cv::Moments moments;
  HuArray hu{};      // the 7 Hu invariants
  HuArray log_hu{};  // H_i = -sign(h_i) log10|h_i| (0 where h_i is 0)
  // Distance from the centroid to the outer boundary at `radial_samples`
  // angles, the first along the orientation (so it turns with the part), then
  // every 360/n degrees towards the image y axis.
  std::vector<double> radial_signature;
  // Pixels of the skeleton of the body (Zhang-Suen thinning), image coordinates.
  std::vector<cv::Point> skeleton;
};

struct FeatureOptions {
  int radial_samples = 64;
  bool skeleton = true;  // thinning is the one costly feature
};

BlobFeatures blobFeatures(const Region& region, const FeatureOptions& options = {});

HuArray huInvariants(const cv::Moments& m);
HuArray logHu(const HuArray& hu);

// Length of an 8-connected closed pixel boundary (as from cv::findContours
// with CHAIN_APPROX_NONE): Vossepoel and Smeulders' estimator from the counts
// of straight steps, diagonal steps and direction changes. Counting steps as
// 1 and sqrt(2) overestimates a disc's perimeter by ~5% (a staircase is not
// a curve); this estimator is within ~1% for circles and slanted lines, and
// 2% short on lines along a pixel axis.
double boundaryLength(const std::vector<cv::Point>& closed);

// The extent of a point set whatever its turn: its diameter (the longest
// distance between two of its points) and its width (the narrowest strip
// that holds it). A shape inside another is neither longer nor wider,
// however the two are turned: what a blob of touching parts may hold.
struct Extent {
  double diameter = 0;
  double width = 0;
};
Extent extentOf(const std::vector<cv::Point2f>& points);
// The same of a region's outline (pixels), the same figures to the last
// digit, in a seventh of the time.
Extent extentOfOutline(const std::vector<cv::Point>& outline);

// Eccentricity of the moments' equivalent ellipse.
double eccentricity(const cv::Moments& m);

std::vector<double> radialSignature(const std::vector<cv::Point>& outer, cv::Point2d centroid,
                                    double start_deg, int samples);

// Zhang-Suen thinning of a CV_8UC1 mask (non-zero = body): a one-pixel-wide
// 255 skeleton of the same size.
cv::Mat skeletonize(const cv::Mat& mask);

// The region as a CV_8UC1 mask over its bounding box (outer minus holes).
cv::Mat regionMask(const Region& region);

// Complex moment c_k = sum w (z - c)^k / (area * scale^k) over the region's
// coverage, with z = x + i y about the centroid c and scale = sqrt(area).
// Turning a part by a turns c_k by k a; a part with k-fold rotational
// symmetry has c_j = 0 for every j that k does not divide. c_2 is the
// inertia: arg c_2 = 2 theta.
std::complex<double> complexMoment(const Region& region, int k);

}  // namespace picksight::vision
