// The filmstrip: the frames of a cell's recent requests (LOCATE, LOCATE
// ALL, WHY, PLC triggers) kept on disk with their replies, so that a
// LOCATE that went wrong can be looked at and replayed through today's
// models. Bounded by count and bytes, with separate (larger) bounds for
// the failures (nothing found, an error, a WHY): a busy cell's successes
// never push out the one frame someone needs to understand.
//
// On disk, in its directory: <id>.png (the frame, lossless, as the vision
// pass saw it) and <id>.json (the sidecar: time, request, reply, camera,
// frame sequence and mapping to sensor pixels, parts found). The sidecar is
// written last, atomically: an entry exists when its sidecar does; a
// damaged sidecar is reported by name and skipped, never a reason to stop.
//
// Never on the robot's critical path: record() only queues (a bounded
// queue; when full, successes are dropped first, and every drop is
// counted); one writer thread encodes, writes and evicts.
//
// Threading: every public method may be called from any thread; the writer
// thread owns the files of entries it writes and evicts; reads take the
// index's lock only to copy from it.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/frame.hpp"
#include "picksight/common/result.hpp"
#include "picksight/results/request_record.hpp"

namespace picksight::filmstrip {

// The filmstrip's failures, as robot ERROR codes 55-59 name them
// (docs/PROTOCOL.md).
enum class FilmstripErrc {
  kNoEntry = 1,  // no entry of that id (never was, or evicted)
  kDamaged,      // its sidecar or image cannot be read
  kOff,          // the app records no filmstrip (--filmstrip-dir none)
  kStorage,      // an export could not be written
  kNoFrame,      // the entry has no frame (a request refused before taking one)
};
const char* errorName(FilmstripErrc e);
PICKSIGHT_ERROR_DOMAIN(FilmstripErrc, "filmstrip")

struct FilmstripOptions {
  std::string dir;  // empty: off
  // Successes: LOCATEs that offered at least one pose.
  size_t max_entries = 200;
  uint64_t max_bytes = 256ull << 20;
  // Failures: nothing found, an error, a WHY (someone asked why).
  size_t max_failures = 1000;
  uint64_t max_failure_bytes = 1024ull << 20;
  // Requests waiting for the writer thread.
  size_t queue = 16;
  // Successes closer than this to the last one kept are not recorded
  // (counted): a cell locating ten times a second would otherwise write
  // 20 MB/s at 1920x1080 for frames nobody looks at, and the disk's work
  // (the kernel's, at normal priority) slows the next LOCATE. Failures are
  // always recorded. 0: every success.
  std::chrono::milliseconds success_interval{1000};
  // Test seam: called on the writer thread before it writes each entry
  // (with that entry's id), so that a test can hold the writer and fill
  // the queue.
  std::function<void(uint64_t id)> before_write;
};

// A part as a LOCATE found it (sensor pixels), for the HMI to mark.
struct StoredPart {
  int type = -1;
  double x = 0;
  double y = 0;
  double angle_deg = 0;
  double score = 0;
  bool offered = false;  // a pose of the reply came from it
};

// One entry, as its sidecar holds it.
struct Entry {
  uint64_t id = 0;
  int64_t time_ms = 0;       // UTC, milliseconds since 1970
  std::string request;       // "LOCATE", "WHY", "PLC"
  std::string request_line;  // as received ("PLC TRIGGER 3" for a PLC)
  std::string reply;
  // The frame of the reply's poses (RequestRecord::replyFrame): "pixels",
  // "vision_mm", "robot_mm", or "" for a reply with no pose frame (and in
  // sidecars written before it was recorded).
  std::string reply_frame;
  std::string client;
  bool failure = false;
  int asked_type = -1;  // -1: every type
  double elapsed_ms = 0;
  std::string camera;
  uint64_t sequence = 0;
  SensorMapping mapping;
  int width = 0;  // the frame's pixels (0: no frame)
  int height = 0;
  std::vector<StoredPart> parts;
  std::string why;        // a failed LOCATE's WHY line, or a WHY's reply
  uint64_t explains = 0;  // a WHY: the LOCATE entry it explains (0: none)
  std::string image;      // the frame's file name ("": no frame)
  uint64_t bytes = 0;     // on disk, sidecar and image
};

// The sidecar's JSON text and back; the parse names what is wrong.
std::string entryJson(const Entry& entry);
Result<Entry> parseEntryJson(const std::string& text);

// Whether a reply means the request failed: an ERROR, or "OK 0".
bool isFailureReply(const std::string& reply);

// What a request hands over: its record (reply filled in) and the frame it
// worked on (may be null). A WHY has no frame of its own: `explains` names
// the entry of the LOCATE it explains, whose image it shares.
struct Take {
  std::shared_ptr<const results::RequestRecord> record;
  std::shared_ptr<const Frame> frame;
  std::string request;  // "LOCATE", "WHY", "PLC"
  uint64_t explains = 0;
};

struct FilmstripFigures {
  uint64_t recorded = 0;           // entries written
  uint64_t dropped_successes = 0;  // dropped by a full queue
  uint64_t dropped_failures = 0;
  uint64_t sampled_out = 0;   // successes within success_interval of the last kept
  uint64_t evicted = 0;       // removed by the bounds
  uint64_t write_errors = 0;  // entries that could not be written
  size_t entries = 0;
  size_t failures = 0;
  uint64_t bytes = 0;
};

class Filmstrip {
 public:
  // Reads the directory's entries (creating it if needed); each damaged
  // sidecar and each image without one is reported in problems(), never
  // removed. Starts the writer thread. An error when the directory cannot
  // be made or listed.
  static Result<std::unique_ptr<Filmstrip>> open(FilmstripOptions options);
  ~Filmstrip();  // writes what is queued, then stops
  Filmstrip(const Filmstrip&) = delete;
  Filmstrip& operator=(const Filmstrip&) = delete;

  // The id the next request's entry will have: taken before its reply is
  // sent (a WHY names the LOCATE it explains by it), recorded after.
  uint64_t reserve();
  // Queues one request under a reserved id; returns at once, false when
  // it was dropped (a full queue).
  bool record(uint64_t id, Take take);
  // Waits until every queued request is written (tests, benchmarks).
  void flush();

  // The newest entries first, at most `max`; with `failures_only`, only
  // failures.
  std::vector<Entry> list(size_t max, bool failures_only = false) const;
  // One entry, read again from its sidecar: kNoEntry, or kDamaged naming
  // the file.
  Result<Entry> entry(uint64_t id) const;
  // Its frame as stored (8-bit grey or BGR), and the entry.
  Result<std::pair<Entry, cv::Mat>> frame(uint64_t id) const;
  // Copies the frames of `ids` (oldest first) into a new directory `path`
  // as <n>.png numbered from 000001, which a video server's dir: camera
  // serves in that order, with the sidecars in its hidden .filmstrip/ (a
  // dir: camera skips hidden files). Refuses an existing path. Returns the
  // number of frames written.
  Result<size_t> exportTo(const std::string& path, const std::vector<uint64_t>& ids) const;

  // What open() found wrong (damaged sidecars, images without one).
  const std::vector<std::string>& problems() const;
  FilmstripFigures figures() const;
  const FilmstripOptions& options() const;

 private:
  struct Impl;
  explicit Filmstrip(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace picksight::filmstrip

PICKSIGHT_ERROR_ENUM(picksight::filmstrip::FilmstripErrc)
