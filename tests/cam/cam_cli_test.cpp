// picksight-cam against a real ZeroMQ REP socket: what each camera command
// sends, and what it prints for people and scripts.
#include "cam_test_support.hpp"

using namespace picksight::camtest;
namespace proto = picksight::proto;

TEST_CASE("list prints an aligned table, or JSON", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* cameras = reply.mutable_list_cameras();
  auto* cam0 = cameras->add_cameras();
  cam0->set_name("cam0");
  cam0->set_source("synthetic:");
  cam0->set_state("streaming");
  cam0->set_mode(proto::FREERUN);
  auto* left = cameras->add_cameras();
  left->set_name("conveyor-left");
  left->set_source("aravis:Basler-12345");
  left->set_state("reconnecting");
  left->set_mode(proto::TRIGGER);
  FakeServer server(context, reply);

  SECTION("text") {
    const Run run = runAt(context, server, {"list"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out ==
          "NAME           SOURCE               STATE         MODE\n"
          "cam0           synthetic:           streaming     freerun\n"
          "conveyor-left  aravis:Basler-12345  reconnecting  trigger\n");
  }
  SECTION("JSON, with the option after the command") {
    const Run run = runAt(context, server, {"list", "--json"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"cameras":[{"name":"cam0","source":"synthetic:","state":"streaming",)"
                     R"("mode":"freerun"},{"name":"conveyor-left","source":"aravis:Basler-12345",)"
                     R"("state":"reconnecting","mode":"trigger"}]})"
                     "\n");
  }
  CHECK(onlyRequest(server).request_case() == proto::ControlRequest::kListCameras);
}

TEST_CASE("list of a server without cameras", "[cam]") {
  zmq::context_t context;
  // The list part left out entirely: proto3 cannot tell it from an empty list.
  FakeServer server(context, okReply());
  CHECK(runAt(context, server, {"list"}).out == "no cameras\n");
  CHECK(runAt(context, server, {"--json", "list"}).out == "{\"cameras\":[]}\n");
}

TEST_CASE("info prints key: value lines, or JSON with escaped strings", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  auto* d = reply.mutable_describe_camera();
  d->mutable_summary()->set_name("cam0");
  d->mutable_summary()->set_source("aravis:Basler-12345");
  d->mutable_summary()->set_state("streaming");
  d->mutable_summary()->set_mode(proto::TRIGGER);
  d->set_vendor("Basler");
  d->set_model("acA1920-40gm \"rev\\2\"");
  d->set_serial("12345");
  d->set_sensor_width(1920);
  d->set_sensor_height(1200);
  d->mutable_roi()->set_x(100);
  d->mutable_roi()->set_y(50);
  d->mutable_roi()->set_width(800);
  d->mutable_roi()->set_height(600);
  d->set_output_width(400);
  d->set_output_height(300);
  d->set_pixel_format(proto::MONO8);
  d->set_fps(40.0);
  d->add_source_formats("Mono8");
  d->add_source_formats("Mono12");
  FakeServer server(context, reply);

  SECTION("text") {
    const Run run = runAt(context, server, {"info", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "camera:         cam0\n"
          "source:         aravis:Basler-12345\n"
          "state:          streaming\n"
          "mode:           trigger\n"
          "vendor:         Basler\n"
          "model:          acA1920-40gm \"rev\\2\"\n"
          "serial:         12345\n"
          "sensor:         1920x1200\n"
          "roi:            x=100 y=50 width=800 height=600\n"
          "output:         400x300\n"
          "pixel format:   mono8\n"
          "fps:            40.0\n"
          "source formats: Mono8, Mono12\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "info", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"name":"cam0","source":"aravis:Basler-12345","state":"streaming",)"
                     R"("mode":"trigger","vendor":"Basler","model":"acA1920-40gm \"rev\\2\"",)"
                     R"("serial":"12345","sensor_width":1920,"sensor_height":1200,)"
                     R"("roi":{"x":100,"y":50,"width":800,"height":600},"output_width":400,)"
                     R"("output_height":300,"pixel_format":"mono8","fps":40.0,)"
                     R"("source_formats":["Mono8","Mono12"]})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kDescribeCamera);
  CHECK(request.describe_camera().camera() == "cam0");
}

TEST_CASE("roi sends the rectangle and confirms it", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("text") {
    const Run run = runAt(context, server, {"roi", "cam0", "10", "20", "300", "200"});
    CHECK(run.code == 0);
    CHECK(run.err.empty());
    CHECK(run.out == "cam0: ROI set to x=10 y=20 width=300 height=200\n");
  }
  SECTION("JSON") {
    const Run run = runAt(context, server, {"--json", "roi", "cam0", "10", "20", "300", "200"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"ok":true,"camera":"cam0","roi":{"x":10,"y":20,"width":300,"height":200}})"
                     "\n");
  }
  const proto::ControlRequest request = onlyRequest(server);
  REQUIRE(request.request_case() == proto::ControlRequest::kSetRoi);
  CHECK(request.set_roi().camera() == "cam0");
  CHECK(request.set_roi().roi().x() == 10);
  CHECK(request.set_roi().roi().y() == 20);
  CHECK(request.set_roi().roi().width() == 300);
  CHECK(request.set_roi().roi().height() == 200);
}

TEST_CASE("size sends a target size or a scale", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("target size") {
    const Run run = runAt(context, server, {"size", "cam0", "640", "480"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: output size set to 640x480\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetSize);
    CHECK(request.set_size().camera() == "cam0");
    CHECK(request.set_size().width() == 640);
    CHECK(request.set_size().height() == 480);
    CHECK(request.set_size().scale() == 0.0);
  }
  SECTION("scale") {
    const Run run = runAt(context, server, {"size", "cam0", "--scale", "0.5"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: output scale set to 0.5\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetSize);
    CHECK(request.set_size().width() == 0);
    CHECK(request.set_size().height() == 0);
    CHECK(request.set_size().scale() == 0.5);
  }
  SECTION("scale, JSON") {
    const Run run = runAt(context, server, {"--json", "size", "cam0", "--scale", "0.25"});
    CHECK(run.code == 0);
    CHECK(run.out == "{\"ok\":true,\"camera\":\"cam0\",\"scale\":0.25}\n");
  }
}

TEST_CASE("mode and format send the enum values", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  SECTION("free-run with a frame rate") {
    const Run run = runAt(context, server, {"mode", "cam0", "freerun", "15"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: mode set to freerun at 15 fps\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().mode() == proto::FREERUN);
    CHECK(request.set_mode().fps() == 15.0);
  }
  SECTION("trigger, frame rate left unchanged, JSON") {
    const Run run = runAt(context, server, {"--json", "mode", "cam0", "trigger"});
    CHECK(run.code == 0);
    CHECK(run.out == "{\"ok\":true,\"camera\":\"cam0\",\"mode\":\"trigger\"}\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().mode() == proto::TRIGGER);
    CHECK(request.set_mode().fps() == 0.0);
  }
  SECTION("hardware trigger on a line, with its edge and timeout") {
    const Run run = runAt(context, server,
                          {"mode", "cam0", "hardware", "--line", "Line2", "--activation", "falling",
                           "--trigger-timeout", "30000"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: mode set to hardware on Line2 (FallingEdge)\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().mode() == proto::HARDWARE_TRIGGER);
    CHECK(request.set_mode().trigger_line() == "Line2");
    CHECK(request.set_mode().trigger_activation() == "FallingEdge");
    CHECK(request.set_mode().trigger_timeout_ms() == 30000);
  }
  SECTION("hardware trigger with the server's defaults, JSON") {
    const Run run = runAt(context, server, {"--json", "mode", "cam0", "hardware"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "{\"ok\":true,\"camera\":\"cam0\",\"mode\":\"hardware\",\"trigger_line\":\"Line1\"}\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetMode);
    CHECK(request.set_mode().trigger_line().empty());
    CHECK(request.set_mode().trigger_activation().empty());
    CHECK(request.set_mode().trigger_timeout_ms() == 0);
  }
  SECTION("format") {
    const Run run = runAt(context, server, {"format", "cam0", "bgr8"});
    CHECK(run.code == 0);
    CHECK(run.out == "cam0: pixel format set to bgr8\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kSetFormat);
    CHECK(request.set_format().camera() == "cam0");
    CHECK(request.set_format().pixel_format() == proto::BGR8);
  }
}

TEST_CASE("trigger prints the sequence number the frame will carry", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  reply.mutable_trigger()->set_sequence(4242);
  SECTION("trigger mode") {
    reply.mutable_trigger()->set_triggered(true);
    FakeServer server(context, reply);
    const Run text = runAt(context, server, {"trigger", "cam0"});
    CHECK(text.code == 0);
    CHECK(text.out == "cam0: triggered, the frame will carry sequence 4242\n");
    const Run json = runAt(context, server, {"--json", "trigger", "cam0"});
    CHECK(json.code == 0);
    CHECK(json.out == "{\"camera\":\"cam0\",\"sequence\":4242,\"triggered\":true}\n");
    const std::vector<proto::ControlRequest> requests = server.stop();
    REQUIRE(requests.size() == 2);
    REQUIRE(requests[0].request_case() == proto::ControlRequest::kTrigger);
    CHECK(requests[0].trigger().camera() == "cam0");
  }
  SECTION("free-run: says the frame is not a dedicated one") {
    reply.mutable_trigger()->set_triggered(false);
    FakeServer server(context, reply);
    const Run run = runAt(context, server, {"trigger", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "cam0: camera is in free-run, the first frame after the request will carry "
          "sequence 4242\n");
  }
}

TEST_CASE("trigger with a reply that lacks the sequence number is an error", "[cam]") {
  zmq::context_t context;
  FakeServer server(context, okReply());
  const Run run = runAt(context, server, {"trigger", "cam0"});
  CHECK(run.code == 1);
  CHECK(run.out.empty());
  CHECK_THAT(run.err, Catch::Contains("unexpected reply: no trigger sequence number"));
}

TEST_CASE("stats prints an aligned table with right-aligned numbers, or JSON", "[cam]") {
  zmq::context_t context;
  proto::ControlReply reply = okReply();
  reply.mutable_statistics()->set_subscribers(3);
  auto* s = reply.mutable_statistics()->add_cameras();
  s->set_camera("cam0");
  s->set_frames_acquired(1200);
  s->set_frames_published(1198);
  s->set_frames_dropped(2);
  s->set_acquisition_errors(0);
  s->set_reconnects(1);
  s->set_fps(29.97);
  s->set_last_sequence(1199);
  s->set_driver_incomplete_buffers(4);
  s->set_driver_missing_packets(17);
  s->set_driver_resent_packets(9);
  s->set_frames_skipped_stale(3);
  FakeServer server(context, reply);

  SECTION("all cameras, text") {
    const Run run = runAt(context, server, {"stats"});
    CHECK(run.code == 0);
    CHECK(run.out ==
          "CAMERA  ACQUIRED  PUBLISHED  DROPPED  ERRORS  RECONNECTS   FPS  LAST SEQ\n"
          "cam0        1200       1198        2       0           1  30.0      1199\n"
          "\n"
          "CAMERA  INCOMPLETE  MISSING PKTS  RESENT PKTS  UNDERRUNS  SEQ GAPS  SKIPPED OLD\n"
          "cam0             4            17            9          0         0            3\n"
          "subscribers: 3\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kStatistics);
    CHECK(request.statistics().camera().empty());
  }
  SECTION("one camera, JSON") {
    const Run run = runAt(context, server, {"--json", "stats", "cam0"});
    CHECK(run.code == 0);
    CHECK(run.out == R"({"subscribers":3,"cameras":[{"camera":"cam0","frames_acquired":1200,)"
                     R"("frames_published":1198,"frames_dropped":2,"acquisition_errors":0,)"
                     R"("reconnects":1,"fps":29.97,"last_sequence":1199,)"
                     R"("driver_incomplete_buffers":4,"driver_missing_packets":17,)"
                     R"("driver_resent_packets":9,"driver_underruns":0,"driver_sequence_gaps":0,)"
                     R"("frames_skipped_stale":3}]})"
                     "\n");
    const proto::ControlRequest request = onlyRequest(server);
    REQUIRE(request.request_case() == proto::ControlRequest::kStatistics);
    CHECK(request.statistics().camera() == "cam0");
  }
}
