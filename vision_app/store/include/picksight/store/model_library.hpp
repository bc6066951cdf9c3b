// The model library: one file per trained part type under
// <data dir>/models/, loaded at start, written atomically on every change.
//
// Threading: every member is thread-safe. Readers get an immutable snapshot
// (shared_ptr), so a recognition in progress never sees a half-changed list.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/store/model_file.hpp"
#include "picksight/vision/models/part_model.hpp"

namespace picksight::app {

using ModelList = std::vector<vision::PartModel>;
using GraspMap = std::map<int, GraspSetup>;  // by type; a type without grasps may be absent

class ModelLibrary {
 public:
  // `directory` is created on the first store if missing.
  explicit ModelLibrary(std::string directory);

  // Loads every *.yaml file of the directory, replacing what was held, in
  // type order. Bad files are skipped; each gets one message naming the file
  // and its problem, as does a `directory` that is not a directory. Of two
  // files for one type, type_<n>.yaml (the one store() writes) wins.
  // Temporary files of interrupted writes are removed first (the library
  // owns its directory; call before any store()).
  std::vector<std::string> load();

  // Adds or replaces the model of model.type: the file first, then memory.
  // A replaced model keeps its grasp styles and gripper.
  Result<void> store(const vision::PartModel& model);
  // Removes the model of `type` (file and memory); ModelErrc::kUnknownType
  // if there is none.
  Result<void> remove(int type);
  // Replaces the grasp styles and gripper of `type`, written with its model;
  // ModelErrc::kUnknownType if there is no model of `type`.
  Result<void> setGrasp(int type, const GraspSetup& grasp);
  // Changes the model of `type` in place: `change` edits a copy (under the
  // library's lock, so a LEARN of the same type at the same moment is never
  // overwritten by the older model), which is validated, prepared again
  // (derived members depend on the tolerances) and written with its grasps,
  // the file first, then memory. Returns the stored model.
  // ModelErrc::kUnknownType if there is no model of `type`, kInvalidModel
  // (nothing written) if the changed model is not valid, kStorage if the file
  // cannot be written.
  Result<vision::PartModel> update(int type, const std::function<void(vision::PartModel&)>& change);

  std::shared_ptr<const ModelList> snapshot() const;
  std::shared_ptr<const GraspMap> grasps() const;
  GraspSetup graspOf(int type) const;
  const std::string& directory() const { return directory_; }
  std::string pathOf(int type) const;

 private:
  const std::string directory_;
  mutable std::mutex mutex_;  // guards models_ and grasps_, serializes writers
  std::shared_ptr<const ModelList> models_;
  std::shared_ptr<const GraspMap> grasps_;
};

}  // namespace picksight::app
