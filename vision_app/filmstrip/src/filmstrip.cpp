// The filmstrip's queue, writer thread, bounds and reads.
#include "picksight/filmstrip/filmstrip.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "picksight/codecs/codecs.hpp"

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"
#include "png_store.hpp"

namespace picksight::filmstrip {
namespace fs = std::filesystem;
namespace {

// "0000000042": names sort as their ids do.
std::string stem(uint64_t id) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010llu", static_cast<unsigned long long>(id));
  return name;
}

// The id of a file name "<10 digits>.<extension>", or 0.
uint64_t idOf(const std::string& name, const std::string& extension) {
  if (name.size() != 10 + 1 + extension.size() || name.compare(11, std::string::npos, extension) ||
      name[10] != '.')
    return 0;
  uint64_t id = 0;
  for (size_t i = 0; i < 10; ++i) {
    if (name[i] < '0' || name[i] > '9') return 0;
    id = id * 10 + static_cast<uint64_t>(name[i] - '0');
  }
  return id;
}

int64_t nowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The entry a request's record describes (everything but id and files).
Entry describe(const Take& take) {
  Entry e;
  e.time_ms = nowMs();
  e.request = take.request;
  e.explains = take.explains;
  if (take.frame) {
    e.camera = take.frame->info.camera;
    e.sequence = take.frame->info.sequence;
    e.mapping = take.frame->mapping;
    e.width = take.frame->image.cols;
    e.height = take.frame->image.rows;
  }
  const results::RequestRecord* r = take.record.get();
  if (!r) return e;
  e.request_line = r->request_line;
  e.reply = r->reply;
  e.client = r->client;
  e.asked_type = r->asked_type;
  e.elapsed_ms = r->elapsed_ms;
  e.failure = take.request == "WHY" || isFailureReply(r->reply);
  // Only a reply with poses has a frame (an ERROR or "OK 0" has none, though
  // the cell's geometry went with the request).
  if (!e.failure) e.reply_frame = r->replyFrame();
  if (take.request == "WHY") e.why = r->reply;
  if (r->locate) {
    const auto& parts = r->locate->parts;
    for (size_t i = 0; i < parts.size(); ++i) {
      const auto& p = parts[i];
      StoredPart s{p.type, p.x, p.y, p.angle_deg, p.score, false};
      s.offered = std::find(r->pick.parts.begin(), r->pick.parts.end(), i) != r->pick.parts.end();
      e.parts.push_back(s);
    }
    e.camera = r->locate->frame.camera;
    e.sequence = r->locate->frame.sequence;
    // Off the robot's path: the regions left out, explained, for a failure.
    if (e.failure && r->request == "LOCATE") e.why = r->why();
  }
  return e;
}

uint64_t fileBytes(const std::string& path) {
  std::error_code ec;
  const auto n = fs::file_size(path, ec);
  return ec ? 0 : static_cast<uint64_t>(n);
}

}  // namespace

struct Filmstrip::Impl {
  explicit Impl(FilmstripOptions o) : options(std::move(o)) {}

  FilmstripOptions options;
  std::vector<std::string> problems;

  mutable std::mutex mutex;  // guards everything below
  std::condition_variable wake;
  std::condition_variable idle;
  struct Job {
    uint64_t id;
    bool failure;  // as far as the request thread can tell (its reply)
    Take take;
  };
  std::deque<Job> queue;
  bool writing = false;
  bool stopping = false;
  uint64_t next_id = 1;
  std::optional<std::chrono::steady_clock::time_point> last_success;
  std::map<uint64_t, Entry> index;  // the entries on disk, oldest first
  FilmstripFigures figures;
  std::thread writer;

  std::string path(const std::string& name) const { return options.dir + "/" + name; }

  void run();
  void write(Job& job);
  void evict();  // call with mutex held
  void remove(const Entry& e);
  void load();
};

void Filmstrip::Impl::load() {
  std::error_code ec;
  std::vector<std::string> sidecars;
  std::vector<uint64_t> images;
  for (const auto& item : fs::directory_iterator(options.dir, ec)) {
    const std::string name = item.path().filename().string();
    if (const uint64_t id = idOf(name, "json")) {
      sidecars.push_back(name);
      next_id = std::max(next_id, id + 1);
    } else if (const uint64_t image = idOf(name, "png")) {
      images.push_back(image);
      next_id = std::max(next_id, image + 1);
    }
  }
  std::sort(sidecars.begin(), sidecars.end());
  for (const auto& name : sidecars) {
    auto text = readFile(path(name));
    auto entry = text ? parseEntryJson(*text) : Result<Entry>(text.error());
    if (entry && entry->id != idOf(name, "json"))
      entry = makeError(FilmstripErrc::kDamaged, "its id is not its name's");
    if (!entry) {
      problems.push_back(path(name) + ": " + entry.error().message + " (skipped, left in place)");
      continue;
    }
    entry->bytes =
        (text ? text->size() : 0) + (entry->image.empty() ? 0 : fileBytes(path(entry->image)));
    index[entry->id] = std::move(*entry);
  }
  // (An image beside a damaged sidecar is reported with the sidecar.)
  for (uint64_t id : images) {
    const bool owned = std::binary_search(sidecars.begin(), sidecars.end(), stem(id) + ".json");
    if (!owned)
      problems.push_back(path(stem(id) + ".png") +
                         ": an image without its sidecar (left in place)");
  }
}

void Filmstrip::Impl::run() {
  // Only on a core nothing else wants: a busy cell's LOCATEs win every
  // time, and the queue, full, drops successes (counted). Nice alone does
  // not do it: a nice 19 thread still takes its share of a busy core.
  sched_param param{};
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param); rc != 0)
    logWarning("filmstrip writer at normal priority: ", std::strerror(rc));
  // Its disk writes too: the idle I/O class (ioprio.h's IOPRIO_CLASS_IDLE,
  // 3, in the top bits) for this thread (who 1: a process or thread id, 0:
  // the caller). glibc has no wrapper.
  constexpr int kWhoProcess = 1;
  constexpr int kIdleClass = 3 << 13;
  if (::syscall(SYS_ioprio_set, kWhoProcess, 0, kIdleClass) != 0)
    logWarning("filmstrip writer at normal I/O priority: ", std::strerror(errno));
  std::unique_lock<std::mutex> lock(mutex);
  for (;;) {
    wake.wait(lock, [&] { return stopping || !queue.empty(); });
    if (queue.empty()) break;  // stopping, everything written
    Job job = std::move(queue.front());
    queue.pop_front();
    writing = true;
    lock.unlock();
    write(job);
    lock.lock();
    writing = false;
    evict();
    if (queue.empty()) idle.notify_all();
  }
  idle.notify_all();
}

void Filmstrip::Impl::write(Job& job) {
  if (options.before_write) options.before_write(job.id);
  Entry e = describe(job.take);
  e.id = job.id;
  const std::string name = stem(e.id);
  uint64_t bytes = 0;
  if (job.take.frame && !job.take.frame->image.empty()) {
    // Stored, not compressed: 1.5 ms at 1920x1080 where deflate at its
    // fastest takes 25 to 70 (png_store.hpp).
    if (const auto png = storedPng(job.take.frame->image)) {
      if (auto ok = writeFileAtomically(path(name + ".png"), *png); ok) {
        e.image = name + ".png";
        bytes += png->size();
      } else {
        logError("filmstrip: ", ok.error().message);
      }
    }
  } else if (e.explains) {
    // A WHY shares the frame of the LOCATE it explains: a second name for
    // the same file, which outlives the LOCATE's entry.
    std::string source;
    {
      std::lock_guard<std::mutex> lock(mutex);
      const auto it = index.find(e.explains);
      if (it != index.end()) {
        source = it->second.image;
        e.camera = it->second.camera;
        e.sequence = it->second.sequence;
        e.mapping = it->second.mapping;
        e.width = it->second.width;
        e.height = it->second.height;
        e.parts = it->second.parts;
        e.asked_type = it->second.asked_type;  // a REPLAY asks what the LOCATE asked
      }
    }
    if (!source.empty() && ::link(path(source).c_str(), path(name + ".png").c_str()) == 0) {
      e.image = name + ".png";
      bytes += fileBytes(path(e.image));
    }
  }
  const std::string json = entryJson(e);
  if (auto ok = writeFileAtomically(path(name + ".json"), json); !ok) {
    logError("filmstrip: ", ok.error().message);
    if (!e.image.empty()) ::unlink(path(e.image).c_str());
    std::lock_guard<std::mutex> lock(mutex);
    ++figures.write_errors;
    return;
  }
  e.bytes = bytes + json.size();
  std::lock_guard<std::mutex> lock(mutex);
  index[e.id] = std::move(e);
  ++figures.recorded;
}

void Filmstrip::Impl::evict() {
  // Each kind within its own bounds, the oldest going first.
  for (const bool failures : {false, true}) {
    const size_t max_count = failures ? options.max_failures : options.max_entries;
    const uint64_t max_bytes = failures ? options.max_failure_bytes : options.max_bytes;
    size_t count = 0;
    uint64_t bytes = 0;
    for (const auto& [id, e] : index) {
      if (e.failure != failures) continue;
      ++count;
      bytes += e.bytes;
    }
    for (auto it = index.begin(); it != index.end() && (count > max_count || bytes > max_bytes);) {
      if (it->second.failure != failures) {
        ++it;
        continue;
      }
      --count;
      bytes -= it->second.bytes;
      remove(it->second);
      ++figures.evicted;
      it = index.erase(it);
    }
  }
}

void Filmstrip::Impl::remove(const Entry& e) {
  // The sidecar first: without it the entry is gone, whatever happens next.
  const std::string name = stem(e.id);
  if (::unlink(path(name + ".json").c_str()) != 0 && errno != ENOENT)
    logError("filmstrip: cannot remove ", path(name + ".json"), ": ", std::strerror(errno));
  if (!e.image.empty()) ::unlink(path(e.image).c_str());
}

Result<std::unique_ptr<Filmstrip>> Filmstrip::open(FilmstripOptions options) {
  if (options.dir.empty()) return makeError(FilmstripErrc::kOff, "no filmstrip directory");
  std::error_code ec;
  fs::create_directories(options.dir, ec);
  if (ec || !fs::is_directory(options.dir))
    return makeError(FilmstripErrc::kStorage,
                     "filmstrip directory " + options.dir + ": " +
                         (ec ? ec.message() : std::string("not a directory")));
  if (auto stale = removeStaleTemporaries(options.dir); !stale) return stale.error();
  options.queue = std::max<size_t>(options.queue, 1);
  auto impl = std::make_unique<Impl>(std::move(options));
  impl->load();
  std::unique_ptr<Filmstrip> strip(new Filmstrip(std::move(impl)));
  {
    // Entries beyond today's bounds (smaller than the last run's) go now.
    std::lock_guard<std::mutex> lock(strip->impl_->mutex);
    strip->impl_->evict();
  }
  Impl* self = strip->impl_.get();
  strip->impl_->writer = std::thread([self] { self->run(); });
  return strip;
}

Filmstrip::Filmstrip(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Filmstrip::~Filmstrip() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  if (impl_->writer.joinable()) impl_->writer.join();
}

uint64_t Filmstrip::reserve() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->next_id++;
}

bool Filmstrip::record(uint64_t id, Take take) {
  const bool failure = take.request == "WHY" || !take.record || isFailureReply(take.record->reply);
  std::unique_lock<std::mutex> lock(impl_->mutex);
  auto& queue = impl_->queue;
  auto& figures = impl_->figures;
  if (!failure) {
    const auto now = std::chrono::steady_clock::now();
    if (impl_->last_success && now - *impl_->last_success < impl_->options.success_interval) {
      ++figures.sampled_out;
      return false;
    }
    impl_->last_success = now;
  }
  if (queue.size() >= impl_->options.queue) {
    // Full: a success makes room for nothing; a failure takes the place
    // of the oldest success waiting, else of the oldest failure.
    if (!failure) {
      ++figures.dropped_successes;
      return false;
    }
    auto success =
        std::find_if(queue.begin(), queue.end(), [](const Impl::Job& j) { return !j.failure; });
    if (success != queue.end()) {
      queue.erase(success);
      ++figures.dropped_successes;
    } else {
      queue.pop_front();
      ++figures.dropped_failures;
    }
  }
  queue.push_back({id, failure, std::move(take)});
  lock.unlock();
  impl_->wake.notify_one();
  return true;
}

void Filmstrip::flush() {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->idle.wait(lock, [&] { return impl_->queue.empty() && !impl_->writing; });
}

std::vector<Entry> Filmstrip::list(size_t max, bool failures_only) const {
  std::vector<Entry> out;
  std::lock_guard<std::mutex> lock(impl_->mutex);
  for (auto it = impl_->index.rbegin(); it != impl_->index.rend() && out.size() < max; ++it) {
    if (failures_only && !it->second.failure) continue;
    out.push_back(it->second);
  }
  return out;
}

Result<Entry> Filmstrip::entry(uint64_t id) const {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    if (!impl_->index.count(id))
      return makeError(FilmstripErrc::kNoEntry,
                       "no filmstrip entry " + std::to_string(id) + " (see FILMSTRIP)");
  }
  const std::string file = impl_->path(stem(id) + ".json");
  auto text = readFile(file);
  if (!text)
    return makeError(FilmstripErrc::kDamaged, file + ": cannot be read: " + text.error().message);
  auto e = parseEntryJson(*text);
  if (!e) return makeError(FilmstripErrc::kDamaged, file + ": " + e.error().message);
  if (e->id != id) return makeError(FilmstripErrc::kDamaged, file + ": its id is not its name's");
  return e;
}

Result<std::pair<Entry, cv::Mat>> Filmstrip::frame(uint64_t id) const {
  auto e = entry(id);
  if (!e) return e.error();
  if (e->image.empty())
    return makeError(FilmstripErrc::kNoFrame, "filmstrip entry " + std::to_string(id) +
                                                  " has no frame (the request failed before one)");
  const std::string file = impl_->path(e->image);
  cv::Mat image = picksight::codecs::imread(file, cv::IMREAD_UNCHANGED);
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    return makeError(FilmstripErrc::kDamaged, file + ": not an 8-bit grey or colour PNG");
  return std::make_pair(std::move(*e), std::move(image));
}

Result<size_t> Filmstrip::exportTo(const std::string& path,
                                   const std::vector<uint64_t>& ids) const {
  std::error_code ec;
  if (fs::exists(path, ec))
    return makeError(FilmstripErrc::kStorage, path + " exists already: name another export");
  fs::create_directories(path + "/.filmstrip", ec);
  if (ec) return makeError(FilmstripErrc::kStorage, path + ": " + ec.message());
  size_t n = 0;
  for (uint64_t id : ids) {
    auto e = entry(id);
    if (!e || e->image.empty()) continue;  // evicted meanwhile, or no frame: nothing to serve
    auto bytes = readFile(impl_->path(e->image));
    if (!bytes) continue;
    char number[16];
    std::snprintf(number, sizeof(number), "%06zu", n + 1);
    if (auto ok = writeFileAtomically(path + "/" + number + ".png", *bytes); !ok)
      return makeError(FilmstripErrc::kStorage, ok.error().message);
    if (auto ok = writeFileAtomically(path + "/.filmstrip/" + number + ".json", entryJson(*e)); !ok)
      return makeError(FilmstripErrc::kStorage, ok.error().message);
    ++n;
  }
  return n;
}

const std::vector<std::string>& Filmstrip::problems() const { return impl_->problems; }

FilmstripFigures Filmstrip::figures() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  FilmstripFigures f = impl_->figures;
  f.entries = impl_->index.size();
  for (const auto& [id, e] : impl_->index) {
    f.failures += e.failure ? 1 : 0;
    f.bytes += e.bytes;
  }
  return f;
}

const FilmstripOptions& Filmstrip::options() const { return impl_->options; }

}  // namespace picksight::filmstrip
