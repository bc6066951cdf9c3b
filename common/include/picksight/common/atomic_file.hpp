// Atomic file replacement: a reader (or a restart after a crash mid-write)
// sees either the old content or the new one, never a torn file.
#pragma once

#include <string>

#include "picksight/common/result.hpp"

namespace picksight {

// Writes `content` to a temporary file beside `path`, fsyncs it, renames it
// over `path` and fsyncs the directory.
Result<void> writeFileAtomically(const std::string& path, const std::string& content);

// Reads a whole file.
Result<std::string> readFile(const std::string& path);

}  // namespace picksight
