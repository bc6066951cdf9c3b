// Job files under <data dir>/jobs/.
#include "picksight/jobs/job_store.hpp"

#include <algorithm>
#include <filesystem>

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"

namespace picksight::jobs {
namespace fs = std::filesystem;
namespace {
constexpr const char* kExtension = ".job";
constexpr const char* kCurrentFile = "current";
}  // namespace

JobStore::JobStore(std::string directory) : directory_(std::move(directory)) {}

std::string JobStore::pathOf(const std::string& name) const {
  return directory_ + "/" + name + kExtension;
}

std::vector<std::string> JobStore::clean() {
  std::vector<std::string> problems;
  if (auto removed = removeStaleTemporaries(directory_); !removed) {
    problems.push_back(removed.error().message);
  } else {
    for (const auto& name : *removed)
      logInfo(directory_, ": removed ", name, " (left by an interrupted write)");
  }
  return problems;
}

Result<std::vector<JobEntry>> JobStore::list() const {
  std::vector<JobEntry> jobs;
  std::error_code ec;
  if (!fs::exists(directory_, ec)) return jobs;
  for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& path = it->path();
    if (path.extension() != kExtension || !it->is_regular_file()) continue;
    const std::string name = path.stem().string();
    if (!checkJobName(name)) continue;
    std::error_code size_ec;
    const auto bytes = fs::file_size(path, size_ec);
    jobs.push_back({name, size_ec ? 0 : static_cast<uint64_t>(bytes)});
  }
  if (ec) return makeError(JobErrc::kStorage, directory_ + ": " + ec.message());
  std::sort(jobs.begin(), jobs.end(),
            [](const JobEntry& a, const JobEntry& b) { return a.name < b.name; });
  return jobs;
}

Result<std::string> JobStore::readText(const std::string& name) const {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  const std::string path = pathOf(name);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return makeError(JobErrc::kNoSuchJob, "no job " + name);
  const auto bytes = fs::file_size(path, ec);
  if (!ec && bytes > kMaxJobBytes)
    return makeError(JobErrc::kTooLarge,
                     path + ": over " + std::to_string(kMaxJobBytes >> 20) + " MiB");
  auto text = readFile(path);
  if (!text) return makeError(JobErrc::kStorage, text.error().message);
  return text;
}

Result<Job> JobStore::read(const std::string& name) const {
  auto text = readText(name);
  if (!text) return text.error();
  auto job = jobFromText(*text);
  if (!job) return Error{job.error().code, pathOf(name) + ": " + job.error().message};
  return job;
}

Result<void> JobStore::write(const std::string& name, const std::string& text) {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  std::error_code ec;
  const bool created = fs::create_directories(directory_, ec);
  if (ec) return makeError(JobErrc::kStorage, directory_ + ": " + ec.message());
  if (created) (void)syncDirectory(fs::absolute(directory_, ec).parent_path().string());
  if (!fs::exists(pathOf(name), ec)) {
    auto jobs = list();
    if (!jobs) return jobs.error();
    if (jobs->size() >= kMaxJobs)
      return makeError(JobErrc::kTooLarge,
                       std::to_string(kMaxJobs) + " jobs are stored already: JOB DELETE one first");
  }
  if (auto written = writeFileAtomically(pathOf(name), text); !written)
    return makeError(JobErrc::kStorage, written.error().message);
  return {};
}

Result<void> JobStore::remove(const std::string& name) {
  if (auto ok = checkJobName(name); !ok) return ok.error();
  std::error_code ec;
  if (!fs::remove(pathOf(name), ec)) {
    if (ec) return makeError(JobErrc::kStorage, pathOf(name) + ": " + ec.message());
    return makeError(JobErrc::kNoSuchJob, "no job " + name);
  }
  (void)syncDirectory(directory_);
  return {};
}

std::optional<std::string> JobStore::current() const {
  auto text = readFile(directory_ + "/" + kCurrentFile);
  if (!text) return std::nullopt;
  std::string name = *text;
  while (!name.empty() && (name.back() == '\n' || name.back() == '\r')) name.pop_back();
  if (!checkJobName(name)) return std::nullopt;
  return name;
}

void JobStore::setCurrent(const std::optional<std::string>& name) {
  const std::string path = directory_ + "/" + kCurrentFile;
  std::error_code ec;
  if (!name) {
    fs::remove(path, ec);
    return;
  }
  fs::create_directories(directory_, ec);
  // Only what the HMI and STATUS show: a lost write costs a name, not a job.
  if (auto ok = writeFileAtomically(path, *name + "\n"); !ok)
    logWarning(path, ": ", ok.error().message);
}

}  // namespace picksight::jobs
