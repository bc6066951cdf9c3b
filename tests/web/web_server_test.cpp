// picksight-web against a real video server and vision app: the camera list,
// images and streams, results as events, camera actions, commands, limits.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>
#include <zmq.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/common/angles.hpp"
#include "picksight/transport/control_client.hpp"
#include "results.pb.h"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;
using e2e::VisionProcess;
using nlohmann::json;
using transport::ControlClient;
using transport::FrameSubscriber;

// The parts of a multipart/x-mixed-replace body as they arrive.
class MjpegParser {
 public:
  struct Part {
    uint64_t sequence = 0;
    std::string jpeg;
  };
  void add(const char* data, size_t size) { buffer_.append(data, size); }
  std::optional<Part> next() {
    const size_t start = buffer_.find("--picksightframe\r\n");
    if (start == std::string::npos) return std::nullopt;
    const size_t end_of_head = buffer_.find("\r\n\r\n", start);
    if (end_of_head == std::string::npos) return std::nullopt;
    const std::string head = buffer_.substr(start, end_of_head - start);
    const size_t length = std::stoul(header(head, "Content-Length"));
    if (buffer_.size() < end_of_head + 4 + length) return std::nullopt;
    Part part;
    part.sequence = std::stoull(header(head, "X-Frame-Sequence"));
    part.jpeg = buffer_.substr(end_of_head + 4, length);
    buffer_.erase(0, end_of_head + 4 + length);
    return part;
  }

 private:
  static std::string header(const std::string& head, const std::string& name) {
    const size_t at = head.find(name + ": ");
    REQUIRE(at != std::string::npos);
    return head.substr(at + name.size() + 2, head.find("\r\n", at) - at - name.size() - 2);
  }
  std::string buffer_;
};

// Reads `count` parts of /stream/<camera>.mjpg; their sequences.
std::vector<uint64_t> streamParts(const WebProcess& web, const std::string& camera, size_t count) {
  auto client = web.client();
  MjpegParser parser;
  std::vector<uint64_t> sequences;
  std::string content_type;
  client.Get(("/stream/" + camera + ".mjpg").c_str(),
             [&](const httplib::Response& res) {
               content_type = res.get_header_value("Content-Type");
               return res.status == 200;
             },
             [&](const char* data, size_t size) {
               parser.add(data, size);
               while (auto part = parser.next()) {
                 const cv::Mat image = picksight::codecs::imdecode(
                     std::vector<unsigned char>(part->jpeg.begin(), part->jpeg.end()),
                     cv::IMREAD_UNCHANGED);
                 CHECK(!image.empty());
                 sequences.push_back(part->sequence);
               }
               return sequences.size() < count;
             });
  CHECK(content_type == "multipart/x-mixed-replace; boundary=picksightframe");
  return sequences;
}

json getJson(const WebProcess& web, const std::string& path, int* status = nullptr) {
  auto res = web.client().Get(path.c_str());
  REQUIRE(res);
  if (status) *status = res->status;
  return json::parse(res->body, nullptr, false);
}

httplib::Result postJson(const WebProcess& web, const std::string& path, const std::string& body) {
  // As the page posts: JSON with the header a cross-site form cannot send.
  return web.client().Post(path.c_str(), {{"X-PickSight", "1"}}, body, "application/json");
}

bool listsCamera(const WebProcess& web, const std::string& camera) {
  const json cameras = getJson(web, "/api/cameras");
  if (!cameras.is_array()) return false;
  for (const auto& c : cameras)
    if (c.value("name", "") == camera) return true;
  return false;
}

// The first camera of /api/cameras, once the poller has described it.
json firstCamera(const WebProcess& web) {
  json camera;
  REQUIRE(pollUntil([&] {
    const json cameras = getJson(web, "/api/cameras");
    if (!cameras.is_array() || cameras.empty() || cameras[0].value("sensor_width", 0) == 0)
      return false;
    camera = cameras[0];
    return true;
  }));
  return camera;
}

}  // namespace

TEST_CASE("the camera list shows the video server's camera with its geometry", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--fps", "20"});
  WebProcess web(videoServerArgs(server));
  const json camera = firstCamera(web);
  CHECK(camera["name"] == "cam0");
  CHECK(camera["mode"] == "freerun");
  CHECK(camera["sensor_width"] == 640);
  CHECK(camera["sensor_height"] == 480);
  CHECK(camera["roi"]["width"] == 640);
  CHECK(camera["simulated_robot"].is_boolean());
  REQUIRE(pollUntil([&] { return getJson(web, "/api/cameras")[0].value("frames", 0) > 0; }));
  int status = 0;
  getJson(web, "/api/cameras/nope/features", &status);
  CHECK(status == 404);
}

TEST_CASE("a snapshot is the published frame pixel for pixel", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=4", "--mode", "trigger"});
  WebProcess web(videoServerArgs(server));
  zmq::context_t context;
  FrameSubscriber subscriber(context, server.frames, "cam0", 16);
  e2e::waitForSubscription(server, subscriber);
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  ControlClient control(context, server.control);
  proto::ControlRequest trigger;
  trigger.mutable_trigger()->set_camera("cam0");
  bool compared = false;
  // The web server's own subscription may start after a trigger or two:
  // trigger until it shows a frame we also received.
  for (int attempt = 0; attempt < 20 && !compared; ++attempt) {
    REQUIRE(control.call(trigger));
    auto frame = subscriber.receive(5s);
    REQUIRE(frame);
    std::optional<httplib::Response> png;
    const std::string wanted = std::to_string(frame->info.sequence);
    pollUntil(
        [&] {
          auto res = web.client().Get("/snapshot/cam0.png");
          if (!res || res->status != 200 || res->get_header_value("X-Frame-Sequence") != wanted)
            return false;
          png = *res;
          return true;
        },
        2s);
    if (!png) continue;
    CHECK(png->get_header_value("Content-Type") == "image/png");
    CHECK(png->get_header_value("X-Frame-Timestamp-Ns") ==
          std::to_string(frame->info.host_timestamp_ns));
    const cv::Mat decoded = picksight::codecs::imdecode(
        std::vector<unsigned char>(png->body.begin(), png->body.end()), cv::IMREAD_UNCHANGED);
    REQUIRE(decoded.size() == frame->image.size());
    REQUIRE(decoded.type() == frame->image.type());
    CHECK(cv::norm(decoded, frame->image, cv::NORM_INF) == 0);
    compared = true;
  }
  CHECK(compared);
  auto jpg = web.client().Get("/frame/cam0.jpg");
  REQUIRE(jpg);
  CHECK(jpg->status == 200);
  CHECK(jpg->get_header_value("Content-Type") == "image/jpeg");
  CHECK(!jpg->get_header_value("X-Frame-Sequence").empty());
  auto missing = web.client().Get("/snapshot/nocamera.png");
  REQUIRE(missing);
  CHECK(missing->status == 404);
}

TEST_CASE("the MJPEG stream delivers frames with increasing sequences", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--fps", "20"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  const auto sequences = streamParts(web, "cam0", 3);
  REQUIRE(sequences.size() >= 3);
  for (size_t i = 1; i < sequences.size(); ++i) CHECK(sequences[i] > sequences[i - 1]);
}

TEST_CASE("a stalled MJPEG reader delays neither another viewer nor snapshots", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=1280,height=960,parts=6", "--fps", "30"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  // A raw client that asks for the stream with a tiny receive buffer and
  // never reads a byte.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  const int small = 4096;
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(web.port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0);
  const std::string request =
      "GET /stream/cam0.mjpg HTTP/1.1\r\nHost: 127.0.0.1\r\n" + web.cookieLine() + "\r\n";
  REQUIRE(::send(fd, request.data(), request.size(), 0) == static_cast<ssize_t>(request.size()));
  // The stalled stream is counted as a viewer once the server serves it.
  REQUIRE(pollUntil([&] {
    auto res = web.client().Get("/metrics");
    return res && res->body.find("picksight_web_viewers{camera=\"cam0\"} 1") != std::string::npos;
  }));
  const auto sequences = streamParts(web, "cam0", 5);
  CHECK(sequences.size() >= 5);
  for (int i = 0; i < 3; ++i) {
    auto png = web.client().Get("/snapshot/cam0.png");
    REQUIRE(png);
    CHECK(png->status == 200);
  }
  ::close(fd);
}

TEST_CASE("events carry results published on a vision app's results stream", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  zmq::context_t context;
  zmq::socket_t publisher(context, zmq::socket_type::pub);
  publisher.bind("tcp://127.0.0.1:*");
  const std::string endpoint = publisher.get(zmq::sockopt::last_endpoint);
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--vision-app", "cell1," + endpoint + ",127.0.0.1:9"});
  WebProcess web(args);

  int status = 0;
  getJson(web, "/api/results/cell1/latest", &status);
  CHECK(status == 404);

  std::atomic<bool> received{false};
  std::atomic<bool> done{false};
  std::string event_data;
  std::thread reader([&] {
    auto client = web.client();
    std::string buffer;
    client.Get("/events", [&](const char* data, size_t size) {
      buffer.append(data, size);
      const size_t at = buffer.find("event: result\ndata: ");
      if (at != std::string::npos) {
        const size_t end = buffer.find('\n', at + 20);
        if (end != std::string::npos) {
          event_data = buffer.substr(at + 20, end - at - 20);
          received = true;
          return false;
        }
      }
      return !done;
    });
  });
  proto::VisionResult result;
  result.set_request_id(7);
  result.set_request("LOCATE");
  result.set_request_line("LOCATE 1");
  result.set_reply("OK 1 10 20 30");
  result.set_elapsed_ms(12.5);
  result.set_camera("cam0");
  result.set_frame_sequence(42);
  result.mutable_binarize()->set_method("fixed");
  result.mutable_binarize()->set_threshold(100);
  result.mutable_binarize()->set_dark_parts(true);
  auto* part = result.add_parts();
  part->set_type(1);
  part->mutable_position()->set_x(100.5);
  const std::string bytes = result.SerializeAsString();
  // PUB drops what it sends before the web server's subscription arrives:
  // send until it shows.
  const bool arrived = pollUntil([&] {
    publisher.send(zmq::buffer(std::string("cell1")), zmq::send_flags::sndmore);
    publisher.send(zmq::buffer(bytes), zmq::send_flags::none);
    return received.load();
  });
  done = true;
  reader.join();
  REQUIRE(arrived);
  const json event = json::parse(event_data);
  CHECK(event["app"] == "cell1");     // filled in from the topic
  CHECK(event["request_id"] == "7");  // 64-bit integers are strings in the mapping
  CHECK(event["request_line"] == "LOCATE 1");
  CHECK(event["parts"][0]["position"]["x"] == 100.5);

  const json latest = getJson(web, "/api/results/cell1/latest", &status);
  CHECK(status == 200);
  CHECK(latest["frame_sequence"] == "42");
  const json apps = getJson(web, "/api/apps");
  REQUIRE(apps.size() == 1);
  CHECK(apps[0]["name"] == "cell1");
  CHECK(apps[0]["camera"] == "cam0");
  CHECK(apps[0]["connected"] == true);
  CHECK(apps[0]["last_result_id"] == 7);
  // The app's camera binarized with the result's settings.
  REQUIRE(pollUntil([&] {
    auto png = web.client().Get("/snapshot/cam0.png");
    return png && png->status == 200;
  }));
  auto binary = web.client().Get("/binary/cell1.png");
  REQUIRE(binary);
  CHECK(binary->status == 200);
  const cv::Mat mask = picksight::codecs::imdecode(
      std::vector<unsigned char>(binary->body.begin(), binary->body.end()), cv::IMREAD_UNCHANGED);
  REQUIRE(mask.type() == CV_8UC1);
  CHECK(mask.size() == cv::Size(320, 240));
  CHECK(cv::countNonZero((mask != 0) & (mask != 255)) == 0);
  auto metrics = web.client().Get("/metrics");
  REQUIRE(metrics);
  CHECK(metrics->body.find("picksight_vision_results_total{app=\"cell1\",request=\"LOCATE\"}") !=
        std::string::npos);
  CHECK(metrics->body.find("picksight_vision_request_seconds_bucket{app=\"cell1\",request="
                           "\"LOCATE\",le=\"+Inf\"}") != std::string::npos);
}

TEST_CASE("a camera ROI posted to the web reaches the camera", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=640,height=480", "--fps", "10"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  auto res = postJson(web, "/api/cameras/cam0/roi", R"({"x":32,"y":16,"width":320,"height":240})");
  REQUIRE(res);
  CHECK(res->status == 200);
  CHECK(json::parse(res->body)["ok"] == true);
  zmq::context_t context;
  ControlClient control(context, server.control);
  proto::ControlRequest describe;
  describe.mutable_describe_camera()->set_camera("cam0");
  auto reply = control.call(describe);
  REQUIRE(reply);
  CHECK(reply->describe_camera().roi().x() == 32);
  CHECK(reply->describe_camera().roi().y() == 16);
  CHECK(reply->describe_camera().roi().width() == 320);
  CHECK(reply->describe_camera().roi().height() == 240);
  // The camera list follows.
  CHECK(pollUntil([&] { return getJson(web, "/api/cameras")[0]["roi"]["x"] == 32; }));

  // The video server's refusal comes back as a client error with its message.
  res = postJson(web, "/api/cameras/cam0/roi", R"({"x":600,"y":0,"width":320,"height":240})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK(!json::parse(res->body)["error"].get<std::string>().empty());
  res = postJson(web, "/api/cameras/cam0/mode", R"({"mode":"sideways"})");
  REQUIRE(res);
  CHECK(res->status == 400);
  res = postJson(web, "/api/cameras/cam0/trigger", "");
  REQUIRE(res);
  CHECK(res->status == 200);
  res = postJson(web, "/api/cameras/nocam/roi", "{}");
  REQUIRE(res);
  CHECK(res->status == 404);
}

TEST_CASE("the hardware mode reaches the video server and its refusal reaches the client",
          "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  const auto error = [](const httplib::Result& res) {
    return json::parse(res->body)["error"].get<std::string>();
  };
  // The synthetic camera has no trigger input: the camera's own message.
  auto res = postJson(web, "/api/cameras/cam0/mode",
                      R"({"mode":"hardware","line":"Line2","activation":"RisingEdge",)"
                      R"("timeout_ms":2000})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK_THAT(error(res), Catch::Contains("has no hardware trigger input"));
  CHECK_THAT(error(res), Catch::Contains("cam0"));
  // The settings travel as given: the video server judges the edge's name.
  res = postJson(web, "/api/cameras/cam0/mode", R"({"mode":"hardware","activation":"Sideways"})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK_THAT(error(res), Catch::Contains("trigger_activation must be one of"));
  CHECK_THAT(error(res), Catch::Contains("'Sideways'"));
  // Refused here, before anything is sent, naming the field.
  res = postJson(web, "/api/cameras/cam0/mode", R"({"mode":"trigger","line":"Line1"})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK_THAT(error(res), Catch::Contains("\"line\""));
  // Nothing changed: the camera still runs free.
  CHECK(getJson(web, "/api/cameras")[0]["mode"] == "freerun");
}

TEST_CASE("bad JSON is refused with a 400 that names the problem", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  WebProcess web(videoServerArgs(server));
  REQUIRE(pollUntil([&] { return listsCamera(web, "cam0"); }));
  auto res = postJson(web, "/api/cameras/cam0/roi", R"({"x": 1,)");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK(json::parse(res->body)["error"].get<std::string>().find("JSON") != std::string::npos);
  res = postJson(web, "/api/cameras/cam0/roi", R"({"x": "left"})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK(json::parse(res->body)["error"].get<std::string>().find("\"x\"") != std::string::npos);
  res = postJson(web, "/api/cameras/cam0/roi", "[1, 2]");
  REQUIRE(res);
  CHECK(res->status == 400);
  // Bodies beyond the limit are refused before they are read.
  res = postJson(web, "/api/cameras/cam0/roi", std::string(100 * 1024, ' '));
  REQUIRE(res);
  CHECK(res->status == 413);
}

TEST_CASE("a command line goes to the vision app and its reply comes back", "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3", "--mode", "trigger"});
  VisionProcess vision(server);
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:" + std::to_string(vision.robot_port), "--vision-app",
                  "gone,none,127.0.0.1:1"});
  auto res = postJson(web, "/api/apps/cam0/command", R"({"line":"STATUS"})");
  REQUIRE(res);
  CHECK(res->status == 200);
  CHECK(json::parse(res->body)["reply"].get<std::string>().rfind("OK", 0) == 0);
  res = postJson(web, "/api/apps/cam0/command", R"({"line":"LOCATE 1"})");
  REQUIRE(res);
  CHECK(res->status == 200);
  // The vision app's LOCATE, as it answers its own robot port: the same
  // parts at the same poses (another frame: within noise, in any order).
  const auto relayed = e2e::parseLocateReply(json::parse(res->body)["reply"].get<std::string>());
  auto direct = vision.connect().request("LOCATE 1", 10s);
  REQUIRE(direct);
  const auto own = e2e::parseLocateReply(*direct);
  REQUIRE(!own.empty());
  REQUIRE(relayed.size() == own.size());
  for (const auto& p : relayed) {
    INFO("relayed " << p.x << " " << p.y << " " << p.rz << "; own: " << *direct);
    CHECK(std::any_of(own.begin(), own.end(), [&](const e2e::Pose& q) {
      return std::hypot(p.x - q.x, p.y - q.y) < 0.5 && angleDiffDeg(p.rz, q.rz) < 1;
    }));
  }

  res = postJson(web, "/api/apps/cam0/command", R"({"line":"STATUS\nLEARN 1"})");
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK_THAT(json::parse(res->body).value("error", ""), Catch::Contains("CR or LF"));
  res = postJson(web, "/api/apps/cam0/command", json{{"line", std::string(300, 'A')}}.dump());
  REQUIRE(res);
  CHECK(res->status == 400);
  CHECK_THAT(json::parse(res->body).value("error", ""), Catch::Contains("longer than"));
  res = postJson(web, "/api/apps/nobody/command", R"({"line":"STATUS"})");
  REQUIRE(res);
  CHECK(res->status == 404);
  CHECK_THAT(json::parse(res->body).value("error", ""), Catch::Contains("'nobody'"));
  res = postJson(web, "/api/apps/gone/command", R"({"line":"STATUS"})");
  REQUIRE(res);
  CHECK(res->status == 502);
  CHECK(json::parse(res->body).contains("error"));
}

TEST_CASE("the first command after the app's idle timeout is executed and not answered ERROR 16",
          "[web]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--mode", "trigger"});
  VisionProcess vision(server, "cam0", "", {"--robot-idle-timeout", "1"});
  WebProcess web({"--video-server", server.frames + "," + server.control, "--vision-app",
                  "cam0,none,127.0.0.1:" + std::to_string(vision.robot_port)});
  const auto reply = [&](const std::string& line) {
    auto res = postJson(web, "/api/apps/cam0/command", json{{"line", line}}.dump());
    REQUIRE(res);
    REQUIRE(res->status == 200);
    return json::parse(res->body)["reply"].get<std::string>();
  };
  CHECK(reply("STATUS").rfind("OK", 0) == 0);
  for (int round = 0; round < 2; ++round) {
    // Past the app's idle timeout: it has sent ERROR 16 on the kept
    // connection and closed it.
    std::this_thread::sleep_for(1800ms);
    const std::string learned = reply("LEARN 4");
    CAPTURE(learned);
    CHECK(learned.rfind("OK 4 ", 0) == 0);
  }
  auto robot = vision.connect();
  CHECK(robot.request("MODELS", 5s)->rfind("OK 1", 0) == 0);
}

TEST_CASE("peers outside the allow-list get 403", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "10"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--allow", "10.0.0.0/8"});
  WebProcess web(args);
  for (const char* path : {"/", "/api/cameras", "/snapshot/cam0.png", "/metrics"}) {
    auto res = web.client().Get(path);
    REQUIRE(res);
    CHECK(res->status == 403);
  }
  auto res = postJson(web, "/api/cameras/cam0/trigger", "");
  REQUIRE(res);
  CHECK(res->status == 403);
}

TEST_CASE("metrics count the camera's frames", "[web]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "20"});
  WebProcess web(videoServerArgs(server));
  CHECK(pollUntil([&] {
    auto res = web.client().Get("/metrics");
    if (!res || res->status != 200) return false;
    const std::string key = "picksight_camera_frames_total{camera=\"cam0\"} ";
    const size_t at = res->body.find(key);
    return at != std::string::npos && res->body[at + key.size()] != '0';
  }));
  auto res = web.client().Get("/metrics");
  REQUIRE(res);
  CHECK(res->get_header_value("Content-Type").rfind("text/plain", 0) == 0);
  for (const char* name :
       {"picksight_camera_drops_total{camera=\"cam0\"}", "picksight_camera_fps{camera=\"cam0\"}",
        "picksight_web_viewers{camera=\"cam0\"}",
        "picksight_web_jpeg_encode_seconds_total{camera=\"cam0\"}"})
    CHECK(res->body.find(name) != std::string::npos);
  // Nobody watched: no JPEG was made. A snapshot is a PNG and makes none either.
  REQUIRE(pollUntil([&] {
    auto png = web.client().Get("/snapshot/cam0.png");
    return png && png->status == 200;
  }));
  res = web.client().Get("/metrics");
  REQUIRE(res);
  CHECK(res->body.find("picksight_web_jpeg_encode_seconds_total{camera=\"cam0\"} 0.000000\n") !=
        std::string::npos);
  auto jpg = web.client().Get("/frame/cam0.jpg");
  REQUIRE(jpg);
  REQUIRE(jpg->status == 200);
  res = web.client().Get("/metrics");
  REQUIRE(res);
  CHECK(res->body.find("picksight_web_jpeg_encode_seconds_total{camera=\"cam0\"} 0.000000\n") ==
        std::string::npos);
}

TEST_CASE("the page and its files come from the assets directory", "[web]") {
  test::TempDir assets;
  assets.write("index.html", "<!doctype html><title>PickSight</title>");
  assets.write("app.js", "console.log(1);");
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--assets", assets.path().string()});
  WebProcess web(args);
  auto page = web.client().Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->get_header_value("Content-Type").rfind("text/html", 0) == 0);
  CHECK(page->body.find("PickSight") != std::string::npos);
  auto script = web.client().Get("/static/app.js");
  REQUIRE(script);
  CHECK(script->status == 200);
  CHECK(script->get_header_value("Content-Type").rfind("text/javascript", 0) == 0);
  for (const char* path : {"/static/missing.js", "/static/../web.yaml", "/static/%2e%2e/x"}) {
    auto res = web.client().Get(path);
    REQUIRE(res);
    CHECK((res->status == 404 || res->status == 400));
  }
}

}  // namespace picksight::webtest
