// The results stream, WHY and LOCATE ALL end to end: a real video server and
// vision app, a real ZeroMQ subscriber, scenes drawn with parts of known
// size, hand and type.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "cell_fixture.hpp"
#include "picksight/common/text.hpp"
#include "results.pb.h"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
constexpr int kShift = 4;  // sub-pixel bits for OpenCV drawing
constexpr int kSuper = 4;  // supersampling, then averaged down: anti-aliased edges

// An L with legs of different lengths and widths (chiral: its mirror image
// is another part), about its own origin, pixels.
const std::vector<cv::Point2d> kEll{{0, 0}, {120, 0}, {120, 30}, {35, 30}, {35, 80}, {0, 80}};

struct Canvas {
  cv::Mat big{480 * kSuper, 640 * kSuper, CV_8UC1, cv::Scalar(200)};

  static cv::Point fine(cv::Point2d p) { return supersampledPoint(p, kSuper, kShift); }
  // The L scaled by `scale`, mirrored (x -> -x) or not, turned by `deg`
  // (image axes) and placed with its box centre at `at`.
  void ell(cv::Point2d at, double deg, double scale = 1.0, bool mirrored = false) {
    const double a = deg * M_PI / 180.0;
    std::vector<cv::Point> poly;
    for (const auto& p : kEll) {
      const double x = (mirrored ? -(p.x - 60) : p.x - 60) * scale;
      const double y = (p.y - 40) * scale;
      poly.push_back(fine(
          {at.x + std::cos(a) * x - std::sin(a) * y, at.y + std::sin(a) * x + std::cos(a) * y}));
    }
    cv::fillPoly(big, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(40), cv::LINE_8,
                 kShift);
  }
  void disc(cv::Point2d centre, double radius) {
    cv::circle(big, fine(centre), static_cast<int>(std::lround(radius * kSuper * (1 << kShift))),
               cv::Scalar(40), cv::FILLED, cv::LINE_8, kShift);
  }
  cv::Mat image() const {
    cv::Mat out;
    cv::resize(big, out, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    return out;
  }
};

// The file camera's image, empty at first.
struct Scene : SceneFile {
  Scene() : SceneFile(Canvas().image()) {}
};

// A file camera in trigger mode, a vision app on it, a robot connected.
struct FileCell {
  Scene scene;
  VideoServerProcess server{{"--source", "cam0=file:" + scene.path, "--mode", "trigger"}};
  VisionProcess vision{server};
  LineClient robot = vision.connect();
};

std::string ask(LineClient& robot, const std::string& request) {
  auto reply = robot.request(request, 20s);
  REQUIRE(reply);
  return *reply;
}

// A SUB socket on the vision app's results.
struct Results {
  zmq::context_t context;
  zmq::socket_t socket{context, zmq::socket_type::sub};
  explicit Results(const std::string& endpoint, const std::string& topic = "cam0") {
    REQUIRE(!endpoint.empty());
    socket.set(zmq::sockopt::subscribe, topic);
    socket.set(zmq::sockopt::linger, 0);
    socket.connect(endpoint);
  }
  std::optional<proto::VisionResult> next(std::chrono::milliseconds timeout) {
    socket.set(zmq::sockopt::rcvtimeo, static_cast<int>(timeout.count()));
    zmq::message_t topic, body;
    if (!socket.recv(topic)) return std::nullopt;
    REQUIRE(topic.more());
    REQUIRE(socket.recv(body));
    CHECK(!body.more());
    proto::VisionResult r;
    REQUIRE(r.ParseFromArray(body.data(), static_cast<int>(body.size())));
    CHECK(r.app() == topic.to_string());
    return r;
  }
  // Sends `line` until its result comes (a SUB joins a moment after it
  // connects), then drains what is on its way: the stream is in step.
  void join(LineClient& robot, const std::string& line) {
    for (int i = 0; i < 100; ++i) {
      ask(robot, line);
      if (next(300ms)) {
        while (next(300ms)) {
        }
        return;
      }
    }
    FAIL("no result on " << line);
  }
  // The result of the request just answered.
  proto::VisionResult after(const std::string& request) {
    auto r = next(10s);
    REQUIRE(r);
    CHECK(r->request() == request);
    return *r;
  }
};

// Trains type 1 (the L) and type 2 (a disc) from scenes of one part each.
void teach(LineClient& robot, const Scene& scene) {
  Canvas ell;
  ell.ell({320, 240}, 10);
  scene.show(ell.image());
  REQUIRE(ask(robot, "LEARN 1 ell").rfind("OK", 0) == 0);
  Canvas disc;
  disc.disc({320, 240}, 25);
  scene.show(disc.image());
  REQUIRE(ask(robot, "LEARN 2 disc").rfind("OK", 0) == 0);
}

// One L, a small L (0.8 times: the area test), a mirrored L and a disc.
cv::Mat mixedScene() {
  Canvas c;
  c.ell({150, 130}, 30);
  c.ell({470, 130}, -20, 0.8);
  c.ell({160, 350}, 75, 1.0, true);
  c.disc({470, 350}, 25);
  return c.image();
}
}  // namespace

TEST_CASE("a LOCATE's result reaches a subscriber with the reply's parts and outlines",
          "[e2e][results]") {
  FileCell cell;
  const Scene& scene = cell.scene;
  VisionProcess& vision = cell.vision;
  LineClient& robot = cell.robot;
  REQUIRE(vision.results_endpoint.rfind("tcp://127.0.0.1:", 0) == 0);
  Results results(vision.results_endpoint);
  results.join(robot, "BLOBS");
  teach(robot, scene);
  const auto learned = results.after("LEARN");
  CHECK(learned.regions_size() == 1);  // LEARN publishes its frame's regions
  results.after("LEARN");

  Canvas two;
  two.ell({170, 150}, 30);
  two.ell({430, 320}, 200);
  scene.show(two.image());
  const std::string reply = ask(robot, "LOCATE 1");
  const auto poses = imagePoses(reply);
  REQUIRE(poses.size() == 2);
  const auto r = results.after("LOCATE");
  CHECK(r.reply() == reply);
  CHECK(r.request_line() == "LOCATE 1");
  CHECK(r.client().rfind("robot 127.0.0.1:", 0) == 0);
  CHECK(r.asked_type() == 1);
  CHECK(r.camera() == "cam0");
  CHECK(r.frame_width() == 640);
  CHECK(r.reply_frame() == "pixels");
  CHECK(r.elapsed_ms() > 0);
  CHECK(r.regions_size() == 2);
  REQUIRE(r.parts_size() == 2);
  for (size_t i = 0; i < poses.size(); ++i) {
    const auto& part = r.parts(static_cast<int>(i));
    INFO("part " << i);
    CHECK(part.type() == 1);
    CHECK(part.name() == "ell");
    CHECK(part.offered());
    CHECK(part.score() > 0.8);
    // Replies carry 3 decimals.
    CHECK(part.position().x() == Approx(poses[i].x).margin(0.001));
    CHECK(part.position().y() == Approx(poses[i].y).margin(0.001));
    CHECK(part.reply_pose().x() == Approx(poses[i].x).margin(0.001));
    // The model's outline at the pose: six corners about the part.
    REQUIRE(part.outline_size() == 1);
    const auto& outline = part.outline(0);
    CHECK(outline.points_size() >= 6);
    for (const auto& p : outline.points())
      CHECK(std::hypot(p.x() - part.position().x(), p.y() - part.position().y()) < 95);
  }
  CHECK(r.rejections_size() == 0);
  CHECK(r.why() == "OK 0 every region reported");
  CHECK(ask(robot, "WHY") == "OK 0 every region reported");
}

TEST_CASE("WHY and the rejections name the test a region failed", "[e2e][results]") {
  FileCell cell;
  const Scene& scene = cell.scene;
  VisionProcess& vision = cell.vision;
  LineClient& robot = cell.robot;
  CHECK(ask(robot, "WHY") == "OK 0 no LOCATE yet");
  Results results(vision.results_endpoint);
  results.join(robot, "BLOBS");
  teach(robot, scene);
  results.after("LEARN");
  results.after("LEARN");
  scene.show(mixedScene());

  const std::string reply = ask(robot, "LOCATE 1");
  const auto poses = imagePoses(reply);
  REQUIRE(poses.size() == 1);
  CHECK(poses[0].x == Approx(150).margin(25));  // the L's centroid is off its box centre
  const auto r = results.after("LOCATE");
  REQUIRE(r.regions_size() == 4);
  REQUIRE(r.rejections_size() == 3);
  const std::string why = ask(robot, "WHY");
  INFO("WHY: " << why);
  CHECK(why == r.why());
  CHECK(why.rfind("OK 3 region ", 0) == 0);
  bool scale = false, mirror = false, other = false;
  for (const auto& rejection : r.rejections()) {
    const auto& region = r.regions(rejection.region());
    INFO(rejection.text());
    CHECK(why.find(rejection.text()) != std::string::npos);
    if (region.centroid().x() > 400 && region.centroid().y() < 240) {
      // The small L: the L at 0.8x, outside the sizes the model's area
      // tolerance allows.
      scale = rejection.test() == "scale";
      CHECK(rejection.nearest_type() == 1);
      CHECK(rejection.measured() == Approx(0.8).margin(0.01));
      CHECK(rejection.measured() < rejection.low());
      CHECK(rejection.low() < rejection.high());
      CHECK(rejection.text().find(" scaled 0.80x outside ") != std::string::npos);
    } else if (region.centroid().x() < 320) {
      mirror = rejection.test() == "mirror";
      CHECK(rejection.nearest_type() == 1);
      CHECK(rejection.text().find(" mirror of type 1") != std::string::npos);
    } else {
      other = rejection.test() == "other type";
      CHECK(rejection.nearest_type() == 2);
      CHECK(rejection.nearest_name() == "disc");
    }
  }
  CHECK(scale);
  CHECK(mirror);
  CHECK(other);
  // WHY is per connection: another robot has not located yet.
  auto other_robot = vision.connect();
  CHECK(ask(other_robot, "WHY") == "OK 0 no LOCATE yet");
}

TEST_CASE("LOCATE ALL labels each part with its type in one pass", "[e2e][results]") {
  FileCell cell;
  const Scene& scene = cell.scene;
  LineClient& robot = cell.robot;
  teach(robot, scene);
  scene.show(mixedScene());
  const std::string reply = ask(robot, "LOCATE ALL");
  INFO(reply);
  const auto fields = splitFields(reply, " ");
  REQUIRE(fields.size() == 2 + 2 * 4);
  CHECK(fields[0] == "OK");
  CHECK(fields[1] == "2");
  for (size_t i = 0; i < 2; ++i) {
    const int type = static_cast<int>(parseInt(fields[2 + 4 * i]).value_or(-9));
    const double x = parseDouble(fields[3 + 4 * i]).value_or(0);
    const double y = -parseDouble(fields[4 + 4 * i]).value_or(0);  // the reply's y is up
    if (type == 1) {
      CHECK(x == Approx(150).margin(25));  // the L's centroid is off its box centre
      CHECK(y == Approx(130).margin(25));
    } else {
      CHECK(type == 2);
      CHECK(x == Approx(470).margin(0.5));
      CHECK(y == Approx(350).margin(0.5));
    }
  }
  CHECK(fields[2] != fields[6]);
  CHECK(ask(robot, "LOCATE all").rfind("OK 2 ", 0) == 0);
  const std::string usage = ask(robot, "LOCATE every");
  CHECK(usage.rfind("ERROR 11 ", 0) == 0);
}

TEST_CASE("a subscriber that never reads does not hold LOCATE back", "[e2e][results]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=12,seed=5", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  // Subscribed with the smallest queue, and never read.
  zmq::context_t context;
  zmq::socket_t stalled(context, zmq::socket_type::sub);
  stalled.set(zmq::sockopt::rcvhwm, 1);
  stalled.set(zmq::sockopt::rcvbuf, 4096);
  stalled.set(zmq::sockopt::linger, 0);
  stalled.set(zmq::sockopt::subscribe, "");
  stalled.connect(vision.results_endpoint);
  int answered = 0;
  for (int i = 0; i < 200; ++i) {
    auto reply = robot.request("LOCATE 1", 20s);
    REQUIRE(reply);
    if (reply->rfind("OK ", 0) == 0) ++answered;
  }
  CHECK(answered == 200);
  CHECK(ask(robot, "PING") == "OK");
}

TEST_CASE("results-bind none publishes nothing and LOCATE works", "[e2e][results]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3", "--mode", "trigger"});
  VisionProcess vision(server, "cam0", "", {"--results-bind", "none"});
  CHECK(vision.results_endpoint.empty());
  auto robot = vision.connect();
  CHECK(parseLocateReply(ask(robot, "LOCATE 1")).size() == 3);
  CHECK(ask(robot, "WHY") == "OK 0 every region reported");
}

TEST_CASE("the results topic is the vision app's name", "[e2e][results]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3", "--mode", "trigger"});
  VisionProcess vision(server, "cam0", "", {"--name", "cell7"});
  auto robot = vision.connect();
  Results results(vision.results_endpoint, "cell7");
  results.join(robot, "LOCATE 1");
  ask(robot, "LOCATE 1");
  const auto r = results.after("LOCATE");
  CHECK(r.app() == "cell7");
  CHECK(r.parts_size() == 3);
  CHECK(r.request_id() > 1);
}

TEST_CASE("a part with no free grasp shows its blocked finger and the region under it",
          "[e2e][results]") {
  FileCell cell;
  const Scene& scene = cell.scene;
  VisionProcess& vision = cell.vision;
  LineClient& robot = cell.robot;
  Canvas ell;
  ell.ell({320, 260}, 10);
  scene.show(ell.image());
  REQUIRE(ask(robot, "LEARN 1 ell").rfind("OK", 0) == 0);
  // No calibration: vision units are pixels, y up. One finger 60 px above
  // the part's centroid (about (308.4, 245.9) in the image).
  REQUIRE(ask(robot, "GRASP 1 ADD 0 0 0") == "OK 1");
  REQUIRE(ask(robot, "GRIPPER 1 FINGER 0 60 20 20") == "OK 1");
  REQUIRE(parseLocateReply(ask(robot, "LOCATE 1")).size() == 1);  // nothing in the way yet
  Results results(vision.results_endpoint);
  results.join(robot, "LOCATE 1");
  ell.disc({308.4, 185.9}, 12);
  scene.show(ell.image());
  CHECK(ask(robot, "LOCATE 1") == "OK 0");
  const auto r = results.after("LOCATE");
  REQUIRE(r.parts_size() == 1);
  REQUIRE(r.regions_size() == 2);
  const auto& part = r.parts(0);
  CHECK_FALSE(part.offered());
  CHECK(part.grasp_style() == -1);
  REQUIRE(part.fingers_size() == 1);
  const auto& finger = part.fingers(0);
  CHECK(finger.blocked());
  CHECK(finger.footprint().points_size() == 4);
  const int disc = part.region() == 0 ? 1 : 0;
  REQUIRE(finger.blocked_by_size() == 1);
  CHECK(finger.blocked_by(0) == disc);
  bool no_grasp = false;
  for (const auto& rejection : r.rejections())
    no_grasp = no_grasp || (rejection.region() == part.region() && rejection.test() == "no grasp");
  CHECK(no_grasp);
  CHECK(ask(robot, "WHY").find(" no free grasp of type 1") != std::string::npos);
}

TEST_CASE("the results stream gives a still bar the turn LOCATE gives it in every frame",
          "[e2e][results][symmetry]") {
  // A bar (alike turned by 180) lying where it was taught, fresh noise in
  // every frame of the synthetic camera: the stream's angle (image axes,
  // the turn nearest the taught pose) and reply pose agree with the reply,
  // and stay within noise of 0, never 180.
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=640,height=480,parts=1,types=rectangle,seed=4",
                             "--mode", "trigger"});
  VisionProcess vision(server);
  LineClient robot = vision.connect();
  Results results(vision.results_endpoint);
  results.join(robot, "BLOBS");
  REQUIRE(ask(robot, "LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
  results.after("LEARN");
  std::vector<double> angles;
  for (int i = 0; i < 20; ++i) {
    const std::string reply = ask(robot, "LOCATE 1");
    const auto poses = parseLocateReply(reply);
    REQUIRE(poses.size() == 1);
    const auto r = results.after("LOCATE");
    CHECK(r.reply() == reply);
    REQUIRE(r.parts_size() == 1);
    const auto& part = r.parts(0);
    CHECK(part.symmetry_deg() == 180);
    CHECK(part.reply_pose().rz_deg() == Approx(poses[0].rz).margin(0.001));
    // Image axes (y down) against the vision frame's (y up): the same turn.
    CHECK(part.angle_deg() == Approx(-poses[0].rz).margin(0.001));
    angles.push_back(part.angle_deg());
  }
  const auto [lo, hi] = std::minmax_element(angles.begin(), angles.end());
  INFO("angles from " << *lo << " to " << *hi);
  CHECK(*hi - *lo < 0.3);
  CHECK(std::abs(*lo) < 0.3);
  CHECK(std::abs(*hi) < 0.3);
}
