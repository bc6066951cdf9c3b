// The control-reply table: driver and server errors get their wire codes,
// and the client decodes them back to what the server meant.
#include <catch2/catch.hpp>

#include "picksight/sources/source.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/video_server/control_errors.hpp"
#include "picksight/video_server/video_errors.hpp"

using namespace picksight;
using namespace picksight::video;

TEST_CASE("control errors map to their wire codes", "[video_server]") {
  CHECK(controlCode(SourceErrc::kTimeout) == proto::Error::TIMEOUT);
  CHECK(controlCode(SourceErrc::kUnavailable) == proto::Error::CAMERA_UNAVAILABLE);
  CHECK(controlCode(SourceErrc::kUnknownFeature) == proto::Error::UNKNOWN_FEATURE);
  CHECK(controlCode(SourceErrc::kBadValue) == proto::Error::OUT_OF_RANGE);
  CHECK(controlCode(SourceErrc::kNotSupported) == proto::Error::NOT_SUPPORTED);
  CHECK(controlCode(VideoErrc::kOutOfRange) == proto::Error::OUT_OF_RANGE);
  CHECK(controlCode(VideoErrc::kUnknownCamera) == proto::Error::UNKNOWN_CAMERA);
  CHECK(controlCode(VideoErrc::kBusy) == proto::Error::BUSY);
  CHECK(controlCode(VideoErrc::kBadRequest) == proto::Error::BAD_REQUEST);
  CHECK(controlCode(std::error_code(5, std::generic_category())) == proto::Error::INTERNAL);
}

TEST_CASE("an error reply carries the code and the message", "[video_server]") {
  const auto reply = errorReply(makeError(VideoErrc::kUnknownCamera, "unknown camera 'x'"));
  CHECK(reply.error().code() == proto::Error::UNKNOWN_CAMERA);
  CHECK(reply.error().text() == "unknown camera 'x'");
}
