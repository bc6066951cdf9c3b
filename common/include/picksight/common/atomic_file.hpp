// Atomic file replacement: a reader (or a restart after a crash mid-write)
// sees either the old content or the new one, never a torn file.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"

namespace picksight {

// Writes `content` to a temporary file beside `path`, fsyncs it, renames it
// over `path` and fsyncs the directory.
Result<void> writeFileAtomically(const std::string& path, const std::string& content);

// Test seam: the same, calling `before_step` with the name of each step just
// before it runs ("create", "write", "sync", "close", "rename", "sync-dir"),
// so that tests can check the order and kill a child process at every step.
// Called on the caller's thread.
Result<void> writeFileAtomically(const std::string& path, const std::string& content,
                                 const std::function<void(std::string_view step)>& before_step);

// Makes the entries of `directory` (a new, renamed or removed file, a new
// subdirectory) durable: fsync of the directory itself.
Result<void> syncDirectory(const std::string& directory);

// Removes from `directory` the temporary files ("<name>.tmp.<pid>") that
// writeFileAtomically leaves when its process dies mid-write, and returns
// their names. For a directory the calling process alone writes to, called
// at start (before any write of its own): it does not ask whether <pid> is
// still alive, because after a reboot the number may belong to anybody.
// A missing directory has nothing to remove.
Result<std::vector<std::string>> removeStaleTemporaries(const std::string& directory);

// Reads a whole file.
Result<std::string> readFile(const std::string& path);

}  // namespace picksight
