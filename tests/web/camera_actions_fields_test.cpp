// The camera actions other than the trigger mode, as the control requests
// picksight-web forwards: each field where it lands, each bound accepted at
// its value and refused one past it naming the field, and an unknown action.
#include <catch2/catch.hpp>

#include <string>

#include <nlohmann/json.hpp>

#include "picksight/web/camera_actions.hpp"
#include "picksight/web/web_errors.hpp"

using namespace picksight;
using nlohmann::json;

namespace {
// The refusal of `body` for `action`: a bad request naming `field`.
void checkRefused(const std::string& action, const json& body, const std::string& field) {
  INFO(action << " " << body.dump());
  auto request = web::cameraAction("cam0", action, body);
  REQUIRE_FALSE(request);
  CHECK(request.error().code == web::WebErrc::kBadRequest);
  CHECK_THAT(request.error().message, Catch::Contains("\"" + field + "\""));
}
}  // namespace

TEST_CASE("a ROI's four fields reach the request as whole pixels up to 65535", "[web]") {
  auto request = web::cameraAction("cam1", "roi",
                                   json{{"x", 10}, {"y", 20}, {"width", 65535}, {"height", 480}});
  REQUIRE(request);
  REQUIRE(request->has_set_roi());
  const auto& roi = request->set_roi();
  CHECK(roi.camera() == "cam1");
  CHECK(roi.roi().x() == 10);
  CHECK(roi.roi().y() == 20);
  CHECK(roi.roi().width() == 65535);
  CHECK(roi.roi().height() == 480);
  checkRefused("roi", json{{"x", 0}, {"y", 0}, {"width", 65536}, {"height", 1}}, "width");
  checkRefused("roi", json{{"x", -1}}, "x");
  checkRefused("roi", json{{"y", 2.5}}, "y");
  checkRefused("roi", json{{"height", "tall"}}, "height");
}

TEST_CASE("an output size is a scale up to 16 or a width and height", "[web]") {
  auto request = web::cameraAction("cam0", "size", json{{"scale", 16}});
  REQUIRE(request);
  REQUIRE(request->has_set_size());
  CHECK(request->set_size().camera() == "cam0");
  CHECK(request->set_size().scale() == 16);
  request = web::cameraAction("cam0", "size", json{{"width", 320}, {"height", 240}});
  REQUIRE(request);
  CHECK(request->set_size().scale() == 0);
  CHECK(request->set_size().width() == 320);
  CHECK(request->set_size().height() == 240);
  checkRefused("size", json{{"scale", 16.5}}, "scale");
  checkRefused("size", json{{"scale", 0}}, "scale");
  checkRefused("size", json{{"scale", -2}}, "scale");
  checkRefused("size", json{{"width", 70000}, {"height", 240}}, "width");
}

TEST_CASE("a camera feature's name and value are bounded and numbers come as text", "[web]") {
  auto request =
      web::cameraAction("cam0", "feature", json{{"name", std::string(256, 'N')}, {"value", 1.5}});
  REQUIRE(request);
  REQUIRE(request->has_set_feature());
  CHECK(request->set_feature().name() == std::string(256, 'N'));
  CHECK(request->set_feature().value() == "1.5");
  request = web::cameraAction("cam0", "feature", json{{"name", "ReverseX"}, {"value", true}});
  REQUIRE(request);
  CHECK(request->set_feature().value() == "true");
  request = web::cameraAction("cam0", "feature",
                              json{{"name", "DeviceUserID"}, {"value", std::string(4096, 'v')}});
  REQUIRE(request);
  CHECK(request->set_feature().value().size() == 4096);
  checkRefused("feature", json{{"name", std::string(257, 'N')}}, "name");
  checkRefused("feature", json{{"name", ""}}, "name");
  checkRefused("feature", json{{"value", "1"}}, "name");
  checkRefused("feature", json{{"name", "Gain"}, {"value", std::string(4097, 'v')}}, "value");
  checkRefused("feature", json{{"name", "Gain"}, {"value", json::array()}}, "value");
}

TEST_CASE("the frame rate and the trigger input's names are accepted up to their bounds", "[web]") {
  auto request = web::cameraAction("cam0", "mode", json{{"mode", "freerun"}, {"fps", 10000}});
  REQUIRE(request);
  CHECK(request->set_mode().mode() == proto::FREERUN);
  CHECK(request->set_mode().fps() == 10000);
  checkRefused("mode", json{{"mode", "freerun"}, {"fps", 10001}}, "fps");
  checkRefused("mode", json{{"mode", "freerun"}, {"fps", -1}}, "fps");
  request = web::cameraAction("cam0", "mode",
                              json{{"mode", "hardware"},
                                   {"line", std::string(64, 'L')},
                                   {"activation", std::string(64, 'A')},
                                   {"timeout_ms", 3600000}});
  REQUIRE(request);
  CHECK(request->set_mode().trigger_line().size() == 64);
  CHECK(request->set_mode().trigger_activation().size() == 64);
  CHECK(request->set_mode().trigger_timeout_ms() == 3600000);
  checkRefused("mode", json{{"mode", "hardware"}, {"activation", std::string(65, 'A')}},
               "activation");
  checkRefused("mode", json{{"mode", "hardware"}, {"timeout_ms", 0.5}}, "timeout_ms");
}

TEST_CASE("the target overlay is a point in mm or hidden", "[web]") {
  auto request = web::cameraAction("cam0", "target", json{{"x_mm", 12.5}, {"y_mm", -3}});
  REQUIRE(request);
  REQUIRE(request->has_set_target());
  CHECK_FALSE(request->set_target().hide());
  CHECK(request->set_target().x_mm() == 12.5);
  CHECK(request->set_target().y_mm() == -3);
  request = web::cameraAction("cam0", "target", json{{"hide", true}});
  REQUIRE(request);
  CHECK(request->set_target().hide());
  checkRefused("target", json{{"hide", "yes"}}, "hide");
  checkRefused("target", json{{"x_mm", 1}}, "y_mm");
  checkRefused("target", json{{"y_mm", 1}}, "x_mm");
  checkRefused("target", json{{"hide", false}}, "x_mm");
}

TEST_CASE("open and close and trigger name their camera and an unknown action is not found",
          "[web]") {
  auto request = web::cameraAction("cam2", "open", json::object());
  REQUIRE(request);
  REQUIRE(request->has_open_stream());
  CHECK(request->open_stream().camera() == "cam2");
  request = web::cameraAction("cam2", "close", json::object());
  REQUIRE(request);
  REQUIRE(request->has_close_stream());
  CHECK(request->close_stream().camera() == "cam2");
  request = web::cameraAction("cam2", "trigger", json::object());
  REQUIRE(request);
  REQUIRE(request->has_trigger());
  CHECK(request->trigger().camera() == "cam2");
  request = web::cameraAction("cam2", "reboot", json::object());
  REQUIRE_FALSE(request);
  CHECK(request.error().code == web::WebErrc::kNotFound);
  CHECK_THAT(request.error().message, Catch::Contains("reboot"));
}
