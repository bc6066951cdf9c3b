// Synthetic scenes with exact ground truth: dark anti-aliased parts on a
// light, unevenly lit, noisy background. Used by the synthetic camera source
// (the embedded default), by tests and by benchmarks.
//
// Conventions: pixel centres at integer coordinates (pixel (u, v) covers
// [u-0.5, u+0.5] x [v-0.5, v+0.5]); image axes x right, y down; angles in
// degrees, a part frame point (px, py) lands at
//   (x + px cos a - py sin a, y + px sin a + py cos a).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>
#include "picksight/synthetic/front_light.hpp"

#include <opencv2/core.hpp>

#include "picksight/synthetic/simulated_robot.hpp"

namespace picksight::synthetic {

// A part's silhouette in its own frame: loops[0] is the outer boundary, the
// others are holes. Canonical frame: the area centroid is the origin, the axis
// of least second moment is +x, and +x points to the side where the part
// reaches farther from the centroid along that axis.
struct Shape {
  std::vector<std::vector<cv::Point2d>> loops;
};

struct PartTruth {
  std::string type;
  double x = 0;  // area centroid, pixels
  double y = 0;
  double angle_deg = 0;       // [0, 360)
  double symmetry_deg = 360;  // 360 directed, 180 axis only, 0 isotropic
  double area_px = 0;         // exact polygon area
  bool touching = false;      // in contact with another part (SceneOptions::touching)
};

struct SceneOptions {
  int width = 1280;
  int height = 960;
  int parts = 8;
  uint64_t seed = 1;
  // Part types to draw from (empty = all of partTypes()).
  std::vector<std::string> types;
  // Size of a part's longest side in pixels (scaled so `parts` fit when needed).
  double part_size = 120;
  double noise_sigma = 3.0;       // grey levels, Gaussian
  bool uneven_light = true;       // smooth illumination gradient and vignetting
  double background_level = 200;  // grey level of the lit background
  double part_level = 45;         // grey level of a part
  // Parts in contact by pairs: each second part is moved against the one
  // before it (a random side, edges meeting with no gap), so that a binary
  // image shows the two as one blob. Pairs that find no free spot stay apart.
  bool touching = false;
  // Gaussian blur of the rendered image (optics), sigma in pixels; 0 = none.
  double blur_sigma = 0;
  // The light of a front-lit cell (front_light.hpp; off: parts lit as from
  // behind). Grey only: a colour front light is refused.
  FrontLight front;
};

// Options for a scene of `parts` parts of `types` (empty = all) in a
// width x height image, everything else at its default: what most scenes
// differ by.
inline SceneOptions sceneOptions(int width, int height, int parts, uint64_t seed,
                                 std::vector<std::string> types = {}) {
  SceneOptions o;
  o.width = width;
  o.height = height;
  o.parts = parts;
  o.seed = seed;
  o.types = std::move(types);
  return o;
}

// The default part types: "rectangle", "l_shape", "l_shape_mirror",
// "disc_holes", "gear".
const std::vector<std::string>& partTypes();

// Every type the generator knows: the default ones, then "l_shape_small"
// (l_shape at 3/4 scale: same shape, other size), "triangle" (equilateral:
// isotropic inertia, 3-fold), "hex_nut" (hexagon with a bore: 6-fold), "t_shape"
// (mirror-symmetric, directed) and "slot" (a stadium with an off-centre bore:
// lines and arcs).
const std::vector<std::string>& allPartTypes();

// The canonical silhouette of a part type whose longest side is `size` pixels.
// Throws std::invalid_argument for an unknown type.
Shape partShape(const std::string& type, double size);

// Symmetry of the inertia-based angle for a shape (see PartTruth::symmetry_deg).
double angleSymmetryDeg(const Shape& shape);

// Exact area of a shape (outer minus holes).
double shapeArea(const Shape& shape);

// Area, centroid and central second moments of a shape (outer minus holes),
// exact for its polygons whatever the winding of each loop. Image axes.
struct ShapeMoments {
  double area = 0;
  double cx = 0;
  double cy = 0;
  double mu20 = 0;  // sum (x - cx)^2 dA
  double mu11 = 0;  // sum (x - cx)(y - cy) dA
  double mu02 = 0;  // sum (y - cy)^2 dA
};
ShapeMoments shapeMoments(const Shape& shape);

// A shape moved from its own frame to image pixels with the pose convention
// above (centroid at (x, y), rotated by angle_deg).
Shape placedShape(const Shape& shape, double x, double y, double angle_deg);

class SceneRenderer {
 public:
  // Lays out the parts (random non-overlapping positions and angles drawn
  // from the seed) and renders the clean image once.
  explicit SceneRenderer(SceneOptions options);

  const SceneOptions& options() const { return options_; }
  const std::vector<PartTruth>& truth() const { return truth_; }
  // Noise-free CV_8UC1 image.
  const cv::Mat& clean() const { return clean_; }
  // The clean image plus sensor noise that differs per frame index and is
  // reproducible for a given (seed, index). Cheap: no re-rendering.
  cv::Mat render(uint64_t frame_index) const;
  // The same frame written into `out` (reallocated only when its size or type
  // differ), so a caller with pooled buffers renders without allocating.
  void renderInto(uint64_t frame_index, cv::Mat& out) const;

  // Shows a simulated robot's calibration target held at `at_mm` (robot mm)
  // as `camera` sees it, over the parts, or no target (nullopt), and renders
  // the clean image again (the layout and the noise stay). The target is as
  // dark as a part and blurred like the rest.
  void setTarget(const RobotCamera& camera, const CalibrationTarget& target,
                 std::optional<cv::Point2d> at_mm);
  // Where the target's dots are drawn; empty with no target.
  const std::vector<TargetDotTruth>& targetTruth() const { return target_truth_; }

 private:
  // clean_ from base_ plus the target, blurred and rounded to 8 bits.
  void renderClean(const RobotCamera* camera, const CalibrationTarget* target,
                   std::optional<cv::Point2d> at_mm);

  SceneOptions options_;
  std::vector<PartTruth> truth_;
  std::vector<TargetDotTruth> target_truth_;
  cv::Mat base_;   // CV_32F: the lit background and the parts, before blur
  cv::Mat light_;  // CV_32F gain per pixel; empty with even light
  cv::Mat clean_;
  std::vector<cv::Mat> noise_bank_;  // CV_16SC1 noise fields reused across frames
};

}  // namespace picksight::synthetic
