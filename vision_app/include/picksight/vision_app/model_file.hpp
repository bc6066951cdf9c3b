// The model file: one part model as human-readable YAML with a format
// version, so an integrator can read, diff and hand-tune (weights, tolerances,
// verify percent) what training produced.
#pragma once

#include <string>

#include "picksight/common/result.hpp"
#include "picksight/vision/part_model.hpp"

namespace picksight::app {

constexpr int kModelFormatVersion = 1;

std::string modelToYaml(const vision::PartModel& model);

// Parses and validates; errors say what is wrong (not which file: the caller
// knows). The model comes back prepared (vision::prepareModel).
Result<vision::PartModel> modelFromYaml(const std::string& text);

}  // namespace picksight::app
