// Errors to robot ERROR codes: the protocol's one table.
#include "picksight/protocol/robot_errors.hpp"

#include <array>
#include <utility>

#include "picksight/calibration/robot_camera.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/cell/vision_settings.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/jobs/job_file.hpp"
#include "picksight/link/camera_link.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/transport/control_client.hpp"

namespace picksight::protocol {

using cell::VisionServiceErrc;
using cell::VisionSettingsErrc;

using store::CellCalibrationErrc;
using store::ModelErrc;

using transport::ControlErrc;

namespace {

using calibration::CalibrationErrc;

constexpr int kInternal = 99;

const std::pair<std::error_code, int> kTable[] = {
    {VisionServiceErrc::kNoTarget, 1},
    {VisionServiceErrc::kSeveralTargets, 2},
    {VisionServiceErrc::kNotADisc, 3},
    {ProtocolErrc::kUnknownCommand, 10},
    {ProtocolErrc::kBadArguments, 11},
    {ProtocolErrc::kRequestTooLong, 12},
    {ProtocolErrc::kTooManyConnections, 13},
    {ProtocolErrc::kEmptyRequest, 14},
    {ProtocolErrc::kNotAllowed, 15},
    {ProtocolErrc::kIdle, 16},
    {ProtocolErrc::kReadOnly, 17},
    {link::CameraErrc::kNoFrame, 20},
    {link::CameraErrc::kNoVideoServer, 21},
    {ControlErrc::kNoReply, 21},
    {link::CameraErrc::kCameraRefused, 22},
    {link::CameraErrc::kUnknownFeature, 22},
    {link::CameraErrc::kNoTriggerPulse, 23},
    {vision::PartModelErrc::kNoPart, 30},
    {vision::PartModelErrc::kSeveralParts, 31},
    {VisionServiceErrc::kUnknownType, 32},
    {ModelErrc::kUnknownType, 32},
    {VisionServiceErrc::kStorageFailed, 33},
    {ModelErrc::kStorage, 33},
    {VisionServiceErrc::kOutsideFrame, 34},
    {VisionServiceErrc::kNoPartInRectangle, 35},
    {VisionServiceErrc::kSeveralPartsInRectangle, 36},
    {ModelErrc::kNothingToUndo, 37},
    {ModelErrc::kUndoRefused, 38},
    {VisionServiceErrc::kViewRefused, 39},
    {CellCalibrationErrc::kNoSuchPoint, 40},
    {CalibrationErrc::kTooFewPoints, 41},
    {CalibrationErrc::kDegeneratePoints, 42},
    {CalibrationErrc::kBadTarget, 3},
    {CalibrationErrc::kBadInput, 11},
    {CellCalibrationErrc::kCalibrationStorage, 43},
    {CalibrationErrc::kBadFile, 43},
    {CellCalibrationErrc::kNotComputed, 44},
    {CellCalibrationErrc::kDamaged, 45},
    {CellCalibrationErrc::kTooManyPoints, 46},
    {CellCalibrationErrc::kPointsChanged, 47},
    {VisionSettingsErrc::kBadSetting, 11},
    {VisionSettingsErrc::kDamaged, 48},
    {VisionSettingsErrc::kStorage, 49},
    {jobs::JobErrc::kNoSuchJob, 50},
    {jobs::JobErrc::kDamaged, 51},
    {jobs::JobErrc::kStorage, 52},
    {jobs::JobErrc::kTooLarge, 53},
    {jobs::JobErrc::kBadName, 54},
    {filmstrip::FilmstripErrc::kNoEntry, 55},
    {filmstrip::FilmstripErrc::kDamaged, 56},
    {filmstrip::FilmstripErrc::kOff, 57},
    {filmstrip::FilmstripErrc::kStorage, 58},
    {filmstrip::FilmstripErrc::kNoFrame, 59},
    {ProtocolErrc::kInternalError, kInternal},
};

}  // namespace

int robotErrorCode(const std::error_code& code) {
  for (const auto& [known, robot] : kTable) {
    if (known == code) return robot;
  }
  // Any other answer of the video server: the camera refused.
  if (code.category() == make_error_code(ControlErrc::kInternal).category()) return 22;
  return kInternal;
}

}  // namespace picksight::protocol
