// The model file: one part model as human-readable YAML with a format
// version, so an integrator can read, diff and hand-tune (weights, tolerances,
// verify percent) what training produced.
#pragma once

#include <string>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/grasp/grasp.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace picksight::store {

// Why a model could not be read, stored or removed.
enum class ModelErrc {
  kUnknownType = 1,  // no model of that type
  kStorage,          // the file or its directory could not be written or removed
  kInvalidModel,     // the model breaks a rule (tolerances, weights, grasps...)
  kBadFile,          // the file is not a readable part model
  kNothingToUndo,    // UNDO: no change left in the history
  kUndoRefused,      // UNDO: the newest entry is damaged or no longer applies (set aside)
};
const char* errorName(ModelErrc e);
PICKSIGHT_ERROR_DOMAIN(ModelErrc, "model")

// Version 2 added the grasp section; version 1 files are still read (no
// grasp styles, no fingers).
constexpr int kModelFormatVersion = 2;
constexpr int kOldestModelFormatVersion = 1;

// How the robot picks a part type: grasp styles in order of preference (in
// the part's frame, vision-frame mm and degrees) and the gripper's fingers.
struct GraspSetup {
  std::vector<grasp::GraspStyle> styles;
  grasp::Gripper gripper;
};

// Limits that keep a model file (and a reply line) small.
constexpr size_t kMaxGraspStyles = 16;
constexpr size_t kMaxFingers = 8;

struct ModelRecord {
  vision::PartModel model;
  GraspSetup grasp;
};

std::string modelToYaml(const vision::PartModel& model, const GraspSetup& grasp = {});

// Parses and validates; errors say what is wrong (not which file: the caller
// knows). The model comes back prepared (vision::prepareModel).
Result<ModelRecord> modelRecordFromYaml(const std::string& text);
Result<vision::PartModel> modelFromYaml(const std::string& text);

// Checks grasp values (finite, in range, within the limits);
// ModelErrc::kInvalidModel says what is wrong.
Result<void> validateGrasp(const GraspSetup& grasp);

}  // namespace picksight::store

PICKSIGHT_ERROR_ENUM(picksight::store::ModelErrc)
