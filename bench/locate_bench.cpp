// LOCATE round trip benchmark: a robot's request sent to its reply received,
// over TCP, fresh frame included (software trigger), at 1920x1080 with 20
// parts; printed beside a competent plain OpenCV pass (Otsu threshold +
// findContours with holes + moments), the labelling pass timed before, and
// PickSight's own vision pass on the same frames, in the same run.
//
// --scale S resizes the camera (S frame pixels per sensor pixel) after one
// part was learned at full size (--learn learns it without resizing), so
// that LOCATE recognizes with scaled models; --results-bind passes the
// vision app's results stream endpoint ("none": no stream), for comparing
// the two in one script.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <zmq.hpp>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "opencv_baseline.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct Stats {
  double median = 0;
  double p99 = 0;
  double min = 0;
};

// Median and p99 by nearest rank.
Stats stats(const std::vector<double>& ms) {
  Stats s;
  if (ms.empty()) return s;
  s.median = picksight::bench::nearestRank(ms, 50);
  s.p99 = picksight::bench::nearestRank(ms, 99);
  s.min = *std::min_element(ms.begin(), ms.end());
  return s;
}

double timeMs(const std::function<void()>& f) {
  const auto t0 = Clock::now();
  f();
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

size_t pickSightPass(const cv::Mat& grey) {
  const cv::Mat mask = picksight::vision::binarize(grey, {});
  return picksight::vision::findRegions(mask, {}, grey).size();
}

void row(const char* what, const Stats& s, double baseline) {
  std::printf("  %-44s %8.2f %8.2f %8.2f   %5.2fx\n", what, s.median, s.p99, s.min,
              baseline > 0 ? s.median / baseline : 0.0);
}

// The synthetic scene's part of largest room around it (its truth, sensor
// pixels), from a frame the robot's LOCATE triggers; nullopt when none came.
std::optional<picksight::TruthPart> loneTruthPart(zmq::context_t& context,
                                                  const std::string& frames,
                                                  picksight::tool_support::LineClient& robot) {
  picksight::transport::FrameSubscriber watcher(context, frames, "cam0", 8);
  const auto deadline = Clock::now() + 10s;
  while (Clock::now() < deadline) {
    (void)robot.request("LOCATE 1", 10s);
    auto frame = watcher.receive(500ms);
    if (!frame || frame->truth.empty()) continue;
    const auto& truth = frame->truth;
    std::optional<picksight::TruthPart> alone;
    double room = -1;
    for (const auto& t : truth) {
      double nearest = 1e300;
      for (const auto& o : truth)
        if (&o != &t) nearest = std::min(nearest, std::hypot(o.x - t.x, o.y - t.y));
      if (nearest > room) {
        room = nearest;
        alone = t;
      }
    }
    return alone;
  }
  return std::nullopt;
}

// LEARN 1 AT a box around the lone part, then the camera resized to
// `scale` (1: left alone). False, with a message, when either failed.
bool learnAndResize(zmq::context_t& context, const picksight::bench::VideoServerRun& server,
                    picksight::tool_support::LineClient& robot, double scale) {
  const auto part = loneTruthPart(context, server.frames, robot);
  if (!part) {
    std::cerr << "bench: no frame with parts to learn from\n";
    return false;
  }
  // The synthetic parts' longest side is 120 px: 100 px either way holds one.
  const int reach = 100;
  const std::string learn = "LEARN 1 bench AT " + std::to_string(std::lround(part->x) - reach) +
                            " " + std::to_string(std::lround(part->y) - reach) + " " +
                            std::to_string(2 * reach) + " " + std::to_string(2 * reach);
  const auto learned = robot.request(learn, 10s);
  if (!learned || learned->rfind("OK", 0) != 0) {
    std::cerr << "bench: " << learn << " -> " << (learned ? *learned : "no reply") << "\n";
    return false;
  }
  std::printf("learned: %s (a %s)\n", learned->c_str(), part->type.c_str());
  if (scale == 1) return true;
  picksight::transport::ControlClient control(context, server.control);
  picksight::proto::ControlRequest request;
  request.mutable_set_size()->set_camera("cam0");
  request.mutable_set_size()->set_scale(scale);
  if (auto resized = control.call(request); !resized) {
    std::cerr << "bench: camera size --scale " << scale << ": " << resized.error().message << "\n";
    return false;
  }
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  double scale = 1;
  bool learn = false;
  std::string results_bind;
  const auto args = picksight::bench::parseLocateArgs(
      argc, argv, {300, 1920, 1080, 20}, [&](picksight::cli::App& app) {
        app.addOption("--scale", scale,
                      "camera resize (frame px per sensor px) after learning one part at full "
                      "size; 1: no resize")
            ->check(picksight::cli::range(0.05, 1.0))
            ->showDefault();
        app.addFlag("--learn", learn, "learn one part before timing (implied by --scale)");
        app.addOption("--results-bind", results_bind,
                      "the vision app's results stream endpoint, 'none' for no stream (default: "
                      "the app's)");
      });
  const int requests = args.requests, width = args.width, height = args.height, parts = args.parts;
  auto server = picksight::bench::startVideoServer(picksight::bench::syntheticCamera(args));
  const std::string data_dir = picksight::bench::makeDataDir();
  if (!server || data_dir.empty()) return 1;
  std::vector<std::string> vision_options;
  if (!results_bind.empty()) vision_options = {"--results-bind", results_bind};
  auto vision = picksight::bench::startVision(*server, data_dir, vision_options);
  if (!vision) return 1;
  picksight::tool_support::LineClient* robot = &vision->robot;
  zmq::context_t context;
  if ((learn || scale != 1) && !learnAndResize(context, *server, *robot, scale)) return 1;

  // Warm-up: caches, page faults, TCP and ZeroMQ connections.
  for (int i = 0; i < 10; ++i) (void)robot->request("LOCATE 1", 10s);
  std::vector<double> round_trips;
  size_t found = 0;
  int failures = 0;
  for (int i = 0; i < requests; ++i) {
    std::string reply;
    round_trips.push_back(timeMs([&] {
      auto r = robot->request("LOCATE 1", 10s);
      reply = r ? *r : std::string();
    }));
    const auto words = picksight::splitFields(reply, " ");
    if (words.size() < 2 || words[0] != "OK") {
      ++failures;
    } else {
      found += static_cast<size_t>(picksight::parseInt(words[1]).value_or(0));
    }
  }
  // Frames of the same camera for the in-process passes, watched only now:
  // during the timed requests the vision app is the camera's one
  // subscriber, as in a cell, and a watcher would share the CPU and the
  // server's sends with it.
  picksight::transport::FrameSubscriber watcher(context, server->frames, "cam0", 64);
  std::this_thread::sleep_for(300ms);
  for (int i = 0; i < 20; ++i) (void)robot->request("LOCATE 1", 10s);
  robot->close();
  std::vector<cv::Mat> images;
  while (images.size() < 20) {
    auto f = watcher.receive(200ms);
    if (!f) break;
    images.push_back(f->image.clone());
  }
  vision->process->terminate();
  server->process->terminate();
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
  if (images.empty()) {
    std::cerr << "bench: no frames watched\n";
    return 1;
  }

  std::vector<double> plain;
  std::vector<double> labelling;
  std::vector<double> ours;
  double plain_sink = 0;
  size_t our_regions = 0;
  // 10 rounds over the frames (200 passes of each kind at 20 frames: enough
  // for a p99), the pass that runs first turning from frame to frame.
  size_t turn = 0;
  for (int round = 0; round < 10; ++round) {
    for (const auto& img : images) {
      picksight::bench::timeInTurn<3>(
          turn++,
          {[&] { plain_sink += picksight::bench::competentOpenCvPass(img); },
           [&] { plain_sink += picksight::bench::labellingOpenCvPass(img); },
           [&] { our_regions = pickSightPass(img); }},
          {&plain, &labelling, &ours});
    }
  }
  const Stats rt = stats(round_trips);
  const Stats base = stats(plain);
  std::printf(
      "LOCATE benchmark: %dx%d, %d parts, %d requests (%d failed), %.1f parts found per reply\n",
      width, height, parts, requests, failures,
      requests > failures ? static_cast<double>(found) / (requests - failures) : 0.0);
  std::printf("  %s, camera scale %.3g, results stream %s\n",
              learn || scale != 1 ? "one type learned" : "no model (every region)", scale,
              results_bind.empty() ? "on (the app's default)" : results_bind.c_str());
  std::printf("  %-44s %8s %8s %8s   %s\n", "ms", "median", "p99", "min", "vs OpenCV pass");
  row("plain OpenCV pass (Otsu+contours+moments)", base, base.median);
  row("PickSight vision pass (adaptive, sub-pixel)", stats(ours), base.median);
  row("LOCATE round trip over TCP, fresh frame", rt, base.median);
  row("old pass, with CC labels (Otsu+CC+contours)", stats(labelling), base.median);
  std::printf(
      "  (%zu regions per frame in the PickSight pass; %zu frames, %zu passes of each kind, in "
      "turns;\n   p99 by nearest rank)\n",
      our_regions, images.size(), plain.size());
  return failures == 0 && plain_sink > 0 ? 0 : 1;
}
