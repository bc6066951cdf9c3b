// Helpers shared by the recognition tests: train a model on a synthetic
// part, recognize a synthetic scene, find the match for a truth part.
#pragma once

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "picksight/synthetic/scene.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace picksight::test {

struct Trained {
  vision::PartModel model;
  double truth_angle = 0;
};

// Trains type id `id` on frame 0 of a one-part scene made with `options`.
inline Trained trainOn(const synthetic::SceneOptions& options, int id, const std::string& type) {
  const synthetic::SceneRenderer s(options);
  auto outcome = vision::trainModel(s.render(0), id, type);
  INFO(type << ": " << (outcome ? std::string() : outcome.error().message));
  REQUIRE(outcome.ok());
  return {outcome.value(), s.truth()[0].angle_deg};
}

// Every type trained by `train(type, id)` with ids 1, 2, ..., and the
// models as the recognizer takes them (pointers into `trained`).
struct TrainedSet {
  std::map<std::string, Trained> trained;
  std::vector<const vision::PartModel*> models;
};

template <typename TrainFn>
TrainedSet trainAll(const std::vector<std::string>& types, TrainFn train) {
  TrainedSet set;
  int id = 1;
  for (const auto& type : types) set.trained[type] = train(type, id++);
  for (const auto& entry : set.trained) set.models.push_back(&entry.second.model);
  return set;
}

// The whole recognition (adaptive binarization, regions, models) of one frame.
inline std::vector<vision::Match> recognizeFrame(
    const synthetic::SceneRenderer& s, uint64_t frame,
    const std::vector<const vision::PartModel*>& models) {
  const cv::Mat grey = s.render(frame);
  return vision::recognize(vision::findRegions(vision::binarize(grey, {}), {}, grey), models);
}

// The match within 5 px of a truth part, or nullptr.
inline const vision::Match* nearest(const std::vector<vision::Match>& matches,
                                    const synthetic::PartTruth& t) {
  const vision::Match* best = nullptr;
  for (const auto& m : matches) {
    if (std::hypot(m.centroid.x - t.x, m.centroid.y - t.y) < 5) best = &m;
  }
  return best;
}

}  // namespace picksight::test
