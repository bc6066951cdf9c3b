// The cell's jobs on disk: one job file (job_file.hpp) per job,
// <data dir>/jobs/<name>.job, each written atomically; which job was last
// loaded or saved is kept in <data dir>/jobs/current.
//
// Threading: not thread-safe; JobSwitch serializes its use.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/jobs/job_file.hpp"

namespace picksight::jobs {

struct JobEntry {
  std::string name;
  uint64_t bytes = 0;
};

class JobStore {
 public:
  explicit JobStore(std::string directory);

  // Removes temporaries of interrupted writes; call once at start.
  std::vector<std::string> clean();
  // Every job, by name; a file whose name is no job name is left out.
  Result<std::vector<JobEntry>> list() const;
  // The job file's text: kNoSuchJob, or kTooLarge / storage errors.
  Result<std::string> readText(const std::string& name) const;
  // The job itself: as readText, then kDamaged naming the file and what is
  // wrong with it.
  Result<Job> read(const std::string& name) const;
  // Writes `text` as job `name` atomically; kTooLarge past kMaxJobs jobs
  // (replacing one is always allowed).
  Result<void> write(const std::string& name, const std::string& text);
  Result<void> remove(const std::string& name);

  // The job last loaded or saved (nullopt: none yet, or it was deleted).
  std::optional<std::string> current() const;
  void setCurrent(const std::optional<std::string>& name);

  std::string pathOf(const std::string& name) const;
  const std::string& directory() const { return directory_; }

 private:
  const std::string directory_;
};

}  // namespace picksight::jobs
