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
// in one rename, the settings and calibration files renamed over theirs.
//
// Threading: every member is thread-safe; job requests run one at a time.
#pragma once

#include <chrono>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
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

  // At start: removes what an interrupted switch or write left; one line
  // per problem.
  std::vector<std::string> clean();

  Result<JobSummary> save(const std::string& name);
  Result<JobSummary> load(const std::string& name);
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
  // importText() with mutex_ held.
  Result<JobSummary> importLocked(const std::string& name, std::string_view text);

  cell::CellContext& cell_;
  store::ModelLibrary& models_;
  mutable std::mutex mutex_;  // serializes job requests; guards store_
  JobStore store_;
  // The import under way (importPiece); guarded by mutex_.
  struct PendingImport {
    std::string name;
    size_t total = 0;
    std::string bytes;
  };
  std::optional<PendingImport> pending_;
};

}  // namespace picksight::jobs
