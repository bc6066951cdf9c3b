// The model library: one file per trained part type under
// <data dir>/models/, loaded at start, written atomically on every change,
// each change recorded first in the undo history (<models>/undo/, see
// model_history.hpp) so that undo() can put the file back byte for byte.
//
// Threading: every member is thread-safe. Readers get an immutable snapshot
// (shared_ptr), so a recognition in progress never sees a half-changed list.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/store/model_file.hpp"
#include "picksight/store/model_history.hpp"
#include "picksight/vision/models/part_model.hpp"

namespace picksight::store {

using ModelList = std::vector<vision::PartModel>;
using GraspMap = std::map<int, GraspSetup>;  // by type; a type without grasps may be absent

// What undo() put back.
// A model's files as stored (JOB SAVE): the model file's text and its
// teach image (none: the type has none).
struct StoredModelFiles {
  int type = -1;
  std::string yaml;
  std::optional<std::string> teach_png;
};

struct UndoOutcome {
  int type = -1;
  std::string change;  // the request undone, as recorded ("LEARN 3 bracket")
  // The model now in force for `type`; nullopt: the undone change had
  // created it, and the type has no model again.
  std::optional<vision::PartModel> restored;
  size_t left = 0;  // changes UNDO can still walk back
};

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

  // Every change below is recorded in the undo history first, described by
  // `change` (the request line; empty: the method's own words); a history
  // that cannot be written refuses the change (kStorage), so that no change
  // is made that UNDO could not take back.

  // Adds or replaces the model of model.type: the file first, then memory.
  // A replaced model keeps its grasp styles and gripper. `teach_png`: the
  // image the model was taught on (PNG bytes), written atomically beside
  // the model file as type_<n>.png after it; without one, an older type's
  // image is removed (it would show another model). The image a change
  // replaces is kept with its undo entry, so undo() puts it back. A teach
  // image that cannot be written is logged and leaves the type without one
  // (the model, the part that matters, is stored).
  Result<void> store(const vision::PartModel& model, std::string_view change = {},
                     const std::optional<std::string>& teach_png = std::nullopt);
  // Removes the model of `type` (file, teach image and memory);
  // ModelErrc::kUnknownType if there is none.
  Result<void> remove(int type, std::string_view change = {});
  // Replaces the grasp styles and gripper of `type`, written with its model;
  // ModelErrc::kUnknownType if there is no model of `type`.
  Result<void> setGrasp(int type, const GraspSetup& grasp, std::string_view change = {});
  // Changes the model of `type` in place: `change` edits a copy (under the
  // library's lock, so a LEARN of the same type at the same moment is never
  // overwritten by the older model), which is validated, prepared again
  // (derived members depend on the tolerances) and written with its grasps,
  // the file first, then memory. Returns the stored model.
  // ModelErrc::kUnknownType if there is no model of `type`, kInvalidModel
  // (nothing written) if the changed model is not valid, kStorage if the file
  // cannot be written.
  Result<vision::PartModel> update(int type, const std::function<void(vision::PartModel&)>& change,
                                   std::string_view what = {});

  // Takes back the newest change still in the history: its type's file
  // written again with the bytes it had before (atomically), or removed if
  // the change had created it, then the model and grasps in memory read from
  // those bytes. ModelErrc::kNothingToUndo when the history is empty;
  // kUndoRefused when the newest entry is damaged, when the file is no longer
  // what that change wrote (edited by hand since, or the change did not
  // complete), or when the old bytes do not read as a model: nothing is
  // changed, the entry is set aside (<name>.damaged) and the message names
  // it; the next undo() reaches the change before it. kStorage when the
  // file cannot be written (the entry is kept).
  Result<UndoOutcome> undo();
  // Changes undo() can still walk back (at most kUndoDepth).
  size_t undoDepth() const;
  // The history's entries that do not read back, one line each.
  std::vector<std::string> checkHistory() const;

  // Every model's files, read under the library's lock (no LEARN between
  // two of them).
  Result<std::vector<StoredModelFiles>> files() const;
  // JOB LOAD: makes `staged` (a complete models directory written and
  // synced by the caller, beside directory()) the library's directory and
  // `models` with `grasps` (read from those files) the models in force, in
  // one step for readers. The two directories are exchanged in one rename
  // (renameat2 RENAME_EXCHANGE), so a crash leaves one whole set of files
  // or the other; `staged` then holds the previous directory, for the
  // caller to remove, and the caller syncs their parent directory (once for
  // all of a job's files). The undo history goes with the previous
  // directory: its changes were made to other models.
  Result<void> adoptDirectory(const std::string& staged, ModelList models, GraspMap grasps);

  std::shared_ptr<const ModelList> snapshot() const;
  std::shared_ptr<const GraspMap> grasps() const;
  GraspSetup graspOf(int type) const;
  const std::string& directory() const { return directory_; }
  std::string pathOf(int type) const;
  // Where `type`'s teach image is (type_<n>.png beside its model file).
  std::string teachImagePathOf(int type) const;

 private:
  // Call with mutex_ held: records the change of `type`'s file to `after`
  // (nullopt: removed) with the file's bytes now; the entry's path.
  Result<std::string> recordChange(int type, std::string_view change,
                                   const std::optional<std::string>& after);
  // Call with mutex_ held: records the change, then writes `text` as
  // `type`'s file atomically; a write that fails drops the entry (nothing
  // changed, so nothing to undo).
  Result<void> writeWithUndo(int type, std::string_view change, const std::string& text);
  // Call with mutex_ held: keeps `type`'s teach image as it is now (empty:
  // none) beside the history entry `entry`, for undo().
  Result<void> keepTeachImage(int type, const std::string& entry);

  const std::string directory_;
  ModelHistory history_;
  mutable std::mutex mutex_;  // guards models_ and grasps_, serializes writers
  std::shared_ptr<const ModelList> models_;
  std::shared_ptr<const GraspMap> grasps_;
};

}  // namespace picksight::store
