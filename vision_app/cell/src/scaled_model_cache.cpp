// Scaled model cache: one library generation, a few scales.
#include "picksight/cell/scaled_model_cache.hpp"

#include <algorithm>
#include <cmath>

#include "picksight/cell/vision_service.hpp"

namespace picksight::cell {

using store::ModelList;

std::shared_ptr<const ModelList> ScaledModelCache::forFrame(std::shared_ptr<const ModelList> models,
                                                            const SensorMapping& mapping) {
  if (!models || models->empty() || !isResized(mapping)) return modelsForFrame(models, mapping);
  const double scale = frameScale(mapping);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // A new generation: what was kept describes models that no longer exist.
    if (!entries_.empty() && entries_.front().source != models) entries_.clear();
    const auto hit = std::find_if(entries_.begin(), entries_.end(),
                                  [&](const Entry& e) { return e.scale == scale; });
    if (hit != entries_.end()) {
      std::rotate(entries_.begin(), hit, hit + 1);
      return entries_.front().scaled;
    }
  }
  // Built outside the lock: scaling every model takes a while, and two
  // requests racing for the same scale merely build it twice.
  auto scaled = modelsForFrame(models, mapping);
  std::lock_guard<std::mutex> lock(mutex_);
  ++builds_;
  if (!entries_.empty() && entries_.front().source != models) entries_.clear();
  const bool known = std::any_of(entries_.begin(), entries_.end(),
                                 [&](const Entry& e) { return e.scale == scale; });
  if (!known) {
    entries_.insert(entries_.begin(), Entry{std::move(models), scale, scaled});
    if (entries_.size() > kScales) entries_.pop_back();
  }
  return scaled;
}

uint64_t ScaledModelCache::builds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return builds_;
}

}  // namespace picksight::cell
