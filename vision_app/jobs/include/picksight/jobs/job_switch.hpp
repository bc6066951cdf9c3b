// JOB SAVE, LOAD, LIST, DELETE, EXPORT and IMPORT for one cell: a job's
// files taken from the cell (models with their grasps and teach images,
// vision settings, calibration, camera settings) and put back in force as
// one switch that no LOCATE sees half of (CellContext::job_switch).
//
// A load checks the whole job first (job_file.hpp, then the vision
// settings and the calibration as their own readers read them) and writes
// its files beside the cell's (<models>.job-staging/, vision.json and
// calibration.yaml with .job-staging): anything wrong and the cell is as
// before. Then, holding the switch alone: the camera settings (put back
// as they were if the camera refuses one), the models directory exchanged
// in one rename, the settings and calibration files renamed over theirs;
// the data directory synced once after. A crash among those renames is
// found at the next start by the marker jobs/switching (naming the job,
// durable before the first rename, removed after the sync): the start
// loads that job again (resume()).
//
// Loaded jobs are kept parsed (at most kParsedJobs, each with the identity
// of its file: device, inode, size, modification time), so that switching
// back to one costs no parsing unless its file changed.
//
// Threading: every member is thread-safe; job requests run one at a time.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "picksight/cell/cell_locate.hpp"
#include "picksight/common/result.hpp"
#include "picksight/jobs/job_file.hpp"
#include "picksight/jobs/job_store.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::jobs {

// The camera features a job keeps, by the names cameras give them (the
// HMI's Camera panel reads the same): the first of each list it has.
const std::vector<std::string>& jobCameraFeatures();

// The number a PLC selects a job by: the digits its name starts with,
// followed by nothing or one of - _ . ("7", "007-brackets", "12_lids": 7,
// 7, 12); nullopt for other names, 0, or past 9999.
std::optional<uint16_t> jobNumber(std::string_view name);

struct JobSummary {
  std::string name;
  size_t models = 0;
  bool calibrated = false;
  bool camera = false;  // camera settings kept or applied
  uint64_t bytes = 0;   // the job file's size
  std::string note;     // e.g. why the camera settings were not kept
};

class JobSwitch {
 public:
  // `cell` and `models` (the cell's, borrowed) outlive the switch; jobs
  // live in `directory` (<data dir>/jobs).
  JobSwitch(std::string directory, cell::CellContext& cell, store::ModelLibrary& models);

  ~JobSwitch();
  JobSwitch(const JobSwitch&) = delete;
  JobSwitch& operator=(const JobSwitch&) = delete;

  static constexpr size_t kParsedJobs = 4;

  // At start: removes what an interrupted switch or write left; one line
  // per problem.
  std::vector<std::string> clean();
  // At start, after the cell's files are loaded: a JOB LOAD a crash
  // interrupted is made again (its name and outcome, for the log);
  // nullopt when none was.
  std::optional<std::string> resume();

  Result<JobSummary> save(const std::string& name);
  Result<JobSummary> load(const std::string& name);
  // JOB LOAD of the one job whose number (jobNumber) is `number`:
  // kNoSuchJob when none or several have it.
  Result<JobSummary> loadNumber(uint16_t number);
  // The number of the job in force (0: none, or its name has none); never
  // waits for a job request (the PLC's registers read it at every poll).
  uint16_t currentNumber() const;
  Result<std::vector<JobEntry>> list() const;
  Result<void> remove(const std::string& name);
  // The job file's text, checked whole (a damaged job is not handed out).
  Result<std::string> exportText(const std::string& name) const;
  // Checks `text` whole and stores it as job `name` (empty: the name inside
  // it); nothing is loaded.
  Result<JobSummary> importText(const std::string& name, std::string_view text);
  // JOB IMPORT over a line protocol: the file's bytes from `offset` on, of
  // `total` in all, kept until the last piece comes, then importText().
  // Pieces come in order (offset 0 starts again; any other offset than the
  // bytes held is kDamaged, and the import is dropped). Nullopt until the
  // last piece.
  Result<std::optional<JobSummary>> importPiece(const std::string& name, size_t offset,
                                                size_t total, std::string_view bytes);
  // Bytes of the job file from `offset` on (at most `limit`) and its size,
  // for JOB EXPORT in pieces; checked whole when `offset` is 0.
  Result<std::pair<std::string, size_t>> exportPiece(const std::string& name, size_t offset,
                                                     size_t limit) const;
  // The job last saved or loaded; nullopt: none, or the cell changed since
  // in ways a job holds is not tracked (the name says what was loaded).
  std::optional<std::string> current() const;

 private:
  // The cell as a job, under the switch's shared hold.
  Result<Job> capture(const std::string& name);
  Result<JobSummary> apply(const Job& job);
  // The job `name` as parsed: from kept_ when its file is the same, else
  // read and checked (store_.read). With mutex_ held.
  Result<std::shared_ptr<const Job>> parsed(const std::string& name);
  // With mutex_ held: waits for the removal of the previous switch's
  // models directory.
  void finishCleaning();
  // The job in force, kept in memory and in jobs/current.
  void setCurrent(const std::optional<std::string>& name);
  // importText() with mutex_ held.
  Result<JobSummary> importLocked(const std::string& name, std::string_view text);

  cell::CellContext& cell_;
  store::ModelLibrary& models_;
  mutable std::mutex mutex_;  // serializes job requests; guards store_
  JobStore store_;
  mutable std::mutex current_mutex_;    // guards current_
  std::optional<std::string> current_;  // as store_.current(), read at clean()
  // The import under way (importPiece); guarded by mutex_.
  struct PendingImport {
    std::string name;
    size_t total = 0;
    std::string bytes;
  };
  std::optional<PendingImport> pending_;
  struct KeptJob {
    std::string name;
    std::string identity;  // of its file when parsed
    std::shared_ptr<const Job> job;
  };
  std::vector<KeptJob> kept_;  // newest last; guarded by mutex_
  // Removes the models directories switches replaced, after the reply.
  std::thread cleaner_;                    // guarded by mutex_
  std::atomic<bool> cleaning_done_{true};  // cleaner_ finished (or none)
  uint64_t removed_ = 0;                   // names replaced directories; guarded by mutex_
};

}  // namespace picksight::jobs
