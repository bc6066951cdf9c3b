// The audit trail's files: append, rotate, read back (audit_trail.hpp).
#include "picksight/web/audit_trail.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {

std::string cut(const std::string& text, size_t limit = kMaxFieldBytes) {
  if (text.size() <= limit) return text;
  return text.substr(0, limit) + "...(" + std::to_string(text.size()) + " bytes)";
}

// The JSON with every string cut to kMaxFieldBytes and at most 32 members
// or elements a level: a record stays small whatever a client sent.
nlohmann::json cutJson(const nlohmann::json& value, int depth = 0) {
  if (value.is_string()) return cut(value.get<std::string>());
  if (!value.is_structured()) return value;
  if (depth >= 4) return "...";
  nlohmann::json out = value.is_object() ? nlohmann::json::object() : nlohmann::json::array();
  size_t n = 0;
  for (auto it = value.begin(); it != value.end(); ++it, ++n) {
    if (n == 32) {
      if (value.is_object())
        out["..."] = std::to_string(value.size()) + " members";
      else
        out.push_back(std::to_string(value.size()) + " elements");
      break;
    }
    if (value.is_object())
      out[cut(it.key(), 64)] = cutJson(it.value(), depth + 1);
    else
      out.push_back(cutJson(*it, depth + 1));
  }
  return out;
}

std::string dump(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

bool writeAll(int fd, const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

// Parses one file's lines into `out` (oldest first); notes name the bad ones.
void parseLines(const std::string& name, const std::string& text, std::vector<nlohmann::json>& out,
                std::vector<std::string>& notes) {
  size_t start = 0;
  size_t number = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++number;
    const std::string_view line(text.data() + start, end - start);
    start = end + 1;
    if (line.empty()) continue;
    auto parsed = nlohmann::json::parse(line, nullptr, false);
    if (parsed.is_discarded() || !parsed.is_object()) {
      if (notes.size() < 100)
        notes.push_back(name + " line " + std::to_string(number) +
                        ": not a JSON record, skipped (" + std::to_string(line.size()) + " bytes)");
      continue;
    }
    out.push_back(std::move(parsed));
  }
}

}  // namespace

Result<std::unique_ptr<AuditTrail>> AuditTrail::open(const AuditOptions& options) {
  std::unique_ptr<AuditTrail> trail(new AuditTrail(options));
  if (options.path.empty()) return trail;
  if (options.max_bytes < 2 * kMaxRecordBytes || options.files < 2)
    return makeError(WebErrc::kBadConfig, "audit trail: a file must hold at least " +
                                              std::to_string(2 * kMaxRecordBytes) +
                                              " bytes, and 2 files at least be kept");
  trail->fd_ = ::open(options.path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
  if (trail->fd_ < 0)
    return makeError(WebErrc::kBadConfig,
                     "audit trail " + options.path + ": cannot open: " + std::strerror(errno));
  struct stat info {};
  ::fstat(trail->fd_, &info);
  trail->size_ = static_cast<size_t>(info.st_size);
  if (trail->size_ > 0) {
    // A record cut by a crash: its line is closed, and skipped when read.
    char last = '\n';
    const int in = ::open(options.path.c_str(), O_RDONLY | O_CLOEXEC);
    if (in >= 0) {
      if (::pread(in, &last, 1, info.st_size - 1) != 1) last = '\n';
      ::close(in);
    }
    if (last != '\n' && writeAll(trail->fd_, "\n")) ++trail->size_;
  }
  return trail;
}

AuditTrail::~AuditTrail() {
  if (fd_ >= 0) ::close(fd_);
}

std::string AuditTrail::utcNow() {
  const auto now = std::chrono::system_clock::now();
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count();
  const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  ::gmtime_r(&seconds, &tm);
  char text[64];
  std::snprintf(text, sizeof(text), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(ms % 1000));
  return text;
}

std::string AuditTrail::line(const AuditRecord& r) {
  nlohmann::json j = nlohmann::json::object();
  j["time"] = r.time.empty() ? utcNow() : r.time;
  const auto text = [&](const char* key, const std::string& value, size_t limit) {
    if (!value.empty()) j[key] = cut(value, limit);
  };
  text("user", r.user, 64);
  text("role", r.role, 16);
  text("address", r.address, 64);
  text("action", r.action, 64);
  text("target", r.target, 128);
  if (!r.arguments.is_null()) j["arguments"] = cutJson(r.arguments);
  text("outcome", r.outcome, 16);
  if (r.status != 0) j["status"] = r.status;
  text("reply", r.reply, kMaxFieldBytes);
  if (r.code != 0) j["code"] = r.code;
  if (!r.before.is_null()) j["before"] = cutJson(r.before);
  if (!r.after.is_null()) j["after"] = cutJson(r.after);
  std::string out = dump(j);
  // Still too long (many long fields): the values go, what was done stays.
  for (const char* key : {"before", "after", "arguments", "reply"}) {
    if (out.size() <= kMaxRecordBytes) break;
    if (j.contains(key))
      j[key] = "(cut: the record was over " + std::to_string(kMaxRecordBytes) + " bytes)";
    out = dump(j);
  }
  return out;
}

std::string AuditTrail::fileName(int n) const {
  return n == 0 ? options_.path : options_.path + "." + std::to_string(n);
}

bool AuditTrail::rotate() {
  ::close(fd_);
  fd_ = -1;
  std::error_code ec;
  std::filesystem::remove(fileName(options_.files - 1), ec);
  for (int n = options_.files - 2; n >= 0; --n) {
    if (std::filesystem::exists(fileName(n), ec))
      std::filesystem::rename(fileName(n), fileName(n + 1), ec);
    if (ec) logError("audit trail: cannot rename ", fileName(n), ": ", ec.message());
  }
  fd_ = ::open(options_.path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
  size_ = 0;
  if (fd_ < 0) {
    logError("audit trail ", options_.path, ": cannot open: ", std::strerror(errno));
    return false;
  }
  const auto directory = std::filesystem::path(options_.path).parent_path().string();
  (void)syncDirectory(directory.empty() ? "." : directory);
  return true;
}

void AuditTrail::record(AuditRecord record) {
  if (record.time.empty()) record.time = utcNow();
  const std::string text = line(record);
  logInfo("audit: ", text);
  std::lock_guard<std::mutex> lock(mutex_);
  if (options_.path.empty()) {
    memory_.push_back(text);
    if (memory_.size() > kMemoryRecords) memory_.pop_front();
    return;
  }
  if (fd_ >= 0 && size_ > 0 && size_ + text.size() + 1 > options_.max_bytes) rotate();
  if (fd_ < 0) {
    // A rotation that could not open the new file: tried again here, not
    // rotated again (that would drop one more old file).
    fd_ = ::open(options_.path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
    struct stat info {};
    size_ = fd_ >= 0 && ::fstat(fd_, &info) == 0 ? static_cast<size_t>(info.st_size) : 0;
    if (fd_ < 0) {
      logError("audit trail ", options_.path, ": cannot open: ", std::strerror(errno));
      return;
    }
  }
  // One write of the whole line: a crash cuts at most this record.
  if (!writeAll(fd_, text + "\n")) {
    logError("audit trail ", options_.path, ": cannot write: ", std::strerror(errno));
    return;
  }
  size_ += text.size() + 1;
  ::fdatasync(fd_);
}

AuditRead AuditTrail::newest(size_t limit) const {
  AuditRead out;
  std::lock_guard<std::mutex> lock(mutex_);
  if (options_.path.empty()) {
    for (auto it = memory_.rbegin(); it != memory_.rend() && out.records.size() < limit; ++it)
      out.records.push_back(nlohmann::json::parse(*it));
    return out;
  }
  for (int n = 0; n < options_.files && out.records.size() < limit; ++n) {
    std::error_code ec;
    if (!std::filesystem::exists(fileName(n), ec)) continue;
    auto text = readFile(fileName(n));
    if (!text) {
      out.notes.push_back(text.error().message);
      continue;
    }
    std::vector<nlohmann::json> records;
    parseLines(std::filesystem::path(fileName(n)).filename().string(), *text, records, out.notes);
    for (auto it = records.rbegin(); it != records.rend() && out.records.size() < limit; ++it)
      out.records.push_back(std::move(*it));
  }
  return out;
}

std::string AuditTrail::exportAll() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string out;
  if (options_.path.empty()) {
    for (const auto& text : memory_) out += text + "\n";
    return out;
  }
  for (int n = options_.files - 1; n >= 0; --n) {
    std::error_code ec;
    if (!std::filesystem::exists(fileName(n), ec)) continue;
    if (auto text = readFile(fileName(n))) out += *text;
  }
  return out;
}

}  // namespace picksight::web
