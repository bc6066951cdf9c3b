// The camera actions' JSON bodies as the control requests picksight-web
// forwards: the hardware trigger mode with its line, edge and timeout, and
// the fields refused before anything is sent.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "picksight/web/camera_actions.hpp"
#include "picksight/web/web_errors.hpp"

using namespace picksight;
using nlohmann::json;

TEST_CASE("the hardware mode is forwarded with its line activation and timeout", "[web]") {
  auto request = web::cameraAction("cam0", "mode",
                                   json{{"mode", "hardware"},
                                        {"line", "Line2"},
                                        {"activation", "FallingEdge"},
                                        {"timeout_ms", 2500}});
  REQUIRE(request);
  REQUIRE(request->has_set_mode());
  const auto& m = request->set_mode();
  CHECK(m.camera() == "cam0");
  CHECK(m.mode() == proto::HARDWARE_TRIGGER);
  CHECK(m.trigger_line() == "Line2");
  CHECK(m.trigger_activation() == "FallingEdge");
  CHECK(m.trigger_timeout_ms() == 2500);
  CHECK(m.fps() == 0);

  // Unset fields stay unset: the video server's defaults (Line1, the
  // camera's edge, 10 s) apply.
  request = web::cameraAction("cam0", "mode", json{{"mode", "hardware"}});
  REQUIRE(request);
  CHECK(request->set_mode().mode() == proto::HARDWARE_TRIGGER);
  CHECK(request->set_mode().trigger_line().empty());
  CHECK(request->set_mode().trigger_activation().empty());
  CHECK(request->set_mode().trigger_timeout_ms() == 0);

  request = web::cameraAction("cam0", "mode", json{{"mode", "trigger"}, {"fps", 5}});
  REQUIRE(request);
  CHECK(request->set_mode().mode() == proto::TRIGGER);
  CHECK(request->set_mode().fps() == 5);
}

TEST_CASE("bad hardware mode fields are refused naming the field", "[web]") {
  struct Bad {
    json body;
    const char* field;
  };
  const Bad bad[] = {
      {{{"mode", "trigger"}, {"line", "Line1"}}, "\"line\""},
      {{{"mode", "freerun"}, {"timeout_ms", 100}}, "\"timeout_ms\""},
      {{{"mode", "hardware"}, {"timeout_ms", 0}}, "\"timeout_ms\""},
      {{{"mode", "hardware"}, {"timeout_ms", 1.5}}, "\"timeout_ms\""},
      {{{"mode", "hardware"}, {"timeout_ms", 3600001}}, "\"timeout_ms\""},
      {{{"mode", "hardware"}, {"timeout_ms", "soon"}}, "\"timeout_ms\""},
      {{{"mode", "hardware"}, {"line", std::string(65, 'L')}}, "\"line\""},
      {{{"mode", "hardware"}, {"activation", json::array()}}, "\"activation\""},
      {{{"mode", "sideways"}}, "\"mode\""},
  };
  for (const auto& b : bad) {
    INFO(b.body.dump());
    auto request = web::cameraAction("cam0", "mode", b.body);
    REQUIRE(!request);
    CHECK(request.error().code == web::WebErrc::kBadRequest);
    CHECK_THAT(request.error().message, Catch::Contains(b.field));
  }
}
