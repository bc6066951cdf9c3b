// A file's whole text read or written in one call, for tests that look at
// or damage what a service stored.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace picksight::test {

// The bytes of the file at `path` (empty when it cannot be read).
inline std::string readFileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Replaces the file at `path` with `text`; throws when it cannot.
inline void writeFileText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out.good()) throw std::runtime_error("cannot write " + path);
}

}  // namespace picksight::test
