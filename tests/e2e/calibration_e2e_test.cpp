// A whole cell calibrated without hardware: the synthetic camera's simulated
// robot holds the target where picksight-cam tells it, the robot protocol
// runs CALCAM, STORE, COMPUTE and LOCATE, and the answers are checked against
// the hidden robot-camera transform. Then the calibration's integrity: a
// damaged file stops LOCATE until CLEARCAL, and bad numbers are refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <optional>

#include "picksight/codecs/codecs.hpp"

#include "cell_fixture.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {

// The hidden transform of the test's cell, as the protocol states it:
// robot = R(rz) * (u * s, -v * s) + (dx, dy).
constexpr double kMmPerPx = 0.25;
constexpr double kRz = 178.7;
constexpr double kDx = 330.5;
constexpr double kDy = -612.25;
const char* const kCamera =
    "cam0=synthetic:width=1280,height=960,parts=0,seed=3,mm_per_px=0.25,rz=178.7,dx=330.5,"
    "dy=-612.25,target_radius=5";

cv::Point2d robotAt(cv::Point2d pixel) {
  const double a = kRz * M_PI / 180;
  const double xv = pixel.x * kMmPerPx;
  const double yv = -pixel.y * kMmPerPx;
  return {std::cos(a) * xv - std::sin(a) * yv + kDx, std::sin(a) * xv + std::cos(a) * yv + kDy};
}

std::string ask(LineClient& robot, const std::string& request) {
  auto reply = robot.request(request, 20s);
  REQUIRE(reply);
  return *reply;
}

// What the robot does: picksight-cam moves its target (or takes it away).
void holdTarget(const VideoServerProcess& server, std::optional<cv::Point2d> at_mm,
                const std::string& target = "disc radius 5 mm") {
  std::vector<std::string> argv = {binPath("picksight-cam"),
                                   "--control",
                                   server.control,
                                   "--timeout",
                                   "10000",
                                   "target",
                                   "cam0"};
  if (at_mm) {
    argv.push_back(formatFixed(at_mm->x, 4));
    argv.push_back(formatFixed(at_mm->y, 4));
  } else {
    argv.push_back("--hide");
  }
  const CommandResult r = run(argv);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.rfind("cam0: target " + target, 0) == 0);
}

}  // namespace

TEST_CASE("a synthetic cell is calibrated through the protocol with its simulated robot",
          "[e2e][calibration]") {
  VideoServerProcess server({"--source", kCamera, "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();

  // The hidden transform is readable, for checking a calibration against.
  const CommandResult info =
      run({binPath("picksight-cam"), "--control", server.control, "info", "cam0"});
  REQUIRE(info.exit_code == 0);
  CHECK(info.out.find("simulated robot: robot = R(178.7 deg) * vision + (330.5, -612.25) mm, "
                      "0.25 mm/px") != std::string::npos);
  CHECK(info.out.find("target:          disc radius 5 mm, hidden") != std::string::npos);

  CHECK(ask(robot, "CALCAM 5").rfind("ERROR 1 ", 0) == 0);  // no target held yet
  holdTarget(server, robotAt({639.5, 479.5}));
  const auto scale = replyNumbers(ask(robot, "CALCAM 5"), 2);
  CHECK(scale[0] == Approx(kMmPerPx).epsilon(0.003));
  CHECK(scale[1] == Approx(kMmPerPx).epsilon(0.003));

  // Seven robot points over the field of view, as an integrator would teach.
  const std::vector<cv::Point2d> pixels{{150.2, 120.7}, {1130.6, 140.3}, {1100.1, 840.9},
                                        {170.4, 820.2}, {640.3, 470.8},  {400.9, 300.1},
                                        {900.5, 650.6}};
  for (size_t i = 0; i < pixels.size(); ++i) {
    const cv::Point2d at = robotAt(pixels[i]);
    holdTarget(server, at);
    CHECK(ask(robot, "STORE " + formatFixed(at.x, 4) + " " + formatFixed(at.y, 4)) ==
          "OK " + std::to_string(i + 1));
  }
  const auto t = replyNumbers(ask(robot, "COMPUTE"), 4);
  CHECK(t[0] == Approx(kDx).margin(1.0));
  CHECK(t[1] == Approx(kDy).margin(1.0));
  CHECK(t[2] == Approx(kRz).margin(0.1));
  CHECK(t[3] < 0.3);
  CHECK(ask(robot, "STATUS").rfind("OK frame=robot ", 0) == 0);

  // LOCATE (no model: every region at its own pose) in robot millimetres,
  // at places no point was stored at.
  for (const cv::Point2d pixel : {cv::Point2d(300.3, 700.2), cv::Point2d(1000.8, 250.4)}) {
    const cv::Point2d truth = robotAt(pixel);
    holdTarget(server, truth);
    const auto poses = parseLocateReply(ask(robot, "LOCATE 1"));
    REQUIRE(poses.size() == 1);
    CHECK(poses[0].x == Approx(truth.x).margin(0.2));
    CHECK(poses[0].y == Approx(truth.y).margin(0.2));
  }

  // The robot takes the target away: nothing to store.
  holdTarget(server, std::nullopt);
  CHECK(ask(robot, "STORE 1 2").rfind("ERROR 1 ", 0) == 0);
}

TEST_CASE("CALCAM GRID measures the scale on a grid of dots through a resized camera",
          "[e2e][calibration]") {
  // A grid of 5 x 4 dots 12 mm apart at 0.25 mm/px, published at 3/4 size:
  // the scale comes back in sensor pixels, as CALCAM's disc gives it.
  VideoServerProcess server(
      {"--source",
       "cam0=synthetic:width=1280,height=960,parts=0,seed=3,mm_per_px=0.25,rz=178.7,dx=330.5,"
       "dy=-612.25,target=grid,grid=5x4,grid_pitch=12,target_radius=3",
       "--mode", "trigger"});
  REQUIRE(run({binPath("picksight-cam"), "--control", server.control, "size", "cam0", "--scale",
               "0.75"})
              .exit_code == 0);
  VisionProcess vision(server);
  auto robot = vision.connect();
  CHECK(ask(robot, "CALCAM GRID").rfind("ERROR 11 ", 0) == 0);
  CHECK(ask(robot, "CALCAM GRID -3").rfind("ERROR 11 ", 0) == 0);
  CHECK(ask(robot, "CALCAM GRID 12").rfind("ERROR 3 ", 0) == 0);  // no grid held yet
  holdTarget(server, robotAt({620.2, 470.7}), "grid");
  const auto scale = replyNumbers(ask(robot, "CALCAM GRID 12"), 2);
  CHECK(scale[0] == Approx(kMmPerPx).epsilon(0.001));
  CHECK(scale[1] == Approx(kMmPerPx).epsilon(0.001));
  CHECK(ask(robot, "STATUS").find(" scale=" + formatFixed(scale[0], 6)) != std::string::npos);
}

TEST_CASE("a camera tilted 2 degrees, calibrated on a dot grid, places parts within 0.05 mm",
          "[e2e][calibration]") {
  // The hidden cell above with the camera tilted 2 degrees (a 1.5 % change
  // of scale across the image). The grid covers most of the sensor: CALCAM
  // GRID takes out the tilt (and fits a lens, here without distortion), so
  // six robot points and COMPUTE give robot millimetres everywhere. The
  // simulated robot holds one kind of target, so the grid and the disc are
  // two video servers in turn, and the calibration goes from one vision app
  // to the next through its file.
  const std::string cell =
      "cam0=synthetic:width=1920,height=1080,parts=0,seed=3,mm_per_px=0.25,rz=178.7,dx=330.5,"
      "dy=-612.25,tilt_x=2";
  test::TempDir data;
  {
    VideoServerProcess server({"--source",
                               cell + ",target=grid,grid=17x9,grid_pitch=25,target_radius=4",
                               "--mode", "trigger"});
    VisionProcess vision(server, "cam0", data.path().string());
    auto robot = vision.connect();
    holdTarget(server, robotAt({959.5, 539.5}), "grid");
    const auto scale = replyNumbers(ask(robot, "CALCAM GRID 25"), 2);
    CHECK(scale[0] == Approx(kMmPerPx).epsilon(0.02));
    CHECK(scale[0] == scale[1]);  // square on the plane once rectified
    CHECK(ask(robot, "STATUS").find(" lens=1 ") != std::string::npos);
    // Again through a resized camera: the lens cannot be fitted there, so
    // the first grid's is kept, and the dots are undistorted by it.
    REQUIRE(run({binPath("picksight-cam"), "--control", server.control, "size", "cam0", "--scale",
                 "0.75"})
                .exit_code == 0);
    const auto again = replyNumbers(ask(robot, "CALCAM GRID 25"), 2);
    CHECK(again[0] == Approx(scale[0]).epsilon(0.001));
    CHECK(ask(robot, "STATUS").find(" lens=1 ") != std::string::npos);
  }
  VideoServerProcess server({"--source", cell + ",target_radius=5", "--mode", "trigger"});
  VisionProcess vision(server, "cam0", data.path().string());
  auto robot = vision.connect();
  REQUIRE(ask(robot, "STATUS").find(" lens=1 ") != std::string::npos);
  const std::vector<cv::Point2d> pixels{{250.2, 160.7}, {1650.6, 190.3}, {1600.1, 900.9},
                                        {280.4, 880.2}, {960.3, 540.8},  {700.9, 350.1}};
  for (const cv::Point2d& p : pixels) {
    const cv::Point2d at = robotAt(p);
    holdTarget(server, at);
    REQUIRE(
        ask(robot, "STORE " + formatFixed(at.x, 4) + " " + formatFixed(at.y, 4)).rfind("OK ", 0) ==
        0);
  }
  const auto t = replyNumbers(ask(robot, "COMPUTE"), 4);
  CHECK(t[3] < 0.05);
  // Parts anywhere in the field, away from the stored points: the robot
  // position LOCATE gives against the one the target was held at.
  double ss = 0;
  const std::vector<cv::Point2d> probes{{120.5, 100.2}, {1800.3, 120.8}, {1790.7, 980.4},
                                        {130.2, 990.6}, {1300.4, 700.1}, {500.6, 650.3}};
  for (const cv::Point2d& p : probes) {
    const cv::Point2d truth = robotAt(p);
    holdTarget(server, truth);
    const auto poses = parseLocateReply(ask(robot, "LOCATE 1"));
    REQUIRE(poses.size() == 1);
    const double e = std::hypot(poses[0].x - truth.x, poses[0].y - truth.y);
    INFO("at pixel " << p << " off by " << e << " mm");
    CHECK(e < 0.08);
    ss += e * e;
  }
  const double rms = std::sqrt(ss / static_cast<double>(probes.size()));
  INFO("placement RMS " << rms << " mm");
  CHECK(rms < 0.05);
}

TEST_CASE("picksight-cam target refuses bad positions and cameras without a robot and sets parts",
          "[e2e][calibration]") {
  test::TempDir dir;
  REQUIRE(
      picksight::codecs::imwrite(dir.file("still.png"), cv::Mat(64, 64, CV_8UC1, cv::Scalar(200))));
  VideoServerProcess server(
      {"--source", kCamera, "--source", "cam1=file:" + dir.file("still.png")});
  const std::string cam = binPath("picksight-cam");
  CHECK(run({cam, "--control", server.control, "target", "cam0", "1", "nan"}).exit_code == 2);
  CHECK(run({cam, "--control", server.control, "target", "cam0", "1"}).exit_code == 2);
  CHECK(run({cam, "--control", server.control, "target", "cam0", "1", "2", "--hide"}).exit_code ==
        2);
  CHECK(run({cam, "--control", server.control, "target", "cam0", "1", "2e7"}).exit_code == 1);
  CHECK(run({cam, "--control", server.control, "target", "cam1", "1", "2"}).exit_code == 1);
  // Held where the camera sees it whole: shown (y is negative all over this
  // cell's view).
  const cv::Point2d inside = robotAt({640, 480});
  const CommandResult held = run({cam, "--control", server.control, "--json", "target", "cam0",
                                  formatFixed(inside.x, 3), formatFixed(inside.y, 3)});
  CHECK(held.exit_code == 0);
  CHECK(held.out.find("\"target_visible\":true") != std::string::npos);
  // Off the image (x = -12.5 mm lies 72 px past its right edge) or across
  // its edge: refused (the server's error, which picksight-cam prints on
  // stderr, names it), and the target stays where it was.
  for (const cv::Point2d& off : {cv::Point2d(-12.5, -600), robotAt({1279, 480})}) {
    const CommandResult refused = run({cam, "--control", server.control, "--json", "target", "cam0",
                                       formatFixed(off.x, 3), formatFixed(off.y, 3)});
    CHECK(refused.exit_code == 1);
    CHECK(refused.out.find("target_visible") == std::string::npos);
  }
  const CommandResult still = run({cam, "--control", server.control, "info", "cam0"});
  CHECK(still.out.find("at robot " + formatFixed(inside.x, 3) + " " + formatFixed(inside.y, 3) +
                       " mm = sensor ") != std::string::npos);
  // The table is loaded or cleared through the camera's Parts feature.
  CHECK(run({cam, "--control", server.control, "set", "cam0", "Parts", "2"}).out == "Parts = 2\n");
  CHECK(run({cam, "--control", server.control, "set", "cam0", "Parts", "900"}).exit_code == 1);
  CHECK(run({cam, "--control", server.control, "get", "cam0", "Parts"}).out == "2\n");
}

TEST_CASE("a damaged calibration file stops LOCATE until CLEARCAL", "[e2e][calibration]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--mode", "trigger"});
  test::TempDir data;
  REQUIRE(writeFileAtomically(data.file("calibration.yaml"), "format_version: [1\n"));
  VisionProcess vision(server, "cam0", data.path().string());
  auto robot = vision.connect();

  const std::string status = ask(robot, "STATUS");
  CHECK(status.rfind("OK frame=none ", 0) == 0);
  CHECK(status.find(" calibration=damaged") != std::string::npos);
  // Never a silent change of frame: LOCATE says why it cannot answer.
  const std::string locate = ask(robot, "LOCATE 1");
  CHECK(locate.rfind("ERROR 45 the calibration file is damaged", 0) == 0);
  CHECK(locate.find("CLEARCAL") != std::string::npos);
  CHECK(ask(robot, "STORE 1 2").rfind("ERROR 45 ", 0) == 0);
  CHECK(ask(robot, "COMPUTE").rfind("ERROR 45 ", 0) == 0);
  CHECK(ask(robot, "CLEARCAL 1").rfind("ERROR 11 ", 0) == 0);

  CHECK(ask(robot, "CLEARCAL") == "OK");
  CHECK(std::filesystem::exists(data.file("calibration.yaml.damaged")));
  const std::string cleared = ask(robot, "STATUS");
  CHECK(cleared.rfind("OK frame=vision-px ", 0) == 0);
  CHECK(cleared.find(" calibration=ok") != std::string::npos);
  CHECK(parseLocateReply(ask(robot, "LOCATE 1")).size() == 1);
}

TEST_CASE("STORE refuses non-finite and out-of-range robot coordinates", "[e2e][calibration]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  for (const char* bad : {"STORE nan 1", "STORE 1 inf", "STORE 1e999 0", "STORE 2000000 0",
                          "STORE 0 -1000001", "STORE 1"}) {
    CHECK(ask(robot, bad).rfind("ERROR 11 ", 0) == 0);
  }
  CHECK(ask(robot, "LIST") == "OK 0");
}
