// picksight-cam features, get, set, open and close against a real ZeroMQ
// REP socket.
#include "cam_test_support.hpp"

using namespace picksight::camtest;
namespace proto = picksight::proto;

TEST_CASE("features prints names, types, values, ranges, units and access", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* list = reply.mutable_list_features();
  *list->add_features() = exposureFeature();
  auto* gain = list->add_features();
  gain->set_name("GainRaw");
  gain->set_type(proto::INTEGER);
  gain->set_value("0");
  gain->set_has_range(true);
  gain->set_max(10);
  gain->set_increment(1);
  gain->set_writable(true);
  *list->add_features() = triggerModeFeature();
  // GenICam float ranges often end at the largest double.
  auto* rate = list->add_features();
  rate->set_name("AcquisitionFrameRate");
  rate->set_type(proto::FLOAT);
  rate->set_value("25.5");
  rate->set_has_range(true);
  rate->set_min(0.1);
  rate->set_max(std::numeric_limits<double>::max());
  rate->set_unit("Hz");
  rate->set_writable(true);
  auto* model = list->add_features();
  model->set_name("DeviceModelName");
  model->set_type(proto::STRING);
  model->set_value("GV01");
  auto* software = list->add_features();
  software->set_name("TriggerSoftware");
  software->set_type(proto::COMMAND);
  software->set_writable(true);
  FakeServer server(context, reply);

  const Run run = runAt(context, server, {"features", "cam0"});
  CHECK(run.code == 0);
  CHECK(run.err.empty());
  CHECK(run.out ==
        "NAME                  TYPE         VALUE  RANGE                         UNIT  WRITABLE\n"
        "ExposureTimeAbs       float        20000  10..1000000                   us    yes\n"
        "GainRaw               integer      0      0..10, step 1                       yes\n"
        "TriggerMode           enumeration  Off    Off|On                              yes\n"
        "AcquisitionFrameRate  float        25.5   0.1..1.7976931348623157e+308  Hz    yes\n"
        "DeviceModelName       string       GV01                                       no\n"
        "TriggerSoftware       command                                                 yes\n");
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kListFeatures);
  CHECK(request.list_features().camera() == "cam0");
}

TEST_CASE("features as JSON: every field of every feature", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  *reply.mutable_list_features()->add_features() = exposureFeature();
  *reply.mutable_list_features()->add_features() = triggerModeFeature();
  FakeServer server(context, reply);
  const Run run = runAt(context, server, {"--json", "features", "cam0"});
  CHECK(run.code == 0);
  CHECK(run.out == R"({"camera":"cam0","features":[{"name":"ExposureTimeAbs","type":"float",)"
                   R"("value":"20000","has_range":true,"min":10.0,"max":1000000.0,"increment":0.0,)"
                   R"("choices":[],"unit":"us","description":"Exposure time","writable":true},)"
                   R"({"name":"TriggerMode","type":"enumeration","value":"Off","has_range":false,)"
                   R"("min":0.0,"max":0.0,"increment":0.0,"choices":["Off","On"],"unit":"",)"
                   R"("description":"","writable":true}]})"
                   "\n");
}

TEST_CASE("features of a camera without any", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  CHECK(runAt(context, server, {"features", "cam0"}).out == "cam0: no features\n");
  CHECK(runAt(context, server, {"--json", "features", "cam0"}).out ==
        "{\"camera\":\"cam0\",\"features\":[]}\n");
}

TEST_CASE("get prints the bare value, or the whole feature as JSON", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, featureReply(exposureFeature()));
  SECTION("text") {
    const Run run = runAt(context, server, {"get", "cam0", "ExposureTimeAbs"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "20000\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "get", "cam0", "ExposureTimeAbs"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"name":"ExposureTimeAbs","type":"float","value":"20000",)"
                     R"("has_range":true,"min":10.0,"max":1000000.0,"increment":0.0,"choices":[],)"
                     R"("unit":"us","description":"Exposure time","writable":true})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kGetFeature);
  CHECK(request.get_feature().camera() == "cam0");
  CHECK(request.get_feature().name() == "ExposureTimeAbs");
}

TEST_CASE("set sends the value as typed and prints the value read back", "[cam]") {
  zmq::context_t context;
  SECTION("text, with the unit") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "ExposureTimeAbs = 20000 us\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetFeature);
    CHECK(request.set_feature().camera() == "cam0");
    CHECK(request.set_feature().name() == "ExposureTimeAbs");
    CHECK(request.set_feature().value() == "20000");
  }
  SECTION("a camera that rounded the value: says what was asked") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "19999.5"});
    CHECK(run.code == 0);
    CHECK(run.out == "ExposureTimeAbs = 20000 us (requested 19999.5)\n");
  }
  SECTION("the same number written differently is not a rounding") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000.0"});
    CHECK(run.out == "ExposureTimeAbs = 20000 us\n");
  }
  SECTION("a negative value is a value, not an option") {
    proto::Feature offset;
    offset.set_name("BlackLevel");
    offset.set_type(proto::INTEGER);
    offset.set_value("-5");
    FakeServer server(context, featureReply(offset));
    const Run run = runAt(context, server, {"set", "cam0", "BlackLevel", "-5"});
    CHECK(run.code == 0);
    CHECK(run.out == "BlackLevel = -5\n");
    CHECK(onlyRequest(server).set_feature().value() == "-5");
  }
  SECTION("an empty string value") {
    proto::Feature user;
    user.set_name("DeviceUserID");
    user.set_type(proto::STRING);
    FakeServer server(context, featureReply(user));
    const Run run = runAt(context, server, {"set", "cam0", "DeviceUserID", ""});
    CHECK(run.code == 0);
    CHECK(run.out == "DeviceUserID = \n");
    const proto::ControlRequest request = onlyRequest(server);
    CHECK(request.set_feature().value().empty());
  }
  SECTION("JSON") {
    FakeServer server(context, featureReply(exposureFeature()));
    const Run run = runAt(context, server, {"set", "cam0", "ExposureTimeAbs", "20000", "--json"});
    CHECK(run.code == 0);
    CHECK_THAT(run.out, Catch::StartsWith(R"({"name":"ExposureTimeAbs","type":"float",)"
                                          R"("value":"20000",)"));
  }
}

TEST_CASE("feature errors exit 1 with the server's text", "[cam]") {
  struct Case {
    std::vector<std::string> args;
    proto::Error::Code code;
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"get", "cam0", "Exposure"},
       proto::Error::UNKNOWN_FEATURE,
       "unknown feature 'Exposure'",
       "picksight-cam: get: unknown feature 'Exposure' (server error UNKNOWN_FEATURE, code 7)\n"},
      {{"set", "cam0", "GainRaw", "99"},
       proto::Error::OUT_OF_RANGE,
       "GainRaw: 99 is out of range 0..10",
       "picksight-cam: set: GainRaw: 99 is out of range 0..10 (server error OUT_OF_RANGE, "
       "code 3)\n"},
      {{"set", "cam0", "GainRaw", "3"},
       proto::Error::CAMERA_UNAVAILABLE,
       "camera 'cam0' is disconnected",
       "picksight-cam: set: camera 'cam0' is disconnected (server error CAMERA_UNAVAILABLE, "
       "code 5)\n"},
      {{"features", "cam0"},
       proto::Error::CAMERA_UNAVAILABLE,
       "camera 'cam0' is disconnected",
       "picksight-cam: features: camera 'cam0' is disconnected (server error CAMERA_UNAVAILABLE, "
       "code 5)\n"},
  };
  zmq::context_t context;
  for (const Case& c : cases) {
    INFO("command: " << c.args[0] << ", error: " << c.text);
    FakeServer server(context, errorReply(c.code, c.text));
    const Run run = runAt(context, server, c.args);
    CHECK(run.code == 1);
    CHECK(run.out.empty());
    CHECK(run.err == c.expected);
  }
}

TEST_CASE("get and set with a reply that lacks the feature are errors", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"get", "cam0", "GainRaw"},
        std::vector<std::string>{"set", "cam0", "GainRaw", "3"}}) {
    INFO("command: " << args[0]);
    const Run run = runAt(context, server, args);
    CHECK(run.code == 1);
    CHECK(run.out.empty());
    CHECK_THAT(run.err, Catch::Contains("unexpected reply: no feature"));
  }
}

TEST_CASE("open and close send the camera and confirm", "[cam]") {
  struct Case {
    std::string command;
    proto::ControlRequest::RequestCase request_case;
    std::string text;
    std::string json;
  };
  const std::vector<Case> cases = {
      {"open", proto::ControlRequest::kOpenStream, "cam0: stream opened\n",
       "{\"ok\":true,\"camera\":\"cam0\",\"open\":true}\n"},
      {"close", proto::ControlRequest::kCloseStream, "cam0: stream closed, device released\n",
       "{\"ok\":true,\"camera\":\"cam0\",\"open\":false}\n"},
  };
  zmq::context_t context;
  for (const Case& c : cases) {
    INFO("command: " << c.command);
    FakeServer server(context, okReply());
    const Run text = runAt(context, server, {c.command, "cam0"});
    CHECK(text.code == 0);
    CHECK(text.out == c.text);
    const Run json = runAt(context, server, {"--json", c.command, "cam0"});
    CHECK(json.code == 0);
    CHECK(json.out == c.json);
    const std::vector<proto::ControlRequest> requests = server.stop();
    REQUIRE(requests.size() == 2);
    REQUIRE(requests[0].request_case() == c.request_case);
    CHECK((c.request_case == proto::ControlRequest::kOpenStream
               ? requests[0].open_stream().camera()
               : requests[0].close_stream().camera()) == "cam0");
  }
}
