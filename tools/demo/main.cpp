// picksight-demo: the whole slice on the embedded synthetic camera. Starts a
// video server and a vision app on free ports, asks for parts the way a
// robot controller does (LOCATE over TCP), prints each reply beside the
// synthetic ground truth, and stops both processes.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <thread>

#include <zmq.hpp>

#include "picksight/common/angles.hpp"
#include "picksight/common/command_line.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/frame_message.hpp"

namespace {
using namespace std::chrono_literals;
using picksight::formatFixed;

std::string binDir() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  std::string p(path, static_cast<size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}

}  // namespace

int main(int argc, char** argv) {
  int requests = 3;
  int parts = 8;
  int width = 1280;
  int height = 960;
  long long seed = 1;
  CLI::App app("Quick-start demo: a synthetic camera, the vision app and a robot's requests.",
               "picksight-demo");
  app.set_help_flag("-h,--help", "print this help");
  app.add_option("--requests", requests, "LOCATE requests to send")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--parts", parts, "parts in the synthetic scene")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--width", width, "image width")
      ->type_name("W")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--height", height, "image height")
      ->type_name("H")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--seed", seed, "scene seed")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  if (auto exit_code = picksight::parseMainArgs(app, argc, argv)) return *exit_code;

  const std::string dir = binDir();
  char data_dir[] = "/tmp/picksight-demo-XXXXXX";
  if (!::mkdtemp(data_dir)) {
    std::perror("mkdtemp");
    return 1;
  }
  // Trigger mode with a new layout on every frame: each LOCATE sees a new scene.
  const std::string source =
      "cam0=synthetic:width=" + std::to_string(width) + ",height=" + std::to_string(height) +
      ",parts=" + std::to_string(parts) + ",seed=" + std::to_string(seed) + ",scene_every=1";
  std::cout << "PickSight demo: synthetic camera " << width << "x" << height << ", " << parts
            << " parts per scene\n";
  picksight::Subprocess server({dir + "/picksight-video-server", "--source", source, "--frames",
                                "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*", "--mode",
                                "trigger"});
  auto frames = server.waitForLine("frames ", 10s);
  auto control = server.waitForLine("control ", 10s);
  if (!frames || !control) {
    std::cerr << "demo: the video server did not start\n";
    return 1;
  }
  picksight::Subprocess vision({dir + "/picksight-vision", "--frames", *frames, "--control",
                                *control, "--camera", "cam0", "--robot-port", "0", "--bind",
                                "127.0.0.1", "--data-dir", data_dir});
  auto port_text = vision.waitForLine("robot ", 10s);
  auto port = port_text ? picksight::parseInt(*port_text) : std::nullopt;
  if (!port) {
    std::cerr << "demo: the vision app did not start\n";
    return 1;
  }
  std::cout << "video server: frames " << *frames << ", control " << *control
            << "\nvision app: robot port " << *port << "\n"
            << "Uncalibrated, LOCATE replies in the vision frame in pixels (x right, y up,\n"
            << "angles counter-clockwise); the tables show both in image axes (y down).\n";

  // The demo also watches the frames, as a viewer would, to read the truth.
  zmq::context_t context;
  picksight::FrameSubscriber watcher(context, *frames, "cam0", 16);
  std::this_thread::sleep_for(300ms);  // let the subscription reach the server

  auto robot = picksight::LineClient::connect("127.0.0.1", static_cast<uint16_t>(*port), 5s);
  if (!robot) {
    std::cerr << "demo: " << robot.error().message << "\n";
    return 1;
  }
  int failures = 0;
  for (int r = 0; r < requests; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto reply = robot->request("LOCATE 1", 10s);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!reply) {
      std::cerr << "demo: LOCATE failed: " << reply.error().message << "\n";
      ++failures;
      continue;
    }
    auto used = robot->request("FRAME", 5s);
    std::cout << "\n> LOCATE 1\n< " << *reply << "\n  (" << formatFixed(ms, 1) << " ms, "
              << (used ? *used : std::string("?")) << ")\n";
    // Find the frame LOCATE used among the watched ones, by sequence number.
    const auto fields = used ? picksight::splitFields(*used, " ") : std::vector<std::string_view>{};
    const auto seq = fields.size() >= 3 ? picksight::parseInt(fields[2]) : std::nullopt;
    std::optional<picksight::Frame> frame;
    for (int tries = 0; tries < 50 && seq; ++tries) {
      auto f = watcher.receive(200ms);
      if (f && static_cast<long long>(f->info.sequence) == *seq) {
        frame = std::move(f);
        break;
      }
    }
    const auto words = picksight::splitFields(*reply, " ");
    if (words.size() < 2 || words[0] != "OK" || !frame) {
      ++failures;
      continue;
    }
    std::printf("  %-16s %9s %9s %8s | %9s %9s %8s | %7s %7s\n", "truth type", "x", "y", "rz",
                "found x", "y", "rz", "d px", "d deg");
    for (const auto& t : frame->truth) {
      double best = std::numeric_limits<double>::max();
      double fx = 0, fy = 0, fr = 0;
      for (size_t i = 2; i + 2 < words.size(); i += 3) {
        // An uncalibrated cell replies in the vision frame (y up, angles
        // counter-clockwise); the truth is in image axes.
        const double x = picksight::parseDouble(words[i]).value_or(0);
        const double y = -picksight::parseDouble(words[i + 1]).value_or(0);
        const double d = std::hypot(x - t.x, y - t.y);
        if (d < best) {
          best = d;
          fx = x;
          fy = y;
          fr = 360.0 - picksight::parseDouble(words[i + 2]).value_or(0);
        }
      }
      const std::string angle_err =
          t.symmetry_deg > 0
              ? formatFixed(picksight::angleDiffDeg(fr, t.angle_deg, t.symmetry_deg), 3)
              : std::string("any");
      std::printf("  %-16s %9.3f %9.3f %8.3f | %9.3f %9.3f %8.3f | %7.3f %7s\n", t.type.c_str(),
                  t.x, t.y, t.angle_deg, fx, fy, fr, best, angle_err.c_str());
    }
  }
  robot->close();
  const int vision_status = vision.terminate();
  const int server_status = server.terminate();
  std::cout << "\nstopped: vision app exit " << WEXITSTATUS(vision_status) << ", video server exit "
            << WEXITSTATUS(server_status) << "\n";
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
  return failures == 0 && vision_status == 0 && server_status == 0 ? 0 : 1;
}
