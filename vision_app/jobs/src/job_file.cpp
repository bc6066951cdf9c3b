// The job file: JSON with the cell's files inside, each with its SHA-256.
#include "picksight/jobs/job_file.hpp"

#include <openssl/evp.h>

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "picksight/store/model_history.hpp"

namespace picksight::jobs {

const char* errorName(JobErrc e) {
  switch (e) {
    case JobErrc::kNoSuchJob:
      return "no such job";
    case JobErrc::kDamaged:
      return "damaged job";
    case JobErrc::kStorage:
      return "job storage";
    case JobErrc::kTooLarge:
      return "job too large";
    case JobErrc::kBadName:
      return "bad job name";
  }
  return "unknown";
}

namespace {
using nlohmann::json;
using store::sha256Hex;

constexpr const char* kFormat = "picksight-job";
constexpr std::string_view kPngSignature("\x89PNG\r\n\x1a\n", 8);

Error damaged(const std::string& what) { return makeError(JobErrc::kDamaged, what); }

// The fields whose bytes carry their own SHA-256 beside them.
bool isPayload(const std::string& key) {
  return key == "yaml" || key == "teach_png" || key == "vision_json" || key == "calibration_yaml";
}

// The content without its payloads (each stands for itself through its
// checksum): what content_sha256 covers, so that a type number, a count or
// a camera setting cannot be edited either, without hashing the payloads'
// megabytes twice.
json manifestOf(const json& content) {
  if (content.is_object()) {
    json out = json::object();
    for (const auto& [key, value] : content.items()) {
      if (!isPayload(key)) out[key] = manifestOf(value);
    }
    return out;
  }
  if (content.is_array()) {
    json out = json::array();
    for (const auto& value : content) out.push_back(manifestOf(value));
    return out;
  }
  return content;
}

const char* modeName(link::CameraMode mode) {
  switch (mode) {
    case link::CameraMode::kFreeRun:
      return "freerun";
    case link::CameraMode::kSoftwareTrigger:
      return "trigger";
    case link::CameraMode::kHardwareTrigger:
      return "hardware_trigger";
  }
  return "freerun";
}

json cameraToJson(const link::CameraSetup& camera) {
  json j = json::object();
  j["roi"] =
      camera.roi
          ? json::array({camera.roi->x, camera.roi->y, camera.roi->width, camera.roi->height})
          : json(nullptr);
  j["output"] = camera.output ? json{{"width", camera.output->width},
                                     {"height", camera.output->height},
                                     {"pixel_format", camera.output->pixel_format}}
                              : json(nullptr);
  j["mode"] = camera.mode ? json{{"mode", modeName(camera.mode->mode)},
                                 {"fps", camera.mode->fps},
                                 {"line", camera.mode->line},
                                 {"timeout_ms", camera.mode->timeout.count()}}
                          : json(nullptr);
  j["features"] = json::array();
  for (const auto& [name, value] : camera.features) j["features"].push_back({name, value});
  return j;
}

// A whole number field in [low, high].
std::optional<long long> whole(const json& j, const char* key, long long low, long long high) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_integer()) return std::nullopt;
  const auto v = it->get<long long>();
  if (v < low || v > high) return std::nullopt;
  return v;
}

Result<link::CameraSetup> cameraFromJson(const json& j) {
  if (!j.is_object()) return damaged("\"camera\" is not an object");
  link::CameraSetup camera;
  if (const auto roi = j.find("roi"); roi != j.end() && !roi->is_null()) {
    if (!roi->is_array() || roi->size() != 4) return damaged("\"camera.roi\" is not 4 numbers");
    int v[4];
    for (size_t i = 0; i < 4; ++i) {
      if (!(*roi)[i].is_number_integer() || (*roi)[i].get<long long>() < 0 ||
          (*roi)[i].get<long long>() > 65535)
        return damaged("\"camera.roi\" holds a value outside 0..65535");
      v[i] = (*roi)[i].get<int>();
    }
    camera.roi = cv::Rect(v[0], v[1], v[2], v[3]);
  }
  if (const auto out = j.find("output"); out != j.end() && !out->is_null()) {
    const auto w = whole(*out, "width", 0, 65535);
    const auto h = whole(*out, "height", 0, 65535);
    const auto f = out->find("pixel_format");
    if (!w || !h || f == out->end() || !f->is_string() ||
        (f->get<std::string>() != "" && f->get<std::string>() != "mono8" &&
         f->get<std::string>() != "bgr8"))
      return damaged("\"camera.output\" needs width, height (0..65535) and pixel_format");
    camera.output = link::CameraOutput{static_cast<uint32_t>(*w), static_cast<uint32_t>(*h),
                                       f->get<std::string>()};
  }
  if (const auto mode = j.find("mode"); mode != j.end() && !mode->is_null()) {
    link::CameraModeSettings m;
    const auto name = mode->find("mode");
    const auto fps = mode->find("fps");
    const auto line = mode->find("line");
    const auto timeout = whole(*mode, "timeout_ms", 0, 3600000);
    if (name == mode->end() || !name->is_string() || fps == mode->end() || !fps->is_number() ||
        !std::isfinite(fps->get<double>()) || fps->get<double>() < 0 || line == mode->end() ||
        !line->is_string() || line->get<std::string>().size() > 64 || !timeout)
      return damaged("\"camera.mode\" needs mode, fps, line and timeout_ms");
    const std::string n = name->get<std::string>();
    if (n == "freerun") {
      m.mode = link::CameraMode::kFreeRun;
    } else if (n == "trigger") {
      m.mode = link::CameraMode::kSoftwareTrigger;
    } else if (n == "hardware_trigger") {
      m.mode = link::CameraMode::kHardwareTrigger;
    } else {
      return damaged("\"camera.mode\" " + n.substr(0, 40) + " unknown");
    }
    m.fps = fps->get<double>();
    m.line = line->get<std::string>();
    m.timeout = std::chrono::milliseconds(*timeout);
    camera.mode = m;
  }
  const auto features = j.find("features");
  if (features == j.end() || !features->is_array() || features->size() > 64)
    return damaged("\"camera.features\" is not a list of at most 64");
  for (const auto& f : *features) {
    if (!f.is_array() || f.size() != 2 || !f[0].is_string() || !f[1].is_string() ||
        f[0].get<std::string>().empty() || f[0].get<std::string>().size() > 256 ||
        f[1].get<std::string>().size() > 4096)
      return damaged("\"camera.features\" holds an entry that is not [name, value]");
    camera.features.emplace_back(f[0].get<std::string>(), f[1].get<std::string>());
  }
  return camera;
}

// A string field whose SHA-256 is recorded beside it as <key>_sha256.
Result<std::string> checkedText(const json& j, const std::string& key, const std::string& what) {
  const auto it = j.find(key);
  const auto sum = j.find(key + "_sha256");
  if (it == j.end() || !it->is_string()) return damaged(what + " is missing");
  if (sum == j.end() || !sum->is_string()) return damaged(what + " has no checksum");
  std::string text = it->get<std::string>();
  if (sha256Hex(text) != sum->get<std::string>())
    return damaged(what + ": checksum does not match (damaged or edited)");
  return text;
}

Result<JobModel> modelFromJson(const json& m, size_t index) {
  const std::string where = "model entry " + std::to_string(index + 1);
  if (!m.is_object()) return damaged(where + " is not an object");
  const auto type = whole(m, "type", 0, 9999);
  if (!type) return damaged(where + " has no type in 0..9999");
  JobModel model;
  model.type = static_cast<int>(*type);
  const std::string name = "type " + std::to_string(model.type) + "'s";
  auto yaml = checkedText(m, "yaml", name + " model file");
  if (!yaml) return yaml.error();
  model.yaml = std::move(*yaml);
  auto record = store::modelRecordFromYaml(model.yaml);
  if (!record) return damaged(name + " model file does not read: " + record.error().message);
  if (record->model.type != model.type)
    return damaged(name + " model file holds type " + std::to_string(record->model.type));
  model.record = std::move(*record);
  if (const auto png = m.find("teach_png"); png != m.end() && !png->is_null()) {
    auto encoded = checkedText(m, "teach_png", name + " teach image");
    if (!encoded) return encoded.error();
    auto bytes = base64Decode(*encoded);
    if (!bytes) return damaged(name + " teach image is not base64");
    if (bytes->compare(0, kPngSignature.size(), kPngSignature) != 0)
      return damaged(name + " teach image is not a PNG");
    model.teach_png = std::move(*bytes);
  }
  return model;
}
}  // namespace

Result<void> checkJobName(std::string_view name) {
  const auto bad = [&](const std::string& why) {
    return makeError(JobErrc::kBadName, "job name " + why + " (1.." + std::to_string(kMaxJobName) +
                                            " of A-Z a-z 0-9 _ . -, not starting with '.')");
  };
  if (name.empty()) return bad("empty");
  if (name.size() > kMaxJobName) return bad("too long");
  if (name[0] == '.') return bad("starts with '.'");
  for (const char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '.' || c == '-';
    if (!ok) return bad("holds a character outside the set");
  }
  return {};
}

std::string base64Encode(std::string_view bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3), '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                reinterpret_cast<const unsigned char*>(bytes.data()),
                                static_cast<int>(bytes.size()));
  out.resize(static_cast<size_t>(n));
  return out;
}

std::optional<std::string> base64Decode(std::string_view text) {
  if (text.size() % 4 != 0) return std::nullopt;
  std::string out(3 * (text.size() / 4), '\0');
  const int n = EVP_DecodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                reinterpret_cast<const unsigned char*>(text.data()),
                                static_cast<int>(text.size()));
  if (n < 0) return std::nullopt;
  // EVP_DecodeBlock counts the padding as zero bytes.
  size_t size = static_cast<size_t>(n);
  if (!text.empty() && text.back() == '=') --size;
  if (text.size() > 1 && text[text.size() - 2] == '=') --size;
  out.resize(size);
  return out;
}

std::string jobToText(const Job& job) {
  json content = json::object();
  json models = json::array();
  for (const auto& m : job.models) {
    json entry = {{"type", m.type}, {"yaml", m.yaml}, {"yaml_sha256", sha256Hex(m.yaml)}};
    if (m.teach_png) {
      std::string encoded = base64Encode(*m.teach_png);
      entry["teach_png_sha256"] = sha256Hex(encoded);
      entry["teach_png"] = std::move(encoded);
    } else {
      entry["teach_png"] = nullptr;
    }
    models.push_back(std::move(entry));
  }
  content["model_count"] = job.models.size();
  content["models"] = std::move(models);
  content["vision_json"] = job.vision_json;
  content["vision_json_sha256"] = sha256Hex(job.vision_json);
  if (job.calibration_yaml) {
    content["calibration_yaml"] = *job.calibration_yaml;
    content["calibration_yaml_sha256"] = sha256Hex(*job.calibration_yaml);
  } else {
    content["calibration_yaml"] = nullptr;
  }
  content["camera"] = job.camera ? cameraToJson(*job.camera) : json(nullptr);
  json file = {{"format", kFormat}, {"version", kJobFormatVersion}, {"name", job.name}};
  file["content_sha256"] = sha256Hex(manifestOf(content).dump());
  file["content"] = std::move(content);
  return file.dump(1) + "\n";
}

Result<Job> jobFromText(std::string_view text) {
  if (text.size() > kMaxJobBytes)
    return makeError(JobErrc::kTooLarge, "over " + std::to_string(kMaxJobBytes >> 20) + " MiB");
  const json file = json::parse(text.begin(), text.end(), nullptr, false);
  if (file.is_discarded()) return damaged("not JSON (cut short, or not a job file)");
  if (!file.is_object() || file.value("format", "") != kFormat)
    return damaged(std::string("not a job file (format is not \"") + kFormat + "\")");
  if (file.value("version", 0) != kJobFormatVersion)
    return damaged("job format version " + file.value("version", json(0)).dump() +
                   ", this cell reads " + std::to_string(kJobFormatVersion));
  Job job;
  if (!file.contains("name") || !file["name"].is_string()) return damaged("no job name");
  job.name = file["name"].get<std::string>();
  if (auto ok = checkJobName(job.name); !ok) return damaged(ok.error().message);
  const auto content = file.find("content");
  if (content == file.end() || !content->is_object()) return damaged("no content");
  if (!file.contains("content_sha256") || !file["content_sha256"].is_string() ||
      file["content_sha256"].get<std::string>() != sha256Hex(manifestOf(*content).dump()))
    return damaged("content checksum does not match (damaged or edited)");
  const auto models = content->find("models");
  if (models == content->end() || !models->is_array()) return damaged("no model list");
  const auto count = whole(*content, "model_count", 0, static_cast<long long>(kMaxJobModels));
  if (!count) return damaged("no model count in 0.." + std::to_string(kMaxJobModels));
  if (models->size() != static_cast<size_t>(*count))
    return damaged("model missing: " + std::to_string(models->size()) + " of " +
                   std::to_string(*count) + " models");
  std::set<int> types;
  for (size_t i = 0; i < models->size(); ++i) {
    auto model = modelFromJson((*models)[i], i);
    if (!model) return model.error();
    if (!types.insert(model->type).second)
      return damaged("type " + std::to_string(model->type) + " twice");
    job.models.push_back(std::move(*model));
  }
  auto vision = checkedText(*content, "vision_json", "the vision settings");
  if (!vision) return vision.error();
  job.vision_json = std::move(*vision);
  if (const auto cal = content->find("calibration_yaml");
      cal != content->end() && !cal->is_null()) {
    auto yaml = checkedText(*content, "calibration_yaml", "the calibration");
    if (!yaml) return yaml.error();
    job.calibration_yaml = std::move(*yaml);
  }
  if (const auto camera = content->find("camera"); camera != content->end() && !camera->is_null()) {
    auto setup = cameraFromJson(*camera);
    if (!setup) return setup.error();
    job.camera = std::move(*setup);
  }
  return job;
}

}  // namespace picksight::jobs
