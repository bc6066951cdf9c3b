// The undo history of the model files.
#include "picksight/store/model_history.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"
#include "picksight/store/model_file.hpp"

namespace picksight::store {
namespace fs = std::filesystem;
namespace {

constexpr std::string_view kMagic = "picksight-model-undo 1";
constexpr std::string_view kEntry = ".undo";
constexpr std::string_view kDamaged = ".undo.damaged";
constexpr size_t kMaxChange = 200;
// A model file is a few kilobytes; a hundred times the largest seen is a
// damaged entry, not a model.
constexpr size_t kMaxEntryBytes = 16u << 20;

// "<10 digits>.undo" (or ".undo.damaged"): its sequence number.
std::optional<uint64_t> sequenceOf(const std::string& name, std::string_view suffix) {
  if (name.size() != 10 + suffix.size() || name.compare(10, std::string::npos, suffix) != 0)
    return std::nullopt;
  uint64_t n = 0;
  for (size_t i = 0; i < 10; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return std::nullopt;
    n = n * 10 + static_cast<uint64_t>(name[i] - '0');
  }
  return n;
}

Error refused(const std::string& path, const std::string& why) {
  return makeError(ModelErrc::kUndoRefused,
                   "undo history entry " + fs::path(path).filename().string() + " " + why);
}

std::string printableChange(std::string_view change) {
  std::string out;
  for (char c : change.substr(0, kMaxChange)) {
    const auto u = static_cast<unsigned char>(c);
    out += u >= 0x20 && u < 0x7f ? c : '?';
  }
  return out;
}
}  // namespace

std::string sha256Hex(std::string_view bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1)
    return {};  // never equal to a recorded digest: the entry is refused
  std::string hex;
  char two[3];
  for (unsigned int i = 0; i < length; ++i) {
    std::snprintf(two, sizeof two, "%02x", digest[i]);
    hex += two;
  }
  return hex;
}

ModelHistory::ModelHistory(std::string directory) : directory_(std::move(directory)) {}

std::vector<std::string> ModelHistory::list(bool damaged) const {
  std::vector<std::pair<uint64_t, std::string>> found;
  std::error_code ec;
  if (!fs::is_directory(directory_, ec)) return {};
  for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (const auto seq = sequenceOf(name, damaged ? kDamaged : kEntry))
      found.emplace_back(*seq, it->path().string());
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> paths;
  for (auto& [seq, path] : found) paths.push_back(std::move(path));
  return paths;
}

Result<std::string> ModelHistory::record(int type, std::string_view change,
                                         const std::optional<std::string>& before,
                                         const std::optional<std::string>& after) {
  std::error_code ec;
  if (fs::create_directories(directory_, ec)) {
    // The new undo/ is an entry of the models directory: durable only once
    // that is synced, or a crash loses the history with it.
    const fs::path parent = fs::absolute(directory_, ec).parent_path();
    if (!ec) (void)syncDirectory(parent.string());
  }
  if (ec) return makeError(ModelErrc::kStorage, directory_ + ": " + ec.message());
  uint64_t next = 1;
  for (bool damaged : {false, true}) {
    for (const auto& path : list(damaged)) {
      const auto seq = sequenceOf(fs::path(path).filename().string(), damaged ? kDamaged : kEntry);
      next = std::max(next, *seq + 1);
    }
  }
  char name[32];
  std::snprintf(name, sizeof name, "%010llu", static_cast<unsigned long long>(next));
  const std::string path = directory_ + "/" + name + std::string(kEntry);
  std::string text = std::string(kMagic) + "\n";
  text += "type " + std::to_string(type) + "\n";
  text += "change " + printableChange(change) + "\n";
  text += before ? "before " + std::to_string(before->size()) + " " + sha256Hex(*before) + "\n"
                 : std::string("before none\n");
  text += "after " + (after ? sha256Hex(*after) : std::string("none")) + "\n";
  text += "end\n";
  if (before) text += *before;
  if (auto written = writeFileAtomically(path, text); !written)
    return makeError(ModelErrc::kStorage, "undo history: " + written.error().message);
  // Bounded: the oldest entries (and set-aside ones) beyond the depth go.
  for (bool damaged : {false, true}) {
    auto paths = list(damaged);
    for (size_t i = 0; i + kUndoDepth < paths.size(); ++i) {
      fs::remove(paths[i], ec);
      fs::remove(teachImageBeside(paths[i]), ec);
    }
  }
  return path;
}

std::string teachImageBeside(const std::string& entry_path) { return entry_path + ".png"; }

void ModelHistory::drop(const std::string& path) {
  std::error_code ec;
  fs::remove(path, ec);
  fs::remove(teachImageBeside(path), ec);
  (void)syncDirectory(directory_);
}

std::string ModelHistory::setAside(const std::string& path) {
  const std::string aside = path + ".damaged";
  std::error_code ec;
  fs::remove(teachImageBeside(path), ec);  // an image is only put back with its entry
  fs::rename(path, aside, ec);
  if (ec) fs::remove(path, ec);  // out of UNDO's way at least
  (void)syncDirectory(directory_);
  return aside;
}

std::optional<std::string> ModelHistory::newest() const {
  auto paths = list(false);
  if (paths.empty()) return std::nullopt;
  return paths.back();
}

size_t ModelHistory::size() const { return list(false).size(); }

Result<UndoEntry> ModelHistory::read(const std::string& path) {
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  if (ec) return refused(path, "cannot be read: " + ec.message());
  if (bytes > kMaxEntryBytes) return refused(path, "is larger than any model file");
  auto text = readFile(path);
  if (!text) return refused(path, "cannot be read: " + text.error().message);
  // Six header lines, then the old file's bytes.
  std::vector<std::string> lines;
  size_t at = 0;
  while (lines.size() < 6) {
    const size_t eol = text->find('\n', at);
    if (eol == std::string::npos) return refused(path, "is damaged: its header is cut short");
    lines.push_back(text->substr(at, eol - at));
    at = eol + 1;
  }
  const auto field = [&](size_t i, std::string_view key) -> std::optional<std::string> {
    if (lines[i].rfind(std::string(key) + " ", 0) != 0) return std::nullopt;
    return lines[i].substr(key.size() + 1);
  };
  if (lines[0] != kMagic) return refused(path, "is damaged: not an undo entry");
  UndoEntry entry;
  const auto type = field(1, "type");
  long long type_number = -1;  // a plain number: GCC's flow analysis misreads an optional here
  if (type) type_number = parseInt(*type).value_or(-1);
  const auto change = field(2, "change");
  const auto before = field(3, "before");
  const auto after = field(4, "after");
  if (type_number < 0 || type_number > 9999 || !change || !before || !after || lines[5] != "end")
    return refused(path, "is damaged: its header does not read");
  entry.type = static_cast<int>(type_number);
  entry.change = *change;
  entry.after_sha256 = *after == "none" ? "" : *after;
  const std::string body = text->substr(at);
  if (*before == "none") {
    if (!body.empty()) return refused(path, "is damaged: bytes after an empty 'before'");
    return entry;
  }
  const auto words = splitFields(*before, " ");
  const auto size = words.size() == 2 ? parseInt(words[0]) : std::nullopt;
  if (!size || *size < 0) return refused(path, "is damaged: its header does not read");
  if (static_cast<size_t>(*size) != body.size())
    return refused(path, "is damaged: " + std::to_string(body.size()) + " bytes of the old file, " +
                             std::to_string(*size) + " recorded");
  if (sha256Hex(body) != words[1])
    return refused(path, "is damaged: the old file's bytes do not match their SHA-256");
  entry.before = body;
  return entry;
}

std::vector<std::string> ModelHistory::check() const {
  std::vector<std::string> problems;
  for (const auto& path : list(false)) {
    if (auto entry = read(path); !entry)
      problems.push_back(entry.error().message + " (UNDO will refuse it)");
  }
  return problems;
}

}  // namespace picksight::store
