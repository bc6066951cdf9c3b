// The models as a resized frame sees them (see modelsForFrame), kept per
// (model library generation, scale), so that a resized or cropped camera
// does not rebuild every model and its boundary distance map on each LOCATE.
//
// A generation is one snapshot of the library: every LEARN, DELETE, reload
// or tolerance change publishes a new list, so a lookup with a list other
// than the cached one drops what was kept for the old one. The cache holds
// that snapshot, so its address cannot be reused while it is a key.
//
// Threading: thread-safe; the lists handed out are immutable and shared.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "picksight/common/frame.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::cell {

class ScaledModelCache {
 public:
  // modelsForFrame(models, mapping), built once per (models, scale).
  std::shared_ptr<const store::ModelList> forFrame(std::shared_ptr<const store::ModelList> models,
                                                   const SensorMapping& mapping);
  // Scaled lists built so far (each miss builds one).
  uint64_t builds() const;

 private:
  struct Entry {
    std::shared_ptr<const store::ModelList> source;
    double scale = 1;
    std::shared_ptr<const store::ModelList> scaled;
  };
  // Scales kept per generation: a camera going back and forth between a
  // few sizes keeps them all.
  static constexpr size_t kScales = 4;

  mutable std::mutex mutex_;    // guards entries_ and builds_
  std::vector<Entry> entries_;  // one generation, most recently used first
  uint64_t builds_ = 0;
};

}  // namespace picksight::cell
