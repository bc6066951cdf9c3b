// Scenes of arbitrary silhouettes (public shape drawings, or any mask) as a
// camera sees them: drawn at 4x, turned, mirrored or scaled there, averaged
// down (anti-aliased edges), on an unevenly lit, blurred, noisy background;
// parts separated, touching by pairs, or overlapping by pairs. The truth is
// measured on the drawn masks, not taken from the nominal pose.
//
// Conventions as in scene.hpp: pixel centres at integer coordinates, image
// axes, a part turned by angle_deg from x towards y. Not thread-safe; one
// scene per thread.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/scene.hpp"

namespace picksight::synthetic {

// Drawings are made this many times finer than the image, then averaged down.
constexpr int kSilhouetteSupersample = 4;

// One kind of part: its mask at the supersampled resolution, cropped to the
// ink, in its trained pose (rotation 0).
struct SilhouetteType {
  std::string name;
  cv::Mat mask;  // CV_8UC1, 255 on the part
};

// A white-on-black drawing (any size) made into a type whose longest side is
// `size_px` image pixels: smoothed so that the drawing's pixel steps become
// curves, scaled, thresholded. Empty mask when the drawing holds no ink.
SilhouetteType silhouetteFromDrawing(const std::string& name, const cv::Mat& drawing,
                                     double size_px);

// One of the repository's own part types (partShape) as a silhouette type.
SilhouetteType silhouetteFromPartType(const std::string& type, double size_px);

enum class Arrangement { kSeparated, kTouching, kOverlapping };
const char* arrangementName(Arrangement a);

// What a part of the scene is: a trained type as trained, or a distractor
// made from one (its mirror image, or a scaled copy).
enum class PartKind { kTrue, kMirrored, kSmaller, kLarger };

struct SilhouetteSceneOptions {
  int width = 1920;
  int height = 1080;
  int parts = 20;
  uint64_t seed = 1;
  Arrangement arrangement = Arrangement::kSeparated;
  // Share of the parts that are distractors (mirrored where the type is
  // chiral, else 0.8x or 1.25x copies).
  double distractor_share = 0.25;
  double smaller_scale = 0.8;
  double larger_scale = 1.25;
  // Overlapping pairs: each pair hides between these fractions of the
  // outline of the part that loses most.
  double min_hidden = 0.05;
  double max_hidden = 0.25;
  double gap_px = 8;  // between parts that are not meant to meet
  double noise_sigma = 3.0;
  double blur_sigma = 0.7;
  double background_level = 200;
  double part_level = 45;
  bool uneven_light = true;
  // The light of a front-lit cell (off: parts lit as from behind).
  FrontLight front;
};

struct SilhouettePart {
  size_t type = 0;  // index into the scene's types
  PartKind kind = PartKind::kTrue;
  cv::Point2d centre;  // centroid of the whole drawn mask, image pixels
  double angle_deg = 0;
  bool touching = false;  // meets its pair partner (touching scenes)
  double hidden = 0;      // fraction of its outline inside another part
  int partner = -1;       // index of the other part of its pair
};

class SilhouetteScene {
 public:
  // Lays out and draws the scene. `chiral[i]`: type i differs from its mirror
  // image (only those get mirrored distractors). Parts that find no free
  // spot are left out (truth() says what was drawn).
  SilhouetteScene(const std::vector<SilhouetteType>& types, const std::vector<bool>& chiral,
                  const SilhouetteSceneOptions& options);

  const std::vector<SilhouettePart>& truth() const { return truth_; }
  // The frame with noise that differs per frame index (CV_8UC1; CV_8UC3,
  // BGR, under a colour front light).
  cv::Mat render(uint64_t frame_index) const;

 private:
  SilhouetteSceneOptions options_;
  std::vector<SilhouettePart> truth_;
  cv::Mat clean_;  // CV_32F grey levels before noise
};

// A training image: one part of `type` turned by `angle_deg` in the middle
// of a `side` x `side` image lit and blurred like the scenes. Returns the
// image; `centre` receives the drawn centroid. At 0 the drawing is copied
// as it is; at any other angle it is resampled as every scene part is,
// which rounds tips and stems thinner than a pixel or two of the
// supersampled drawing.
cv::Mat renderSilhouetteAlone(const SilhouetteType& type, int side,
                              const SilhouetteSceneOptions& look, uint64_t seed,
                              cv::Point2d* centre, double angle_deg = 0);

// A training image as the cell's camera takes it: a whole frame of
// look.width x look.height, lit as the scenes are across the frame, with
// one part of `type` turned by `angle_deg` whose drawn centroid lies at
// `where` (to a quarter pixel; `centre` receives it). renderSilhouetteAlone
// lights its small image with a whole frame's fall-off and vignette: across
// the part, several times the light's change of any scene.
cv::Mat renderSilhouetteInFrame(const SilhouetteType& type, const SilhouetteSceneOptions& look,
                                uint64_t seed, cv::Point2d where, cv::Point2d* centre,
                                double angle_deg = 0);

}  // namespace picksight::synthetic
