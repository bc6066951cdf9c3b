// Part models (prototypes): body features with tolerances, a boundary model,
// the part's symmetries, and the tests made on a model alone (its values,
// the Hu distance, which hand a region shows). Training a model from an
// image and preparing its derived data are the training stage's
// (picksight/vision/training/part_training.hpp).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/result.hpp"

#include "picksight/vision/models/boundary_model.hpp"
#include "picksight/vision/models/boundary_verification.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"
#include "picksight/vision/segmentation/colour_axis.hpp"

namespace picksight::vision {

// What the search for touching parts reads of a model (blob_search/): held
// here as an opaque shared pointer, built by prepareModel (training/), so
// that this stage does not include the stage above it.
struct BlobSearchModel;

// The highest orientation and symmetry order a model may have (training
// tries orders up to it; validateModel rejects more).
constexpr int kMaxModelOrder = 24;

struct BodyModel {
  double area = 0;              // pixels
  double area_tolerance = 0.1;  // relative: a match is within area * (1 +- this)
  int holes = 0;
  HuArray log_hu{};
  // Invariants too close to 0 for their sign and magnitude to survive
  // rotation and resampling (most of a symmetric part's odd-order ones) are
  // left out of the distance.
  std::array<bool, 7> hu_used{};
  double hu_tolerance = 1.0;  // on sum_i |H_i(a) - H_i(b)| over the used invariants
  // A part that equals its mirror image (after a turn): its boundary and the
  // mirror image's, lined up, lie apart by less than 3 px of length. A part
  // that does not is never matched to its mirror image: where the two
  // boundaries differ, however little of the outline that is, the mirror
  // image fits the edges better (showsMirrorImage).
  bool mirror_symmetric = false;
};

struct PartModel {
  int type = 0;
  std::string name;
  BodyModel body;
  // Rotation from the complex moment of order k (see complexMoment):
  // rotation = (arg c_k - phase) / k + j 360 / k, j picked by verification.
  // k = 2 is the axis of least inertia; parts with isotropic inertia (a
  // square, a gear) need a higher order. 0: no order carries a direction (a
  // disc): rotation 0.
  int orientation_order = 2;
  double orientation_phase_deg = 0;
  // k-fold rotational symmetry: the part looks the same turned by 360/k.
  // 1 = none, 0 = any turn (a disc).
  int symmetry_order = 1;
  // Where the part was in the training image (information only: the model
  // frame is the trained pose with the centroid at the origin).
  cv::Point2d trained_centroid;
  double trained_angle_deg = 0;
  // More views of the part than the teach image (LEARNVIEW): where each
  // read the part's centroid, in the teach image's frame (its own reading
  // at 0, 0), and where the model's origin now lies in that frame (the
  // median of every reading, the teach image's included; see
  // addViewReading). One image's texture, glints and noise put its centroid
  // a tenth of a pixel off, and every part found afterwards inherited it;
  // readings of the part lying elsewhere average it out.
  std::vector<cv::Point2d> views;
  cv::Point2d origin_shift;
  // The region settings it was trained with (pixels): regions and holes
  // smaller than these were not part of the image it learned from.
  double min_region_area = 0;
  double min_hole_area = 0;
  // The polarity the cell's settings had when it was taught (its regions
  // were the dark or the light ones), so that a change of polarity names the
  // models taught under the other. None: taught before it was recorded.
  std::optional<Polarity> taught_polarity;
  // Taught in colour: the part's colour and its surface's, when colour told
  // them apart better than grey levels (colourSeparatesBetter). Colour
  // frames are then read projected on this axis. None: grey levels.
  std::optional<ColourAxis> colour;
  // Boundary: primitives in the model frame, their corners, and the
  // verification settings.
  double conformity = 1.0;      // pixels
  double edge_tolerance = 2.0;  // pixels between a model point and an image edge
  double verify_percent = 80;   // of the weighted boundary length
  std::vector<BoundaryLoop> loops;
  std::vector<Corner> corners;

  // Derived by prepareModel (not stored).
  std::vector<BoundarySample> samples;
  double radius = 0;  // of the boundary about the origin
  // Distance to the boundary in the model frame, up to twice the edge
  // tolerance: what tells the two hands apart (showsMirrorImage), at the
  // cost of a lookup however many primitives the boundary has. Shared
  // between copies of the model; read-only.
  std::shared_ptr<const BoundaryDistanceMap> boundary_map;
  // Its most telling corners and arcs, screening and edge samples, derived
  // once instead of at every blob searched. Shared, read-only.
  std::shared_ptr<const BlobSearchModel> blob_search;

  // Period of the reported rotation: 360 / symmetry order, 0 for any.
  double symmetryDeg() const { return symmetry_order == 0 ? 0.0 : 360.0 / symmetry_order; }
};

// The rotation reported for a part of `model` found turned by `turn_deg`
// from its taught pose: of the turns the model's symmetry makes look alike,
// the one nearest the taught pose, in (-S/2, S/2] with S = symmetryDeg():
// (-180, 180] for a part with none, (-90, 90] for a bar, (-45, 45] for a
// square; 0 for a disc. The one rule of every reported angle (recognition
// and the blob search; LOCATE, LOCATE ALL, the PLC and the results stream
// take it from the Match). Parts are taught lying as they usually lie, so
// the range's edge, where a turn of S/2 either way looks alike and noise
// picks the sign, sits as far from where parts lie as it can; the
// [0, S) this replaced had its edge at the taught pose itself, and a bar
// lying still there came out 0.0 or 179.9 frame by frame.
double reportedTurnDeg(const PartModel& model, double turn_deg);

// At most this many views beyond the teach image; a reading or an origin
// further than these from the teach image's centroid is not the same part's
// centroid (a part of another type, a speck joined), and a model that says
// so is damaged.
constexpr size_t kMaxModelViews = 32;
constexpr double kMaxViewReadingPx = 2.0;
constexpr double kMaxOriginShiftPx = 1.0;

// Where a model's origin lies in its teach image's frame given the
// centroids its views read there: the median of each coordinate over them
// and the teach image's own (0, 0). A median, not a mean: a view whose
// threshold clipped a limb or took in a speck reads its centroid half a
// pixel off, and must not drag the origin with it.
cv::Point2d originFromViews(const std::vector<cv::Point2d>& views);
// How far a model's readings (the teach image's and each view's) lie from
// its origin: the median distance (px), 0 without views.
double viewSpread(const PartModel& model);

// Why a model could not be trained, or is not valid.
enum class PartModelErrc {
  kNotGrey = 1,   // the training image is not 8-bit grey
  kNoPart,        // no part in the training image
  kSeveralParts,  // more than one part in the training image
  kInvalid,       // a model's values are out of range or inconsistent
};
const char* errorName(PartModelErrc e);
PICKSIGHT_ERROR_DOMAIN(PartModelErrc, "part model")

// Where a model lies in the image, in pixels (not grasp::Pose, which is in
// millimetres in the vision frame): model point m lands at
// centre + R(angle) (m.x, s m.y), s = -1 for the mirror image of the model.
struct ImagePose {
  cv::Point2d centre;
  double angle_deg = 0;
  bool mirrored = false;
};

// Whether the region whose edges are `edges` shows the mirror image of a
// chiral model rather than the model, given the best pose of each: decided
// only on the boundary where the two placed hands lie apart (weighted by
// how far apart, from the edge tolerance to twice it), so that a small
// off-axis notch decides as surely as the legs of an L. True as well when
// nothing there tells them apart.
bool showsMirrorImage(const PartModel& model, const ImagePose& direct, const ImagePose& mirror,
                      const EdgeDistance& edges);

// The weighted boundary length of the model that lies apart from its mirror
// image turned by `turn_deg` (weighted as showsMirrorImage weighs it): how
// far the part is from equal to its mirror image at that turn.
double chiralLength(const PartModel& model, double turn_deg);

// Checks a model's values (finite, in range, consistent); kInvalid says
// what is wrong.
Result<void> validateModel(const PartModel& model);

// Checks a prepared model's symmetry order against its own boundary (a
// model file's value, which decides the range every angle is reported in):
// turned by 360 / symmetry_order (by every 15 degrees for 0, a disc), the
// boundary must lie on itself. kInvalid names the order and how much of the
// boundary fits.
Result<void> checkSymmetry(const PartModel& model);

// Sum |H_i(a) - H_i(b)| over the invariants the model uses, the 7th (the
// mirror's sign) left out; H2..H6 compared above a floor set by the model's
// H1 (part_model.cpp), below which a part counts as round.
double huDistance(const BodyModel& body, const HuArray& log_hu);

}  // namespace picksight::vision

PICKSIGHT_ERROR_ENUM(picksight::vision::PartModelErrc)
