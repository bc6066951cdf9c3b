// The web HMI's audit trail (docs/WEB.md#audit-trail): every change made
// through the page (set-up lines to the vision apps, camera settings, users)
// and every login, as one JSON object per line in a bounded set of rotated
// files, each record also written to the log (stderr: the journal under
// systemd).
//
// Bounds: a record is at most kMaxRecordBytes (longer fields are cut and
// say so); a file at most max_bytes: the record that would pass the cap
// starts a new file, "FILE" becomes "FILE.1", "FILE.1" "FILE.2"..., and
// the oldest beyond `files` (the current one included) is deleted, so the
// trail never holds more than max_bytes x files. Without a path the newest
// kMemoryRecords records are kept in memory only.
//
// Durability: each record is one write(2) to a file opened O_APPEND and
// then fdatasync'd: a crash loses at most the record being written, and a
// line cut by one is skipped with a note when read (as is any line that is
// not a JSON object), never fatal.
//
// Threading: every member may be called from any thread (one mutex).
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "picksight/common/result.hpp"

namespace picksight::web {

constexpr size_t kMaxRecordBytes = 2048;
constexpr size_t kMemoryRecords = 1000;
// The longest text kept of one field (a reply, an argument, a value).
constexpr size_t kMaxFieldBytes = 256;

struct AuditOptions {
  std::string path;  // empty: memory only
  size_t max_bytes = 1 << 20;
  int files = 5;  // the current file and files - 1 rotated ones
};

// One change or login. Empty strings and null JSON are left out of the
// line; `time` is filled in (UTC, ISO 8601 with milliseconds) when empty.
struct AuditRecord {
  std::string time;
  std::string user;
  std::string role;
  std::string address;  // the client's
  std::string action;   // "command", "camera.roi", "user.set", "login"...
  std::string target;   // the vision app or camera, the user changed
  nlohmann::json arguments;
  std::string outcome;  // "ok", "error" (the cell refused the value), "refused" (the role)
  int status = 0;       // the HTTP status the page got
  std::string reply;    // the reply line or the message
  int code = 0;         // a robot reply's ERROR number
  nlohmann::json before;
  nlohmann::json after;
};

// The newest records (newest first) and what could not be read.
struct AuditRead {
  std::vector<nlohmann::json> records;
  std::vector<std::string> notes;
};

class AuditTrail {
 public:
  // Opens (or creates) options.path for appending; errors name the file. A
  // last line cut by a crash is closed with a newline first, so the next
  // record starts a line of its own.
  static Result<std::unique_ptr<AuditTrail>> open(const AuditOptions& options);

  // Writes the record (and logs it). A failed write is logged, never thrown.
  void record(AuditRecord record);
  // Up to `limit` newest records, newest first.
  AuditRead newest(size_t limit) const;
  // Every file's bytes, oldest first, as stored (for the export).
  std::string exportAll() const;
  const AuditOptions& options() const { return options_; }

  // The JSON line of a record (without the newline), at most kMaxRecordBytes.
  static std::string line(const AuditRecord& record);
  // Now as "2026-12-02T07:40:00.123Z".
  static std::string utcNow();

  ~AuditTrail();
  AuditTrail(const AuditTrail&) = delete;
  AuditTrail& operator=(const AuditTrail&) = delete;

 private:
  explicit AuditTrail(AuditOptions options) : options_(std::move(options)) {}
  // The file of rotation `n` (0: the current one).
  std::string fileName(int n) const;
  // Closes the current file, shifts the rotated ones, opens a new one.
  bool rotate();  // under mutex_

  const AuditOptions options_;
  mutable std::mutex mutex_;
  int fd_ = -1;                     // under mutex_
  size_t size_ = 0;                 // under mutex_: bytes of the current file
  std::deque<std::string> memory_;  // under mutex_: without a path
};

}  // namespace picksight::web
