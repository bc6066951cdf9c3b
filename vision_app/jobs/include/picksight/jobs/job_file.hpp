// A job as one file: a product's models (with their grasps and teach
// images), vision settings, calibration and camera settings, written as
// JSON with every stored file's bytes inside (images in base64), a
// SHA-256 of each file and one of the rest (types, counts, camera), so that a truncated,
// edited or damaged job is refused by name before anything is changed. The
// same text is kept under <data dir>/jobs/ and moved between cells (export,
// import).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/link/camera_link.hpp"
#include "picksight/store/model_file.hpp"

namespace picksight::jobs {

// Why a job request failed (robot ERROR 50-54, docs/PROTOCOL.md).
enum class JobErrc {
  kNoSuchJob = 1,  // no job of that name
  kDamaged,        // the job file is not a whole, sound job (named with what is wrong)
  kStorage,        // the job or the cell's files could not be written
  kTooLarge,       // a bound: the job file's size, the number of jobs or models
  kBadName,        // a name outside [A-Za-z0-9_.-], 1..64 characters, or starting with '.'
};
const char* errorName(JobErrc e);
PICKSIGHT_ERROR_DOMAIN(JobErrc, "job")

constexpr size_t kMaxJobName = 64;
// A job file's size: 16 models with 1024 px teach images are a few MB.
constexpr size_t kMaxJobBytes = size_t{64} << 20;
constexpr size_t kMaxJobs = 256;
constexpr size_t kMaxJobModels = 256;
constexpr int kJobFormatVersion = 1;

// One trained type as its files: the model file's text and its teach image.
struct JobModel {
  int type = -1;
  std::string yaml;                      // type_<n>.yaml, as stored
  std::optional<std::string> teach_png;  // type_<n>.png; none: no teach image
  store::ModelRecord record;             // the model file as read (jobFromText)
};

struct Job {
  std::string name;
  std::vector<JobModel> models;                 // by type, each type once
  std::string vision_json;                      // vision.json's text
  std::optional<std::string> calibration_yaml;  // none: the cell was not calibrated
  std::optional<link::CameraSetup> camera;      // none: the camera has no settings to keep
};

// kBadName unless `name` is 1..kMaxJobName of [A-Za-z0-9_.-], not starting
// with '.' (a file name on every system, never a path).
Result<void> checkJobName(std::string_view name);

// The job file's text.
std::string jobToText(const Job& job);

// Reads a job file's text: kDamaged naming what is wrong (not JSON or cut
// short, another format or version, a checksum that does not match, a
// model missing or of another type than its entry says, a model file that
// does not read, an image that is not PNG), kTooLarge over kMaxJobBytes.
// The job's own name is checked too; the caller may store it under another.
Result<Job> jobFromText(std::string_view text);

// Base64 (RFC 4648, with padding), for images inside the JSON.
std::string base64Encode(std::string_view bytes);
std::optional<std::string> base64Decode(std::string_view text);

}  // namespace picksight::jobs

PICKSIGHT_ERROR_ENUM(picksight::jobs::JobErrc)
