// Any GenICam feature of an Aravis device by name, typed, as the Source
// interface's Feature: read with its range or choices, written after checking
// type and range so errors name the feature and the range.
#pragma once

#include <arv.h>

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
  Result<Feature> get(const std::string& name) const;
  // Commands execute; the value is ignored for them.
  Result<void> set(const std::string& name, const std::string& value) const;

 private:
  Result<ArvGcFeatureNode*> node(const std::string& name) const;
  Feature describe(ArvGcFeatureNode* node) const;
  void collect(ArvGcNode* category, std::vector<Feature>& out, int depth) const;

  ArvDevice* device_;
};

}  // namespace picksight::video
