// Vision cell wiring.
#include "picksight/vision_app/vision_cell.hpp"

#include "picksight/protocol/calibration_commands.hpp"
#include "picksight/protocol/model_commands.hpp"

namespace picksight::app {

VisionCell::VisionCell(const std::string& data_dir, std::unique_ptr<CameraLink> camera,
                       VisionOptions options)
    : models_(data_dir + "/models"),
      calibration_(data_dir + "/calibration.yaml"),
      vision_(std::move(camera), std::move(options), &models_),
      protocol_(vision_),
      context_(vision_, calibration_) {
  addModelCommands(protocol_.table(), vision_);
  addCalibrationCommands(protocol_.table(), vision_, calibration_);
  addCellCommands(protocol_.table(), context_);
}

std::vector<std::string> VisionCell::load() {
  std::vector<std::string> problems;
  for (auto& p : models_.load()) problems.push_back("model rejected: " + p);
  if (auto ok = calibration_.load(); !ok)
    problems.push_back(
        "calibration rejected (LOCATE and changes refused until repaired, or CLEARCAL): " +
        ok.error().message);
  return problems;
}

}  // namespace picksight::app
