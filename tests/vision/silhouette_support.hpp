// Helpers of the tests on public silhouettes: models trained from drawings
// of the test data the way the silhouette benchmark trains them, scenes of
// them recognized, and the drawn part a report is about.
#pragma once

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "picksight/codecs/codecs.hpp"

#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace picksight::test {

struct SilhouetteSpec {
  std::string name;
  std::string file;  // under the test data directory; empty: the own part type `name`
  double size_px = 0;
};

// Binarization as the benchmark sets it: a window wider than any part.
inline vision::BinarizeOptions silhouetteBinarization() {
  vision::BinarizeOptions b;
  b.adaptive_window = 400;
  return b;
}

// The types and their models, type i trained alone on an image rendered
// with `look` and seed first_seed + i.
struct SilhouetteModels {
  std::vector<synthetic::SilhouetteType> types;
  std::vector<vision::PartModel> models;
  std::vector<bool> chiral;
  // The models as the recognizer takes them: valid while `models` is.
  std::vector<const vision::PartModel*> list() const {
    std::vector<const vision::PartModel*> out;
    for (const auto& m : models) out.push_back(&m);
    return out;
  }
};

// `front`: under a front light, binarized as LOCATE binarizes by default,
// each type taught from the largest region of its image (a textured belt's
// blotches are regions too), as LEARN takes the dominant part.
inline SilhouetteModels trainSilhouettes(const std::vector<SilhouetteSpec>& specs,
                                         const synthetic::SilhouetteSceneOptions& look,
                                         uint64_t first_seed = 7, bool front = false) {
  vision::TrainOptions train;
  if (!front) train.binarize = silhouetteBinarization();
  SilhouetteModels out;
  for (size_t i = 0; i < specs.size(); ++i) {
    const SilhouetteSpec& spec = specs[i];
    if (spec.file.empty()) {
      out.types.push_back(synthetic::silhouetteFromPartType(spec.name, spec.size_px));
    } else {
      const std::string path = std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + spec.file;
      const cv::Mat drawing = picksight::codecs::imread(path, cv::IMREAD_GRAYSCALE);
      INFO(path);
      REQUIRE_FALSE(drawing.empty());
      out.types.push_back(synthetic::silhouetteFromDrawing(spec.name, drawing, spec.size_px));
    }
    const int side = static_cast<int>(spec.size_px * 1.5) + 300;
    const cv::Mat image =
        synthetic::renderSilhouetteAlone(out.types.back(), side, look, first_seed + i, nullptr);
    const auto outcome = [&] {
      if (!front) return vision::trainModel(image, static_cast<int>(i), spec.name, train);
      const auto regions =
          vision::findRegions(vision::binarize(image, train.binarize), train.regions, image);
      REQUIRE_FALSE(regions.empty());
      size_t largest = 0;
      for (size_t k = 1; k < regions.size(); ++k) {
        if (regions[k].area > regions[largest].area) largest = k;
      }
      return vision::trainModelFromRegion(image, regions[largest], static_cast<int>(i), spec.name,
                                          train);
    }();
    INFO(spec.name << ": " << (outcome ? std::string() : outcome.error().message));
    REQUIRE(outcome.ok());
    out.chiral.push_back(!outcome.value().body.mirror_symmetric);
    out.models.push_back(outcome.value());
  }
  return out;
}

// A scene of `parts` parts on a 1280 x 720 frame.
inline synthetic::SilhouetteSceneOptions smallScene(
    const synthetic::SilhouetteSceneOptions& look, uint64_t seed, int parts,
    double distractor_share,
    synthetic::Arrangement arrangement = synthetic::Arrangement::kSeparated) {
  synthetic::SilhouetteSceneOptions o = look;
  o.width = 1280;
  o.height = 720;
  o.parts = parts;
  o.seed = seed;
  o.distractor_share = distractor_share;
  o.arrangement = arrangement;
  return o;
}

// Frame `frame` of a scene recognized with every model.
// `front`: binarized as LOCATE binarizes by default (see trainSilhouettes).
inline std::vector<vision::Match> recognizeSilhouettes(const synthetic::SilhouetteScene& scene,
                                                       uint64_t frame,
                                                       const SilhouetteModels& models,
                                                       bool front = false) {
  const cv::Mat grey = scene.render(frame);
  const vision::BinarizeOptions binarization =
      front ? vision::BinarizeOptions{} : silhouetteBinarization();
  return vision::recognize(vision::findRegions(vision::binarize(grey, binarization), {}, grey),
                           models.list());
}

// The drawn part a report is about: the one whose centroid lies within
// `radius` of the reported one (parts lie farther apart than that, their
// gap, so at most one does); nullptr when there is none.
inline const synthetic::SilhouettePart* drawnNear(
    const std::vector<synthetic::SilhouettePart>& truth, const vision::Match& m, double radius) {
  const auto near =
      std::find_if(truth.begin(), truth.end(), [&](const synthetic::SilhouettePart& t) {
        return std::hypot(t.centre.x - m.centroid.x, t.centre.y - m.centroid.y) < radius;
      });
  return near == truth.end() ? nullptr : &*near;
}

// As drawnNear, but fails the test case when there is none.
inline const synthetic::SilhouettePart& drawnUnder(
    const std::vector<synthetic::SilhouettePart>& truth, const vision::Match& m, double radius) {
  INFO(m.model->name << " reported at " << m.centroid.x << ", " << m.centroid.y
                     << (m.from_edges ? " from its edges" : ""));
  const synthetic::SilhouettePart* near = drawnNear(truth, m, radius);
  REQUIRE(near != nullptr);
  return *near;
}

}  // namespace picksight::test
