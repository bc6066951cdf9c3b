// Any GenICam feature of an Aravis device by name, typed, as the Source
// interface's Feature: read with its range or choices, written after checking
// type and range so errors name the feature and the range.
#pragma once

#include <arv.h>

#include <optional>
#include <string>
#include <vector>

#include "picksight/sources/source.hpp"

namespace picksight::video {

class GenicamFeatures {
 public:
  // Borrows the device: it must outlive this object. Not thread-safe: the
  // owning source calls it from its acquisition thread only.
  explicit GenicamFeatures(ArvDevice* device) : device_(device) {}

  // Every implemented, available feature under the "Root" category.
  std::vector<Feature> list() const;
  // The names of every feature under "Root", from the XML alone (no device
  // access); listed() describes one as list() would, or nullopt when list()
  // leaves it out (not implemented, not available).
  std::vector<std::string> names() const;
  std::optional<Feature> listed(const std::string& name) const;
  Result<Feature> get(const std::string& name) const;
  // Commands execute; the value is ignored for them.
  Result<void> set(const std::string& name, const std::string& value) const;

 private:
  Result<ArvGcFeatureNode*> node(const std::string& name) const;
  Feature describe(ArvGcFeatureNode* node) const;
  // Calls `visit` for every feature node under `category`, in order.
  template <typename Visit>
  void walk(ArvGcNode* category, const Visit& visit, int depth) const;
  static bool listable(ArvGcFeatureNode* feature);

  ArvDevice* device_;
};

}  // namespace picksight::video
