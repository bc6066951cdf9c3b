// picksight-demo: a whole cell on the embedded synthetic camera and its
// simulated robot. Starts a video server and a vision app on free ports,
// then does what an integrator and a robot program do over the robot
// protocol: CALCAM, STORE at several robot points, COMPUTE, LEARN, GRASP,
// LOCATE, and prints each answer beside the hidden truth (the camera's
// robot-camera transform and the parts' true places), then stops both. With
// --web PORT it then keeps the cell running (camera in free-run) with
// picksight-web serving its HMI on that port, until interrupted.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <thread>

#include <opencv2/core.hpp>
#include <zmq.hpp>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/stop_signals.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"

namespace {
using namespace std::chrono_literals;
using picksight::formatFixed;

// The demo cell's hidden robot-camera transform: the robot's frame turned by
// 178.7 degrees, a 10 mm disc as the calibration target.
constexpr double kMmPerPx = 0.25;
constexpr double kRz = 178.7;
constexpr double kDx = 330.5;
constexpr double kDy = -612.25;
constexpr double kTargetRadius = 5;

std::string binDir() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  std::string p(path, static_cast<size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}

// The numbers after "OK" of a reply; empty for an error.
std::vector<double> replyNumbers(const std::string& reply) {
  const auto words = picksight::splitFields(reply, " ");
  std::vector<double> out;
  if (words.empty() || words[0] != "OK") return out;
  for (size_t i = 1; i < words.size(); ++i)
    out.push_back(picksight::parseDouble(words[i]).value_or(NAN));
  return out;
}

// The cell as the demo drives it: the robot's TCP line, the camera's
// control socket (the simulated robot moves the target; the scene's part
// count stands for an operator clearing or loading the table), and a
// subscriber watching the frames for their truth.
class Cell {
 public:
  Cell(zmq::context_t& context, const std::string& control, const std::string& frames,
       picksight::tool_support::LineClient robot)
      : control_(context, control, 10s),
        watcher_(context, frames, "cam0", 64),
        robot_(std::move(robot)) {}

  // Sends a robot request, prints it and its reply.
  std::string say(const std::string& request) {
    auto reply = robot_.request(request, 30s);
    const std::string text = reply ? *reply : "(no reply: " + reply.error().message + ")";
    std::cout << "> " << request << "\n< " << text << "\n";
    if (text.rfind("OK", 0) != 0) ++failures_;
    return text;
  }

  // The simulated robot: its hidden transform (from the camera's own
  // description), and moving its target.
  std::optional<picksight::proto::SimulatedRobot> describe() {
    picksight::proto::ControlRequest request;
    request.mutable_describe_camera()->set_camera("cam0");
    auto reply = control_.call(request);
    if (!reply || !reply->describe_camera().has_simulated_robot()) return std::nullopt;
    return reply->describe_camera().simulated_robot();
  }
  bool holdTarget(std::optional<cv::Point2d> at_mm) {
    picksight::proto::ControlRequest request;
    auto* target = request.mutable_set_target();
    target->set_camera("cam0");
    target->set_hide(!at_mm);
    if (at_mm) {
      target->set_x_mm(at_mm->x);
      target->set_y_mm(at_mm->y);
    }
    return check(control_.call(request), "target");
  }
  bool setParts(int parts) {
    picksight::proto::ControlRequest request;
    auto* feature = request.mutable_set_feature();
    feature->set_camera("cam0");
    feature->set_name("Parts");
    feature->set_value(std::to_string(parts));
    return check(control_.call(request), "Parts");
  }

  // Free-run at `fps`: a live view for the web page.
  bool setFreerun(double fps) {
    picksight::proto::ControlRequest request;
    auto* mode = request.mutable_set_mode();
    mode->set_camera("cam0");
    mode->set_mode(picksight::proto::FREERUN);
    mode->set_fps(fps);
    return check(control_.call(request), "mode");
  }

  // The truth of the frame the last vision request worked on (FRAME).
  std::optional<picksight::Frame> lastFrame() {
    auto used = robot_.request("FRAME", 5s);
    const auto fields = used ? picksight::splitFields(*used, " ") : std::vector<std::string_view>{};
    const auto seq = fields.size() >= 3 ? picksight::parseInt(fields[2]) : std::nullopt;
    for (int tries = 0; tries < 100 && seq; ++tries) {
      auto f = watcher_.receive(200ms);
      if (f && static_cast<long long>(f->info.sequence) == *seq) return f;
    }
    return std::nullopt;
  }

  void fail() { ++failures_; }
  int failures() const { return failures_; }
  void close() { robot_.close(); }

 private:
  bool check(const picksight::Result<picksight::proto::ControlReply>& reply, const char* what) {
    if (reply) return true;
    std::cerr << "demo: " << what << ": " << reply.error().message << "\n";
    ++failures_;
    return false;
  }

  picksight::transport::ControlClient control_;
  picksight::transport::FrameSubscriber watcher_;
  picksight::tool_support::LineClient robot_;
  int failures_ = 0;
};

// Sensor pixels to robot mm through the hidden homography.
cv::Point2d toRobot(const cv::Matx33d& sensor_to_robot, cv::Point2d px) {
  const cv::Vec3d r = sensor_to_robot * cv::Vec3d(px.x, px.y, 1);
  return {r[0] / r[2], r[1] / r[2]};
}

void calibrate(Cell& cell, const cv::Matx33d& robot_to_sensor, int width, int height, int points) {
  const cv::Matx33d sensor_to_robot = robot_to_sensor.inv();
  std::cout << "\n1. Camera scale: the robot holds the disc (radius " << kTargetRadius
            << " mm) in the middle of the view.\n";
  cell.holdTarget(toRobot(sensor_to_robot, {0.5 * (width - 1), 0.5 * (height - 1)}));
  const auto scale = replyNumbers(cell.say("CALCAM " + formatFixed(kTargetRadius, 1)));
  if (scale.size() == 2) {
    std::cout << "   truth " << formatFixed(kMmPerPx, 6) << " mm/px: error "
              << formatFixed(100 * (scale[0] / kMmPerPx - 1), 3) << " % x, "
              << formatFixed(100 * (scale[1] / kMmPerPx - 1), 3) << " % y\n";
  }

  std::cout << "\n2. Robot-camera calibration: the robot holds the disc at " << points
            << " points over the view.\n";
  const int cols = (points + 1) / 2;
  for (int i = 0; i < points; ++i) {
    // Two rows, staggered, inside the central 80 % of the image.
    const int row = i / cols;
    const double fx = cols > 1 ? 0.1 + 0.8 * (i % cols) / (cols - 1) : 0.5;
    const double fy = row == 0 ? 0.15 + 0.05 * (i % 2) : 0.8 + 0.05 * (i % 2);
    const cv::Point2d robot =
        toRobot(sensor_to_robot, {fx * (width - 1) + 0.37 * i, fy * (height - 1) + 0.21 * i});
    cell.holdTarget(robot);
    cell.say("STORE " + formatFixed(robot.x, 3) + " " + formatFixed(robot.y, 3));
  }
  const auto t = replyNumbers(cell.say("COMPUTE"));
  if (t.size() == 4) {
    std::cout << "   truth dx " << formatFixed(kDx) << " dy " << formatFixed(kDy) << " rz "
              << formatFixed(kRz) << ": error " << formatFixed(t[0] - kDx) << " "
              << formatFixed(t[1] - kDy) << " mm, " << formatFixed(t[2] - kRz) << " deg\n";
  }
}

void pick(Cell& cell, const cv::Matx33d& robot_to_sensor, int parts, int requests) {
  const cv::Matx33d sensor_to_robot = robot_to_sensor.inv();
  std::cout << "\n3. Teaching: the robot puts the disc away; one part on the table.\n";
  cell.holdTarget(std::nullopt);
  cell.setParts(1);
  cell.say("LEARN 1 bracket");
  const auto learned = cell.lastFrame();
  cell.say("GRASP 1 ADD 0 0 0");
  if (!learned || learned->truth.size() != 1) {
    std::cerr << "demo: no truth for the taught part\n";
    cell.fail();
    return;
  }
  const double learned_deg = learned->truth[0].angle_deg;

  std::cout << "\n4. Picking: " << parts << " parts on the table; LOCATE replies in robot mm.\n";
  cell.setParts(parts);
  for (int r = 0; r < requests; ++r) {
    const auto poses = replyNumbers(cell.say("LOCATE 1"));
    const auto frame = cell.lastFrame();
    if (poses.empty() || !frame) {
      cell.fail();
      continue;
    }
    std::printf("   %9s %9s %8s | %9s %9s %8s | %7s %7s\n", "truth x", "y", "rz", "found x", "y",
                "rz", "d mm", "d deg");
    for (const auto& t : frame->truth) {
      // The part's true place and turn in the robot frame: image angles turn
      // clockwise, the robot's counter-clockwise, from the taught pose.
      const cv::Point2d truth = toRobot(sensor_to_robot, {t.x, t.y});
      const double truth_rz = picksight::normalizeDeg(kRz - (t.angle_deg - learned_deg));
      double best = HUGE_VAL;
      size_t found = 0;
      for (size_t i = 1; i + 2 < poses.size(); i += 3) {
        const double d = std::hypot(poses[i] - truth.x, poses[i + 1] - truth.y);
        if (d < best) {
          best = d;
          found = i;
        }
      }
      if (found == 0) {
        std::printf("   %9.3f %9.3f %8.3f | %9s\n", truth.x, truth.y, truth_rz, "not found");
        continue;
      }
      const double d_deg = t.symmetry_deg > 0
                               ? picksight::angleDiffDeg(poses[found + 2], truth_rz, t.symmetry_deg)
                               : 0.0;
      std::printf("   %9.3f %9.3f %8.3f | %9.3f %9.3f %8.3f | %7.3f %7.3f\n", truth.x, truth.y,
                  truth_rz, poses[found], poses[found + 1], poses[found + 2], best, d_deg);
    }
  }
}

// The start-up lines of a PickSight process ("robot 1234", "results tcp://...")
// up to its "ready" line, by their first word.
std::map<std::string, std::string> startLines(picksight::tool_support::Subprocess& process) {
  std::map<std::string, std::string> lines;
  while (auto line = process.readLine(10s)) {
    if (*line == "ready") break;
    const size_t space = line->find(' ');
    if (space != std::string::npos) lines[line->substr(0, space)] = line->substr(space + 1);
  }
  return lines;
}

// Serves the cell's HMI on `port` until SIGINT or SIGTERM.
int serveWeb(const picksight::StopSignals& stop, Cell& cell, const std::string& dir,
             const std::string& frames, const std::string& control, const std::string& results,
             int robot_port, int port) {
  cell.setFreerun(10);
  picksight::tool_support::Subprocess web({dir + "/picksight-web", "--listen",
                                           "127.0.0.1:" + std::to_string(port), "--video-server",
                                           frames + "," + control, "--vision-app",
                                           "cam0," + (results.empty() ? "none" : results) +
                                               ",127.0.0.1:" + std::to_string(robot_port)});
  // Its users live in memory: it prints the one admin's random password
  // before its URL.
  std::string password;
  std::optional<std::string> line;
  while ((line = web.readLine(10s)) && line->rfind("web ", 0) != 0)
    if (line->rfind("admin-password ", 0) == 0) password = line->substr(15);
  if (!line) {
    std::cerr << "demo: picksight-web did not start\n";
    return 1;
  }
  std::cout << "\nThe cell's HMI: " << line->substr(4) << "  (Ctrl-C stops the cell)\n"
            << "log in as admin, password " << password << std::endl;
  stop.wait();
  std::cout << "stopping" << std::endl;
  return WEXITSTATUS(web.terminate());
}

}  // namespace

// The demo's script top to bottom (options, the two processes, calibrate,
// pick, the web): long, but read in one go it is the quick start's
// walk-through; calibrate() and pick() hold the steps' details.
int main(int argc, char** argv) {
  int requests = 2;
  int parts = 6;
  int points = 8;
  int width = 1280;
  int height = 960;
  long long seed = 1;
  int web_port = -1;
  picksight::cli::App app(
      "Quick-start demo: a whole cell on the synthetic camera and its simulated robot:\n"
      "CALCAM, STORE, COMPUTE, LEARN, GRASP and LOCATE in robot millimetres, beside the truth.",
      "picksight-demo");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--requests", requests, "LOCATE requests to send")
      ->typeName("N")
      ->check(picksight::cli::range(0, 100))
      ->showDefault();
  app.addOption("--parts", parts, "parts on the table when picking")
      ->typeName("N")
      ->check(picksight::cli::range(1, 40))
      ->showDefault();
  app.addOption("--points", points, "calibration points to STORE")
      ->typeName("N")
      ->check(picksight::cli::range(3, 64))
      ->showDefault();
  app.addOption("--width", width, "image width")
      ->typeName("W")
      ->check(picksight::cli::range(320, 4096))
      ->showDefault();
  app.addOption("--height", height, "image height")
      ->typeName("H")
      ->check(picksight::cli::range(240, 4096))
      ->showDefault();
  app.addOption("--seed", seed, "scene seed")
      ->typeName("S")
      ->check(picksight::cli::nonNegativeNumber())
      ->showDefault();
  app.addOption("--web", web_port,
                "after the script, keep the cell running with its web HMI on this port "
                "(127.0.0.1; 0: any free port) until interrupted")
      ->typeName("PORT")
      ->check(picksight::cli::range(0, 65535));
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  // Blocked before any thread or child starts: Ctrl-C reaches the demo's
  // wait (and the children's own), never a ZeroMQ thread.
  std::optional<picksight::StopSignals> stop_signals;
  if (web_port >= 0) stop_signals.emplace();

  const std::string dir = binDir();
  char data_dir[] = "/tmp/picksight-demo-XXXXXX";
  if (!::mkdtemp(data_dir)) {
    std::perror("mkdtemp");
    return 1;
  }
  // An empty table to start with (the calibration needs the disc alone);
  // the parts are all of one type, the one taught.
  const std::string source =
      "cam0=synthetic:width=" + std::to_string(width) + ",height=" + std::to_string(height) +
      ",parts=0,types=l_shape,size=160,seed=" + std::to_string(seed) +
      ",mm_per_px=" + formatFixed(kMmPerPx, 3) + ",rz=" + formatFixed(kRz, 3) +
      ",dx=" + formatFixed(kDx, 3) + ",dy=" + formatFixed(kDy, 3) +
      ",target_radius=" + formatFixed(kTargetRadius, 3);
  std::cout << "PickSight demo: a whole cell on the synthetic camera (" << width << "x" << height
            << ") and its simulated robot\n";
  picksight::tool_support::Subprocess server({dir + "/picksight-video-server", "--source", source,
                                              "--frames", "tcp://127.0.0.1:*", "--control",
                                              "tcp://127.0.0.1:*", "--mode", "trigger"});
  auto frames = server.waitForLine("frames ", 10s);
  auto control = server.waitForLine("control ", 10s);
  if (!frames || !control) {
    std::cerr << "demo: the video server did not start\n";
    return 1;
  }
  picksight::tool_support::Subprocess vision(
      {dir + "/picksight-vision", "--frames", *frames, "--control", *control, "--camera", "cam0",
       "--robot-port", "0", "--bind", "127.0.0.1", "--data-dir", data_dir});
  auto started = startLines(vision);
  auto port = started.count("robot") ? picksight::parseInt(started["robot"]) : std::nullopt;
  if (!port) {
    std::cerr << "demo: the vision app did not start\n";
    return 1;
  }
  std::cout << "video server: frames " << *frames << ", control " << *control
            << "\nvision app: robot port " << *port << ", data " << data_dir << "\n";
  auto robot =
      picksight::tool_support::LineClient::connect("127.0.0.1", static_cast<uint16_t>(*port), 5s);
  if (!robot) {
    std::cerr << "demo: " << robot.error().message << "\n";
    return 1;
  }
  zmq::context_t context;
  Cell cell(context, *control, *frames, std::move(*robot));
  std::this_thread::sleep_for(300ms);  // let the watcher's subscription reach the server

  const auto hidden = cell.describe();
  if (!hidden || hidden->robot_to_sensor_size() != 9) {
    std::cerr << "demo: the camera has no simulated robot\n";
    return 1;
  }
  std::cout << "hidden robot-camera transform (the camera's description): robot = R("
            << formatFixed(hidden->rz_deg()) << " deg) * vision + (" << formatFixed(hidden->dx_mm())
            << ", " << formatFixed(hidden->dy_mm()) << ") mm at "
            << formatFixed(hidden->mm_per_px()) << " mm/px\n\n";
  cv::Matx33d h;
  for (int i = 0; i < 9; ++i) h.val[i] = hidden->robot_to_sensor(i);

  cell.say("STATUS");
  calibrate(cell, h, width, height, points);
  pick(cell, h, parts, requests);
  cell.say("STATUS");

  int web_status = 0;
  if (web_port >= 0) {
    web_status =
        serveWeb(*stop_signals, cell, dir, *frames, *control, started["results"], *port, web_port);
  }
  cell.close();
  const int vision_status = vision.terminate();
  const int server_status = server.terminate();
  std::cout << "\nstopped: vision app exit " << WEXITSTATUS(vision_status) << ", video server exit "
            << WEXITSTATUS(server_status) << "\n";
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
  return cell.failures() == 0 && vision_status == 0 && server_status == 0 && web_status == 0 ? 0
                                                                                             : 1;
}
