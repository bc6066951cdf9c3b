// LOCATE end to end in robot coordinates, as a calibrated cell runs it: 9
// trained part types (each with two grasp styles and a two-finger gripper),
// a robot-camera calibration, a 1920x1080 synthetic camera with 20 parts;
// a robot's request sent to its reply received over TCP, fresh frame
// (software trigger) included. Prints median, p99 and min; never fails on time.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "picksight/cell/cell_locate.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/cell_commands.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

const std::vector<std::string> kTypes{"rectangle",  "l_shape", "l_shape_mirror",
                                      "disc_holes", "gear",    "triangle",
                                      "hex_nut",    "t_shape", "slot"};

picksight::synthetic::SceneOptions scene(int width, int height, int parts, uint64_t seed,
                                         std::vector<std::string> types) {
  auto o = picksight::synthetic::sceneOptions(width, height, parts, seed, std::move(types));
  o.part_size = 120;
  return o;
}

// Models, grasps and a calibration written as a cell set up through the
// protocol would have them.
bool prepareDataDir(const std::string& dir) {
  picksight::store::ModelLibrary library(dir + "/models");
  int type = 1;
  for (const auto& name : kTypes) {
    const picksight::synthetic::SceneRenderer one(scene(400, 400, 1, 1000 + type, {name}));
    const auto trained = picksight::vision::trainModel(one.render(0), type, name);
    if (!trained || !library.store(*trained)) {
      std::fprintf(stderr, "bench: training %s failed: %s\n", name.c_str(),
                   (trained ? "cannot store" : trained.error().message.c_str()));
      return false;
    }
    picksight::store::GraspSetup grasp;
    grasp.styles = {{0, 0, 0}, {0, 0, 90}};
    grasp.gripper.fingers = {{0, 8, 2, 1.5}, {0, -8, 2, 1.5}};
    if (!library.setGrasp(type, grasp)) return false;
    ++type;
  }
  picksight::store::CellCalibration calibration(dir + "/calibration.yaml");
  if (!calibration.setScale({0.1, 0.1, 0})) return false;
  const picksight::calibration::RigidTransform truth{350, -80, 30, false};
  for (const cv::Point2d v : {cv::Point2d(10, -10), cv::Point2d(180, -15), cv::Point2d(170, -100),
                              cv::Point2d(20, -95)}) {
    if (!calibration.addPoint({v, truth.apply(v)})) return false;
  }
  return static_cast<bool>(calibration.compute());
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Breakdown {
  double recognition_ms = 0;
  double grasps_ms = 0;
  uint64_t poses_digest = 0;  // of every reply over 5 scenes x 9 types, in process
  size_t poses = 0;
};

// FNV-1a over the reply lines: equal digests, equal replies, so that a
// change meant to keep the poses shows that it did.
void digest(uint64_t& hash, const std::string& text) {
  if (hash == 0) hash = 1469598103934665603ull;
  for (const char c : text + "\n") {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
}

// Where a request's vision time goes, in process on the camera's scene: the
// other engineer's recognition, and this cell's grasp selection.
Breakdown breakdown(const std::string& data_dir, int width, int height, int parts) {
  picksight::store::ModelLibrary library(data_dir + "/models");
  picksight::store::CellCalibration calibration(data_dir + "/calibration.yaml");
  if (!library.load().empty() || !calibration.load() || !calibration.geometry()) return {};
  const picksight::synthetic::SceneRenderer renderer(scene(width, height, parts, 5, kTypes));
  const picksight::Frame frame = picksight::frameFromImage(renderer.render(1), "cam0", 1);
  const auto geometry = *calibration.geometry();
  std::vector<double> recognition, grasps;
  for (int i = 0; i < 100; ++i) {
    const int type = 1 + i % static_cast<int>(kTypes.size());
    auto t0 = Clock::now();
    const auto outcome = picksight::cell::locateInFrame(frame, {}, library.snapshot(), type);
    recognition.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    t0 = Clock::now();
    const auto pick = picksight::cell::pickPoses(outcome, *library.grasps(), geometry);
    grasps.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (pick.poses.size() > outcome.parts.size()) return {};
  }
  Breakdown b{median(recognition), median(grasps)};
  for (uint64_t seed = 5; seed < 10; ++seed) {
    const picksight::synthetic::SceneRenderer scenes(scene(width, height, parts, seed, kTypes));
    const picksight::Frame shot = picksight::frameFromImage(scenes.render(1), "cam0", 1);
    for (int type = 1; type <= static_cast<int>(kTypes.size()); ++type) {
      // The cell's one LOCATE path, as the offline CLI runs it on an image.
      const auto located = picksight::cell::locateAndPick(
          calibration, &library, [&]() -> picksight::Result<picksight::cell::LocateOutcome> {
            return picksight::cell::locateInFrame(shot, {}, library.snapshot(), type);
          });
      if (!located) return {};
      b.poses += located->pick.poses.size();
      digest(b.poses_digest, picksight::protocol::locateReply(located->pick));
    }
  }
  return b;
}
}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  const auto args = picksight::bench::parseLocateArgs(argc, argv, {500, 1920, 1080, 20});
  const int requests = args.requests, width = args.width, height = args.height, parts = args.parts;
  const std::string data_dir = picksight::bench::makeDataDir();
  if (data_dir.empty() || !prepareDataDir(data_dir)) return 1;
  std::string types;
  for (const auto& t : kTypes) types += (types.empty() ? "" : "+") + t;
  auto server = picksight::bench::startVideoServer(
      picksight::bench::syntheticCamera(args, "size=120,types=" + types));
  if (!server) return 1;
  auto vision = picksight::bench::startVision(*server, data_dir);
  if (!vision) return 1;
  picksight::tool_support::LineClient* robot = &vision->robot;

  for (int i = 0; i < 10; ++i) (void)robot->request("LOCATE 1", 10s);  // warm-up
  std::vector<double> ms;
  int failures = 0;
  size_t offered = 0;
  uint64_t replies_digest = 0;
  for (int i = 0; i < requests; ++i) {
    const std::string request = "LOCATE " + std::to_string(1 + i % static_cast<int>(kTypes.size()));
    const auto t0 = Clock::now();
    auto reply = robot->request(request, 10s);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    const std::string text = reply ? *reply : std::string();
    digest(replies_digest, text);
    const auto words = picksight::splitFields(text, " ");
    if (words.size() < 2 || words[0] != "OK") {
      ++failures;
    } else {
      offered += static_cast<size_t>(picksight::parseInt(words[1]).value_or(0));
    }
  }
  auto status = robot->request("STATUS", 5s);
  robot->close();
  vision->process->terminate();
  server->process->terminate();
  const Breakdown inside = breakdown(data_dir, width, height, parts);
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);

  std::sort(ms.begin(), ms.end());
  const double median = ms[ms.size() / 2];
  const double p99 =
      ms[std::min(ms.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(ms.size())))];
  std::printf(
      "cell LOCATE benchmark: %dx%d, %d parts, %zu trained types with grasps, robot frame\n", width,
      height, parts, kTypes.size());
  std::printf("  %d requests (%d failed), %.2f grasps offered per reply (one type per request)\n",
              requests, failures,
              requests > failures ? static_cast<double>(offered) / (requests - failures) : 0.0);
  std::printf(
      "  round trip ms: median %.2f  p99 %.2f  min %.2f  max %.2f   (goal: median <= 10, p99 <= "
      "20)\n",
      median, p99, ms.front(), ms.back());
  std::printf(
      "  in process, same scene, median ms: recognition of %zu types %.2f, grasp selection and\n"
      "  robot frame %.3f\n",
      kTypes.size(), inside.recognition_ms, inside.grasps_ms);
  std::printf(
      "  replies digest %016llx (robot port, %d requests); in process %zu poses over 5\n"
      "  scenes x %zu types, digest %016llx\n",
      static_cast<unsigned long long>(replies_digest), requests, inside.poses, kTypes.size(),
      static_cast<unsigned long long>(inside.poses_digest));
  std::printf("  %s\n", status ? status->c_str() : "STATUS failed");
  return failures == 0 ? 0 : 1;
}
