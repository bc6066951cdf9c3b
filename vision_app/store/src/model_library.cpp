// Model library on disk.
#include "picksight/store/model_library.hpp"

#include <fcntl.h>
#include <linux/fs.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <utility>

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"
#include "picksight/store/model_file.hpp"

namespace picksight::store {
namespace fs = std::filesystem;

ModelLibrary::ModelLibrary(std::string directory)
    : directory_(std::move(directory)),
      history_(directory_ + "/undo"),
      models_(std::make_shared<const ModelList>()),
      grasps_(std::make_shared<const GraspMap>()) {}

std::string ModelLibrary::pathOf(int type) const {
  return directory_ + "/type_" + std::to_string(type) + ".yaml";
}

std::string ModelLibrary::teachImagePathOf(int type) const {
  return directory_ + "/type_" + std::to_string(type) + ".png";
}

Result<void> ModelLibrary::keepTeachImage(int type, const std::string& entry) {
  const std::string image = teachImagePathOf(type);
  std::error_code ec;
  std::string bytes;
  if (fs::exists(image, ec)) {
    auto read = readFile(image);
    if (!read)
      return makeError(ModelErrc::kStorage,
                       "cannot keep the teach image for UNDO: " + read.error().message);
    bytes = std::move(*read);
  }
  auto kept = writeFileAtomically(teachImageBeside(entry), bytes);
  if (!kept)
    return makeError(ModelErrc::kStorage,
                     "cannot keep the teach image for UNDO: " + kept.error().message);
  return {};
}

std::vector<std::string> ModelLibrary::load() {
  std::vector<std::string> problems;
  // Left by a write that a crash interrupted; this process owns the directory.
  for (const auto& dir : {directory_, history_.directory()}) {
    if (auto removed = removeStaleTemporaries(dir); !removed) {
      problems.push_back(removed.error().message);
    } else {
      for (const auto& name : *removed) {
        logInfo(dir, ": removed ", name, " (left by an interrupted write)");
      }
    }
  }
  std::error_code ec;
  std::vector<fs::path> files;
  if (!fs::exists(directory_, ec)) {
    ec.clear();  // no model trained yet
  } else if (fs::is_directory(directory_, ec)) {
    for (fs::directory_iterator it(directory_, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().extension() == ".yaml") files.push_back(it->path());
    }
  } else if (!ec) {
    problems.push_back(directory_ + ": not a directory: no model can be loaded or stored");
  }
  if (ec) problems.push_back(directory_ + ": " + ec.message());
  // By name, so that which of two files for one type is reported is stable.
  std::sort(files.begin(), files.end());
  std::map<int, std::pair<fs::path, ModelRecord>> by_type;  // ordered by type number
  for (const auto& path : files) {
    auto text = readFile(path.string());
    if (!text) {
      problems.push_back(path.string() + ": " + text.error().message);
      continue;
    }
    auto record = modelRecordFromYaml(*text);
    if (!record) {
      problems.push_back(path.string() + ": " + record.error().message);
      continue;
    }
    const int type = record->model.type;
    // try_emplace leaves `record` alone when the type is already there.
    auto [it, fresh] = by_type.try_emplace(type, path, std::move(*record));
    if (fresh) continue;
    // Two files for one type: the one store() writes (type_<n>.yaml) wins,
    // so that a restart keeps what LEARN wrote last.
    const std::string why = " is already defined by another file";
    if (path.filename() == fs::path(pathOf(type)).filename()) {
      problems.push_back(it->second.first.string() + ": type " + std::to_string(type) + why);
      it->second = {path, std::move(*record)};
    } else {
      problems.push_back(path.string() + ": type " + std::to_string(type) + why);
    }
  }
  auto models = std::make_shared<ModelList>();
  auto grasps = std::make_shared<GraspMap>();
  for (auto& [type, loaded] : by_type) {
    (*grasps)[type] = loaded.second.grasp;
    models->push_back(std::move(loaded.second.model));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  models_ = std::move(models);
  grasps_ = std::move(grasps);
  return problems;
}

Result<std::string> ModelLibrary::recordChange(int type, std::string_view change,
                                               const std::optional<std::string>& after) {
  const std::string path = pathOf(type);
  std::error_code ec;
  std::optional<std::string> before;
  if (fs::exists(path, ec)) {
    auto text = readFile(path);
    if (!text)
      return makeError(ModelErrc::kStorage,
                       "cannot keep the file for UNDO: " + text.error().message);
    before = std::move(*text);
  } else if (ec) {
    return makeError(ModelErrc::kStorage, path + ": " + ec.message());
  }
  return history_.record(type, change, before, after);
}

Result<void> ModelLibrary::writeWithUndo(int type, std::string_view change,
                                         const std::string& text) {
  auto entry = recordChange(type, change, text);
  if (!entry) return entry.error();
  auto written = writeFileAtomically(pathOf(type), text);
  if (!written) history_.drop(*entry);
  return written;
}

Result<void> ModelLibrary::store(const vision::PartModel& model, std::string_view change,
                                 const std::optional<std::string>& teach_png) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::error_code ec;
  if (fs::create_directories(directory_, ec)) {
    // A new models/ is itself an entry of its parent: durable only once the
    // parent is synced, or a crash loses the directory with every model.
    const fs::path parent = fs::absolute(directory_, ec).parent_path();
    if (!ec) (void)syncDirectory(parent.string());
  }
  if (ec) return makeError(ModelErrc::kStorage, directory_ + ": " + ec.message());
  const auto kept = grasps_->find(model.type);
  const std::string text = modelToYaml(model, kept == grasps_->end() ? GraspSetup{} : kept->second);
  auto entry =
      recordChange(model.type,
                   change.empty() ? "LEARN " + std::to_string(model.type) + " " + model.name
                                  : std::string(change),
                   text);
  if (!entry) return entry.error();
  if (auto kept = keepTeachImage(model.type, *entry); !kept) {
    history_.drop(*entry);
    return kept;
  }
  if (auto written = writeFileAtomically(pathOf(model.type), text); !written) {
    history_.drop(*entry);
    return written;
  }
  // The model is stored; its image follows (an old one would show another
  // model, so it goes whatever happens).
  const std::string image = teachImagePathOf(model.type);
  fs::remove(image, ec);
  if (teach_png) {
    if (auto saved = writeFileAtomically(image, *teach_png); !saved)
      logWarning(image, ": the teach image was not written: ", saved.error().message);
  }
  auto models = std::make_shared<ModelList>(*models_);
  models->erase(std::remove_if(models->begin(), models->end(),
                               [&](const vision::PartModel& m) { return m.type == model.type; }),
                models->end());
  models->push_back(model);
  std::sort(models->begin(), models->end(),
            [](const vision::PartModel& a, const vision::PartModel& b) { return a.type < b.type; });
  models_ = std::move(models);
  return {};
}

Result<void> ModelLibrary::remove(int type, std::string_view change) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool known = std::any_of(models_->begin(), models_->end(),
                                 [&](const vision::PartModel& m) { return m.type == type; });
  if (!known)
    return makeError(ModelErrc::kUnknownType, "no model for type " + std::to_string(type));
  auto entry = recordChange(
      type, change.empty() ? "FORGET " + std::to_string(type) : std::string(change), std::nullopt);
  if (!entry) return entry.error();
  if (auto kept = keepTeachImage(type, *entry); !kept) {
    history_.drop(*entry);
    return kept;
  }
  std::error_code ec;
  fs::remove(pathOf(type), ec);
  if (ec) {
    history_.drop(*entry);
    return makeError(ModelErrc::kStorage, pathOf(type) + ": " + ec.message());
  }
  fs::remove(teachImagePathOf(type), ec);
  // Without this a crash can bring the forgotten model back at restart.
  (void)syncDirectory(directory_);
  auto models = std::make_shared<ModelList>(*models_);
  models->erase(std::remove_if(models->begin(), models->end(),
                               [&](const vision::PartModel& m) { return m.type == type; }),
                models->end());
  models_ = std::move(models);
  auto grasps = std::make_shared<GraspMap>(*grasps_);
  grasps->erase(type);
  grasps_ = std::move(grasps);
  return {};
}

Result<void> ModelLibrary::setGrasp(int type, const GraspSetup& grasp, std::string_view change) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto model = std::find_if(models_->begin(), models_->end(),
                                  [&](const vision::PartModel& m) { return m.type == type; });
  if (model == models_->end())
    return makeError(ModelErrc::kUnknownType, "no model for type " + std::to_string(type));
  if (auto valid = validateGrasp(grasp); !valid) return valid.error();
  const std::string text = modelToYaml(*model, grasp);
  auto written = writeWithUndo(
      type, change.empty() ? "GRASP " + std::to_string(type) : std::string(change), text);
  if (!written) return makeError(ModelErrc::kStorage, written.error().message);
  auto grasps = std::make_shared<GraspMap>(*grasps_);
  (*grasps)[type] = grasp;
  grasps_ = std::move(grasps);
  return {};
}

Result<vision::PartModel> ModelLibrary::update(
    int type, const std::function<void(vision::PartModel&)>& change, std::string_view what) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto found = std::find_if(models_->begin(), models_->end(),
                                  [&](const vision::PartModel& m) { return m.type == type; });
  if (found == models_->end())
    return makeError(ModelErrc::kUnknownType, "no model for type " + std::to_string(type));
  vision::PartModel changed = *found;
  change(changed);
  changed.type = type;  // the file name and the list order depend on it
  if (auto valid = vision::validateModel(changed); !valid)
    return makeError(ModelErrc::kInvalidModel, valid.error().message);
  vision::prepareModel(changed);
  const auto kept = grasps_->find(type);
  const std::string text =
      modelToYaml(changed, kept == grasps_->end() ? GraspSetup{} : kept->second);
  auto written = writeWithUndo(
      type, what.empty() ? "TOLERANCE " + std::to_string(type) : std::string(what), text);
  if (!written) return makeError(ModelErrc::kStorage, written.error().message);
  auto models = std::make_shared<ModelList>(*models_);
  for (auto& m : *models) {
    if (m.type == type) m = changed;
  }
  models_ = std::move(models);
  return changed;
}

Result<UndoOutcome> ModelLibrary::undo() {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto newest = history_.newest();
  if (!newest) {
    return makeError(ModelErrc::kNothingToUndo,
                     "nothing to undo (the last " + std::to_string(kUndoDepth) +
                         " changes to models are kept; each UNDO takes back one)");
  }
  // Every way an entry can fail to apply sets it aside, so that one bad
  // entry never blocks the changes before it, and says so.
  const auto refuse = [&](const std::string& why) -> Error {
    const std::string aside = fs::path(history_.setAside(*newest)).filename().string();
    return makeError(ModelErrc::kUndoRefused,
                     why + ": not applied, nothing changed; set aside as " + aside +
                         " (UNDO again takes back the change before it)");
  };
  auto entry = ModelHistory::read(*newest);
  if (!entry) return refuse(entry.error().message);
  const std::string path = pathOf(entry->type);
  std::error_code ec;
  std::optional<std::string> now;
  if (fs::exists(path, ec)) {
    auto text = readFile(path);
    if (!text) return makeError(ModelErrc::kStorage, text.error().message);
    now = std::move(*text);
  } else if (ec) {
    return makeError(ModelErrc::kStorage, path + ": " + ec.message());
  }
  const std::string now_sha = now ? sha256Hex(*now) : "";
  if (now_sha != entry->after_sha256) {
    return refuse("type " + std::to_string(entry->type) + "'s model file is not what '" +
                  entry->change +
                  "' left (changed since by hand, or that change did not complete)");
  }
  std::optional<ModelRecord> record;
  if (entry->before) {
    auto parsed = modelRecordFromYaml(*entry->before);
    if (!parsed || parsed->model.type != entry->type) {
      return refuse("type " + std::to_string(entry->type) + "'s file before '" + entry->change +
                    "' does not read as its model" +
                    (parsed ? std::string() : ": " + parsed.error().message));
    }
    record = std::move(*parsed);
  }
  if (record) {
    if (auto written = writeFileAtomically(path, *entry->before); !written)
      return makeError(ModelErrc::kStorage, written.error().message);
  } else {
    fs::remove(path, ec);
    if (ec) return makeError(ModelErrc::kStorage, path + ": " + ec.message());
    (void)syncDirectory(directory_);
  }
  // The teach image as it was before that change, when the change touched
  // it (LEARN, FORGET): kept beside the entry, empty for none.
  const std::string beside = teachImageBeside(*newest);
  if (fs::exists(beside, ec)) {
    const std::string image = teachImagePathOf(entry->type);
    auto old_image = readFile(beside);
    if (old_image && !old_image->empty()) {
      if (auto put = writeFileAtomically(image, *old_image); !put)
        logWarning(image, ": the teach image was not put back: ", put.error().message);
    } else {
      fs::remove(image, ec);
    }
  }
  history_.drop(*newest);
  const int type = entry->type;
  auto models = std::make_shared<ModelList>(*models_);
  models->erase(std::remove_if(models->begin(), models->end(),
                               [&](const vision::PartModel& m) { return m.type == type; }),
                models->end());
  auto grasps = std::make_shared<GraspMap>(*grasps_);
  grasps->erase(type);
  UndoOutcome out;
  out.type = type;
  out.change = entry->change;
  if (record) {
    (*grasps)[type] = record->grasp;
    out.restored = record->model;
    models->push_back(std::move(record->model));
    std::sort(
        models->begin(), models->end(),
        [](const vision::PartModel& a, const vision::PartModel& b) { return a.type < b.type; });
  }
  models_ = std::move(models);
  grasps_ = std::move(grasps);
  out.left = history_.size();
  return out;
}

size_t ModelLibrary::undoDepth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return history_.size();
}

std::vector<std::string> ModelLibrary::checkHistory() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return history_.check();
}

Result<std::vector<StoredModelFiles>> ModelLibrary::files() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<StoredModelFiles> out;
  for (const auto& model : *models_) {
    StoredModelFiles f;
    f.type = model.type;
    auto yaml = readFile(pathOf(model.type));
    if (!yaml) return makeError(ModelErrc::kStorage, yaml.error().message);
    f.yaml = std::move(*yaml);
    std::error_code ec;
    if (fs::exists(teachImagePathOf(model.type), ec)) {
      auto png = readFile(teachImagePathOf(model.type));
      if (!png) return makeError(ModelErrc::kStorage, png.error().message);
      f.teach_png = std::move(*png);
    }
    out.push_back(std::move(f));
  }
  return out;
}

Result<void> ModelLibrary::adoptDirectory(const std::string& staged, ModelList models,
                                          GraspMap grasps) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::error_code ec;
  if (fs::exists(directory_, ec)) {
    // One rename for both directories: never a moment without a whole one.
    if (::syscall(SYS_renameat2, AT_FDCWD, staged.c_str(), AT_FDCWD, directory_.c_str(),
                  RENAME_EXCHANGE) != 0)
      return makeError(ModelErrc::kStorage, "cannot put " + staged + " in place of " + directory_ +
                                                ": " + std::strerror(errno));
  } else {
    fs::rename(staged, directory_, ec);
    if (ec) return makeError(ModelErrc::kStorage, directory_ + ": " + ec.message());
  }
  std::sort(models.begin(), models.end(),
            [](const vision::PartModel& a, const vision::PartModel& b) { return a.type < b.type; });
  models_ = std::make_shared<const ModelList>(std::move(models));
  grasps_ = std::make_shared<const GraspMap>(std::move(grasps));
  return {};
}

std::shared_ptr<const ModelList> ModelLibrary::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return models_;
}

std::shared_ptr<const GraspMap> ModelLibrary::grasps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return grasps_;
}

GraspSetup ModelLibrary::graspOf(int type) const {
  const auto all = grasps();
  const auto it = all->find(type);
  return it == all->end() ? GraspSetup{} : it->second;
}

}  // namespace picksight::store
