// The robot error table: every domain error a request can meet gets the code
// docs/PROTOCOL.md promises robot programs, whatever the enums' own values.
#include <catch2/catch.hpp>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/cell/vision_settings.hpp"
#include "picksight/link/camera_link.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/protocol/robot_errors.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_file.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/vision/models/part_model.hpp"

using namespace picksight;
using namespace picksight::protocol;
using namespace picksight::cell;
using namespace picksight::store;
using namespace picksight::transport;

TEST_CASE("robot error codes are the documented ones", "[vision_app][protocol]") {
  CHECK(robotErrorCode(VisionServiceErrc::kNoTarget) == 1);
  CHECK(robotErrorCode(VisionServiceErrc::kSeveralTargets) == 2);
  CHECK(robotErrorCode(VisionServiceErrc::kNotADisc) == 3);
  CHECK(robotErrorCode(ProtocolErrc::kUnknownCommand) == 10);
  CHECK(robotErrorCode(ProtocolErrc::kBadArguments) == 11);
  CHECK(robotErrorCode(ProtocolErrc::kRequestTooLong) == 12);
  CHECK(robotErrorCode(ProtocolErrc::kTooManyConnections) == 13);
  CHECK(robotErrorCode(ProtocolErrc::kEmptyRequest) == 14);
  CHECK(robotErrorCode(picksight::link::CameraErrc::kNoFrame) == 20);
  CHECK(robotErrorCode(picksight::link::CameraErrc::kNoVideoServer) == 21);
  CHECK(robotErrorCode(ControlErrc::kNoReply) == 21);
  CHECK(robotErrorCode(picksight::link::CameraErrc::kCameraRefused) == 22);
  CHECK(robotErrorCode(picksight::link::CameraErrc::kUnknownFeature) == 22);
  CHECK(robotErrorCode(vision::PartModelErrc::kNoPart) == 30);
  CHECK(robotErrorCode(vision::PartModelErrc::kSeveralParts) == 31);
  CHECK(robotErrorCode(VisionServiceErrc::kUnknownType) == 32);
  CHECK(robotErrorCode(ModelErrc::kUnknownType) == 32);
  CHECK(robotErrorCode(VisionServiceErrc::kStorageFailed) == 33);
  CHECK(robotErrorCode(ModelErrc::kStorage) == 33);
  CHECK(robotErrorCode(CellCalibrationErrc::kNoSuchPoint) == 40);
  CHECK(robotErrorCode(calibration::CalibrationErrc::kTooFewPoints) == 41);
  CHECK(robotErrorCode(calibration::CalibrationErrc::kDegeneratePoints) == 42);
  CHECK(robotErrorCode(CellCalibrationErrc::kCalibrationStorage) == 43);
  CHECK(robotErrorCode(CellCalibrationErrc::kNotComputed) == 44);
  CHECK(robotErrorCode(CellCalibrationErrc::kDamaged) == 45);
  CHECK(robotErrorCode(CellCalibrationErrc::kTooManyPoints) == 46);
  CHECK(robotErrorCode(CellCalibrationErrc::kPointsChanged) == 47);
  CHECK(robotErrorCode(VisionSettingsErrc::kBadSetting) == 11);
  CHECK(robotErrorCode(VisionSettingsErrc::kDamaged) == 48);
  CHECK(robotErrorCode(VisionSettingsErrc::kStorage) == 49);
  CHECK(robotErrorCode(ProtocolErrc::kInternalError) == 99);
}

TEST_CASE("an error the robot table does not know is an internal error", "[vision_app][protocol]") {
  // Same number as a known code, another domain: the domain decides.
  CHECK(robotErrorCode(std::error_code(1, std::generic_category())) == 99);
  CHECK(robotErrorCode(vision::PartModelErrc::kNotGrey) == 99);
  // Any refusal the video server gives a setting is the camera refusing it.
  CHECK(robotErrorCode(ControlErrc::kOutOfRange) == 22);
}

TEST_CASE("errorReply writes the table's code and the message", "[vision_app][protocol]") {
  CHECK(errorReply(makeError(CellCalibrationErrc::kNoSuchPoint, "no point with id 7")) ==
        "ERROR 40 no point with id 7");
  CHECK(errorReply(ProtocolErrc::kBadArguments, "usage: LOCATE <type>") ==
        "ERROR 11 usage: LOCATE <type>");
}
