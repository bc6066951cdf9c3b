// Jobs taken from the cell and put back in force as one switch.
#include "picksight/jobs/job_switch.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"

namespace picksight::jobs {
namespace fs = std::filesystem;
namespace {
constexpr const char* kStaging = ".job-staging";
constexpr const char* kSwitchingMarker = "switching";
// Models directories a switch replaced: <models>.job-replaced.<n>.
constexpr const char* kRemoved = ".job-replaced.";

// Removes every models directory a switch replaced beside `models`.
void removeReplaced(const std::string& models) {
  const fs::path path(models);
  const std::string prefix = path.filename().string() + kRemoved;
  std::error_code ec;
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::vector<fs::path> found;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().filename().string().rfind(prefix, 0) == 0) found.push_back(it->path());
  }
  for (const auto& p : found) fs::remove_all(p, ec);
}

// What tells one version of a file from another without reading it: an
// atomic write makes a new inode, an edit in place a new size or time.
std::string fileIdentity(const std::string& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) return {};
  return std::to_string(s.st_dev) + ":" + std::to_string(s.st_ino) + ":" +
         std::to_string(s.st_size) + ":" + std::to_string(s.st_mtim.tv_sec) + "." +
         std::to_string(s.st_mtim.tv_nsec);
}

// One file of a staged job: written, not yet synced (syncStaged() syncs
// them all at once), not renamed (its directory, or its rename over the
// cell's file, makes it count).
Result<void> writeStaged(const std::string& path, std::string_view bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return makeError(JobErrc::kStorage, path + ": " + std::strerror(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      return makeError(JobErrc::kStorage, path + ": " + std::strerror(e));
    }
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) return makeError(JobErrc::kStorage, path + ": " + std::strerror(errno));
  return {};
}

// Every staged file and directory on disk before any is renamed in: one
// syncfs() of the file system they are on. An fsync per file costs a
// journal commit each (on ext4 about 5 ms apiece: 33 files, most of a
// switch); one sync of the file system costs one, whatever else is
// pending on it.
Result<void> syncStaged(const std::string& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return makeError(JobErrc::kStorage, directory + ": " + std::strerror(errno));
  const bool synced = ::syncfs(fd) == 0;
  const int e = errno;
  ::close(fd);
  if (!synced) return makeError(JobErrc::kStorage, directory + ": " + std::strerror(e));
  return {};
}

// Whatever a staged switch left: the files beside the cell's.
struct Staging {
  std::string models;
  std::string vision;
  std::string calibration;
  void remove() const {
    std::error_code ec;
    fs::remove_all(models, ec);
    fs::remove(vision, ec);
    fs::remove(calibration, ec);
  }
};

// The holder of the switch for one load: LOCATEs wait until it goes.
class Switching {
 public:
  explicit Switching(cell::JobSwitchGate& gate) : gate_(gate) { gate_.lock(); }
  ~Switching() { gate_.unlock(); }
  Switching(const Switching&) = delete;
  Switching& operator=(const Switching&) = delete;

 private:
  cell::JobSwitchGate& gate_;
};
}  // namespace

std::optional<uint16_t> jobNumber(std::string_view name) {
  size_t digits = 0;
  while (digits < name.size() && name[digits] >= '0' && name[digits] <= '9') ++digits;
  if (digits == 0) return std::nullopt;
  if (digits < name.size() && name[digits] != '-' && name[digits] != '_' && name[digits] != '.')
    return std::nullopt;
  unsigned value = 0;
  for (size_t i = 0; i < digits; ++i) {
    value = value * 10 + static_cast<unsigned>(name[i] - '0');
    if (value > 9999) return std::nullopt;
  }
  if (value == 0) return std::nullopt;
  return static_cast<uint16_t>(value);
}

const std::vector<std::string>& jobCameraFeatures() {
  static const std::vector<std::string> names = {
      "ExposureTime", "ExposureTimeAbs", "exposure_time_absolute", "Gain", "GainRaw", "gain"};
  return names;
}

JobSwitch::JobSwitch(std::string directory, cell::CellContext& cell, store::ModelLibrary& models)
    : cell_(cell), models_(models), store_(std::move(directory)) {}

JobSwitch::~JobSwitch() {
  std::lock_guard<std::mutex> lock(mutex_);
  finishCleaning();
}

void JobSwitch::finishCleaning() {
  if (cleaner_.joinable()) cleaner_.join();
}

std::vector<std::string> JobSwitch::clean() {
  std::lock_guard<std::mutex> lock(mutex_);
  finishCleaning();
  Staging{models_.directory() + kStaging, cell_.vision.settingsPath() + kStaging,
          cell_.calibration.path() + kStaging}
      .remove();
  removeReplaced(models_.directory());
  {
    std::lock_guard<std::mutex> current(current_mutex_);
    current_ = store_.current();
  }
  return store_.clean();
}

std::optional<std::string> JobSwitch::resume() {
  const std::string marker = store_.directory() + "/" + kSwitchingMarker;
  auto text = readFile(marker);
  if (!text) return std::nullopt;
  std::string name = *text;
  while (!name.empty() && name.back() == '\n') name.pop_back();
  auto loaded = load(name);
  if (loaded) return "JOB LOAD " + name + " was interrupted (a crash or a stop): loaded again";
  // Whatever the files are now, they are not the job: say so, once.
  std::error_code ec;
  fs::remove(marker, ec);
  return "JOB LOAD " + name.substr(0, kMaxJobName) + " was interrupted and cannot be made again (" +
         loaded.error().message + "): the cell's files may mix two jobs; load a job";
}

Result<std::shared_ptr<const Job>> JobSwitch::parsed(const std::string& name) {
  const std::string identity = fileIdentity(store_.pathOf(name));
  for (const auto& k : kept_) {
    if (k.name == name && !identity.empty() && k.identity == identity) return k.job;
  }
  auto job = store_.read(name);
  if (!job) return job.error();
  job->name = name;
  auto shared = std::make_shared<const Job>(std::move(*job));
  kept_.erase(
      std::remove_if(kept_.begin(), kept_.end(), [&](const KeptJob& k) { return k.name == name; }),
      kept_.end());
  if (kept_.size() >= kParsedJobs) kept_.erase(kept_.begin());
  // The identity read before the file: a change since shows as another.
  if (!identity.empty()) kept_.push_back({name, identity, shared});
  return shared;
}

Result<Job> JobSwitch::capture(const std::string& name) {
  const cell::OneJob one_job(cell_.job_switch);
  Job job;
  job.name = name;
  auto files = models_.files();
  if (!files) return files.error();
  for (auto& f : *files) {
    JobModel m;
    m.type = f.type;
    m.yaml = std::move(f.yaml);
    m.teach_png = std::move(f.teach_png);
    job.models.push_back(std::move(m));
  }
  if (auto damage = cell_.vision.settingsDamage())
    return makeError(cell::VisionSettingsErrc::kDamaged,
                     "the vision settings file is damaged (" + damage->substr(0, 200) + ")");
  job.vision_json = cell::visionSettingsJson(cell_.vision.options());
  auto calibration = cell_.calibration.fileText();
  if (!calibration) return calibration.error();
  job.calibration_yaml = std::move(*calibration);
  return job;
}

Result<JobSummary> JobSwitch::save(const std::string& name) {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto job = capture(name);
  if (!job) return job.error();
  JobSummary summary;
  // The camera's settings are read between requests, outside the switch's
  // hold: a slow camera never delays a LOCATE more than a request would.
  auto camera = cell_.vision.withCamera(
      [](link::CameraLink& link) { return link.setup(jobCameraFeatures()); });
  if (camera) {
    job->camera = std::move(*camera);
  } else {
    summary.note = "camera settings not kept: " + camera.error().message;
  }
  const std::string text = jobToText(*job);
  if (text.size() > kMaxJobBytes)
    return makeError(JobErrc::kTooLarge, "job " + name + " would be over " +
                                             std::to_string(kMaxJobBytes >> 20) + " MiB");
  if (auto ok = store_.write(name, text); !ok) return ok.error();
  setCurrent(name);
  summary.name = name;
  summary.models = job->models.size();
  summary.calibrated = job->calibration_yaml.has_value();
  summary.camera = job->camera.has_value();
  summary.bytes = text.size();
  return summary;
}

Result<JobSummary> JobSwitch::load(const std::string& name) {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto job = parsed(name);
  if (!job) return job.error();
  auto loaded = apply(**job);
  if (!loaded) {
    // Which file, for a refusal that is the job's fault.
    if (loaded.error().code == JobErrc::kDamaged)
      return makeError(JobErrc::kDamaged, store_.pathOf(name) + ": " + loaded.error().message);
    return loaded;
  }
  setCurrent(name);
  return loaded;
}

Result<JobSummary> JobSwitch::apply(const Job& job) {
  // Every check before any change: the settings and the calibration as
  // their own readers read them.
  auto options = cell::parseVisionSettingsJson(job.vision_json, cell_.vision.options());
  if (!options)
    return makeError(JobErrc::kDamaged, "its vision settings: " + options.error().message);
  const Staging staging{models_.directory() + kStaging, cell_.vision.settingsPath() + kStaging,
                        cell_.calibration.path() + kStaging};
  staging.remove();
  const std::string marker = store_.directory() + "/" + kSwitchingMarker;
  const auto fail = [&](const Error& e) -> Error {
    staging.remove();
    std::error_code ignored;
    fs::remove(marker, ignored);
    return e;
  };
  std::error_code ec;
  fs::create_directories(staging.models, ec);
  if (ec) return fail(makeError(JobErrc::kStorage, staging.models + ": " + ec.message()));
  store::ModelList models;
  store::GraspMap grasps;
  for (const auto& m : job.models) {
    const std::string base = staging.models + "/type_" + std::to_string(m.type);
    if (auto ok = writeStaged(base + ".yaml", m.yaml); !ok) return fail(ok.error());
    if (m.teach_png) {
      if (auto ok = writeStaged(base + ".png", *m.teach_png); !ok) return fail(ok.error());
    }
    models.push_back(m.record.model);
    grasps[m.type] = m.record.grasp;
  }

  if (!cell_.vision.settingsPath().empty()) {
    if (auto ok = writeStaged(staging.vision, job.vision_json); !ok) return fail(ok.error());
  }
  if (job.calibration_yaml) {
    if (auto ok = writeStaged(staging.calibration, *job.calibration_yaml); !ok)
      return fail(ok.error());
    if (auto ok = store::CellCalibration::check(staging.calibration); !ok)
      return fail(makeError(JobErrc::kDamaged, "its calibration: " + ok.error().message));
  }
  // The marker is on disk with the staged files, before the first rename.
  fs::create_directories(store_.directory(), ec);
  if (auto ok = writeStaged(marker, job.name + "\n"); !ok) return fail(ok.error());
  if (auto ok = syncStaged(staging.models); !ok) return fail(ok.error());

  {
    const Switching alone(cell_.job_switch);
    if (job.camera) {
      auto applied = cell_.vision.withCamera([&](link::CameraLink& link) -> Result<void> {
        auto before = link.setup(jobCameraFeatures());
        if (!before) return before.error();
        if (auto ok = link.applySetup(*job.camera); !ok) {
          // Put back what was read: the job is refused whole.
          if (auto back = link.applySetup(*before); !back)
            logError("JOB LOAD: the camera's settings were not all put back: ",
                     back.error().message);
          return ok;
        }
        return {};
      });
      if (!applied)
        return fail(Error{applied.error().code,
                          "the camera refused the job's settings: " + applied.error().message});
    }
    if (auto ok = models_.adoptDirectory(staging.models, std::move(models), std::move(grasps)); !ok)
      return fail(ok.error());
    // Renames of files already checked and synced: past the models, what
    // could fail here is the disk itself, reported as such.
    if (auto ok = cell_.vision.adoptSettings(*options, staging.vision); !ok)
      return fail(ok.error());
    if (auto ok = cell_.calibration.adopt(
            job.calibration_yaml ? std::optional<std::string>(staging.calibration) : std::nullopt);
        !ok)
      return fail(ok.error());
  }
  // One sync for the three renames (their directories: the data directory
  // in a VisionCell), then the marker goes.
  std::set<std::string> directories;
  for (const auto& path :
       {models_.directory(), cell_.vision.settingsPath(), cell_.calibration.path()}) {
    if (path.empty()) continue;
    const std::string parent = fs::path(path).parent_path().string();
    directories.insert(parent.empty() ? "." : parent);
  }
  for (const auto& directory : directories) {
    if (auto ok = syncDirectory(directory); !ok)
      logWarning("JOB LOAD ", job.name, ": ", ok.error().message);
  }
  fs::remove(marker, ec);
  // The previous models directory, exchanged into the staging path, goes
  // after the reply: removing a few MB of files is no part of the switch
  // (on ext4 it can take longer than the switch). Renamed out of the next
  // switch's way, it is removed by the cleaner, with any a busy cleaner
  // left before.
  const std::string old = models_.directory() + kRemoved + std::to_string(++removed_);
  fs::rename(staging.models, old, ec);
  if (ec) {
    staging.remove();
  } else if (cleaning_done_) {
    finishCleaning();
    cleaning_done_ = false;
    cleaner_ = std::thread([this, models = models_.directory()] {
      removeReplaced(models);
      cleaning_done_ = true;
    });
  }
  JobSummary summary;
  summary.name = job.name;
  summary.models = job.models.size();
  summary.calibrated = job.calibration_yaml.has_value();
  summary.camera = job.camera.has_value();
  return summary;
}

Result<std::vector<JobEntry>> JobSwitch::list() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return store_.list();
}

Result<void> JobSwitch::remove(const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto ok = store_.remove(name); !ok) return ok;
  if (current() == name) setCurrent(std::nullopt);
  return {};
}

Result<std::string> JobSwitch::exportText(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto text = store_.readText(name);
  if (!text) return text;
  if (auto job = jobFromText(*text); !job)
    return Error{job.error().code, store_.pathOf(name) + ": " + job.error().message};
  return text;
}

Result<JobSummary> JobSwitch::importText(const std::string& name, std::string_view text) {
  std::lock_guard<std::mutex> lock(mutex_);
  return importLocked(name, text);
}

Result<std::optional<JobSummary>> JobSwitch::importPiece(const std::string& name, size_t offset,
                                                         size_t total, std::string_view bytes) {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  if (total > kMaxJobBytes)
    return makeError(JobErrc::kTooLarge,
                     "a job file is at most " + std::to_string(kMaxJobBytes >> 20) + " MiB");
  std::lock_guard<std::mutex> lock(mutex_);
  if (offset == 0) pending_ = PendingImport{name, total, {}};
  if (!pending_ || pending_->name != name || pending_->total != total ||
      pending_->bytes.size() != offset || offset + bytes.size() > total) {
    pending_.reset();
    return makeError(JobErrc::kDamaged, "import of " + name + ": piece at " +
                                            std::to_string(offset) +
                                            " out of order (start again at 0)");
  }
  pending_->bytes.append(bytes);
  if (pending_->bytes.size() < total) return std::optional<JobSummary>();
  const std::string text = std::move(pending_->bytes);
  pending_.reset();
  auto imported = importLocked(name, text);
  if (!imported) return imported.error();
  return std::optional<JobSummary>(std::move(*imported));
}

Result<std::pair<std::string, size_t>> JobSwitch::exportPiece(const std::string& name,
                                                              size_t offset, size_t limit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto text = store_.readText(name);
  if (!text) return text.error();
  if (offset == 0) {
    if (auto job = jobFromText(*text); !job)
      return Error{job.error().code, store_.pathOf(name) + ": " + job.error().message};
  }
  if (offset > text->size())
    return makeError(JobErrc::kNoSuchJob,
                     "job " + name + " has " + std::to_string(text->size()) + " bytes");
  return std::make_pair(text->substr(offset, limit), text->size());
}

Result<JobSummary> JobSwitch::importLocked(const std::string& name, std::string_view text) {
  auto job = jobFromText(text);
  if (!job) return job.error();
  const std::string stored = name.empty() ? job->name : name;
  if (auto ok = checkJobName(stored); !ok) return ok.error();
  if (auto ok = store_.write(stored, std::string(text)); !ok) return ok.error();
  JobSummary summary;
  summary.name = stored;
  summary.models = job->models.size();
  summary.calibrated = job->calibration_yaml.has_value();
  summary.camera = job->camera.has_value();
  summary.bytes = text.size();
  return summary;
}

std::optional<std::string> JobSwitch::current() const {
  std::lock_guard<std::mutex> lock(current_mutex_);
  return current_;
}

void JobSwitch::setCurrent(const std::optional<std::string>& name) {
  store_.setCurrent(name);
  std::lock_guard<std::mutex> lock(current_mutex_);
  current_ = name;
}

uint16_t JobSwitch::currentNumber() const {
  const auto name = current();
  return name ? jobNumber(*name).value_or(0) : 0;
}

Result<JobSummary> JobSwitch::loadNumber(uint16_t number) {
  auto jobs = list();
  if (!jobs) return jobs.error();
  std::vector<std::string> named;
  for (const auto& entry : *jobs) {
    if (jobNumber(entry.name) == number) named.push_back(entry.name);
  }
  if (named.empty())
    return makeError(JobErrc::kNoSuchJob, "no job numbered " + std::to_string(number) +
                                              " (a job's number starts its name: " +
                                              std::to_string(number) + "-<name>)");
  if (named.size() > 1)
    return makeError(JobErrc::kNoSuchJob, "jobs " + named[0] + " and " + named[1] +
                                              " both have number " + std::to_string(number));
  return load(named[0]);
}

}  // namespace picksight::jobs
