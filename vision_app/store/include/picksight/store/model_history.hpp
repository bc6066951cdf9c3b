// The model library's undo history: before each change of a model file
// (LEARN, TOLERANCE, GRASP, GRIPPER, FORGET), the file's bytes as they were
// (or that there was none) and a digest of what the change writes, so that
// UNDO can put the old bytes back exactly, and only over the file that change
// left.
//
// On disk, beside the models: <models dir>/undo/<sequence>.undo, one file per
// change, written atomically before the change itself, the newest numbered
// highest; kUndoDepth entries at most (the oldest dropped). An entry that
// does not read back whole (its header, its length, its SHA-256) is damaged:
// reported, never applied.
//
// Threading: none of its own; ModelLibrary calls it under its lock.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"

namespace picksight::store {

// How many changes UNDO can walk back.
constexpr size_t kUndoDepth = 32;

// One change as recorded: the type whose file it changed, the request that
// changed it, the file before (nullopt: there was none) and the SHA-256 (hex)
// of the file after (empty: the change removed it).
struct UndoEntry {
  int type = -1;
  std::string change;
  std::optional<std::string> before;
  std::string after_sha256;
};

// The teach image a change replaced or removed is kept beside its entry,
// as <entry>.png (empty: the type had none), and goes with the entry
// (drop(), setAside(), the oldest dropped); see ModelLibrary.
std::string teachImageBeside(const std::string& entry_path);

// SHA-256 of `bytes`, lower-case hex.
std::string sha256Hex(std::string_view bytes);

class ModelHistory {
 public:
  // `directory`: where the entries live (created on the first record).
  explicit ModelHistory(std::string directory);

  // Records a change of `type`'s file from `before` to `after` (nullopt:
  // none), described by `change` (kept printable, at most 200 characters),
  // and drops entries beyond kUndoDepth. The entry's path, for drop() when
  // the change itself then fails.
  Result<std::string> record(int type, std::string_view change,
                             const std::optional<std::string>& before,
                             const std::optional<std::string>& after);
  // Removes an entry (its change failed, or it was undone).
  void drop(const std::string& path);
  // Renames a damaged or stale entry to <name>.damaged (kept for a person to
  // read, out of UNDO's way); the new name.
  std::string setAside(const std::string& path);

  // The newest entry's path; nullopt when there is none.
  std::optional<std::string> newest() const;
  // Entries UNDO can still reach.
  size_t size() const;
  // Reads and checks one entry; ModelErrc::kUndoRefused says what is wrong.
  static Result<UndoEntry> read(const std::string& path);
  // Every entry that does not read back, one line each (for the start's log).
  std::vector<std::string> check() const;
  const std::string& directory() const { return directory_; }

 private:
  // Entries (".undo") or set-aside ones (".undo.damaged"), oldest first.
  std::vector<std::string> list(bool damaged) const;
  const std::string directory_;
};

}  // namespace picksight::store
