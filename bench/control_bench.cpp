// LOCATE round trip while another client snaps over the control socket: the
// real picksight-video-server (synthetic camera, trigger mode) and
// picksight-vision, LOCATE alone and LOCATE during a snap loop measured in
// alternating rounds so machine noise hits both; prints median, p99 and their
// ratio (the control plane's goal: during snaps within 2x of alone).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "picksight.pb.h"
#include "picksight/tool_support/line_client.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/control_client.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct Figures {
  double median = 0;
  double p99 = 0;  // nearest rank
};

Figures figures(std::vector<double> ms) {
  Figures f;
  if (ms.empty()) return f;
  std::sort(ms.begin(), ms.end());
  f.median = ms[ms.size() / 2];
  const auto rank = static_cast<size_t>(std::ceil(0.99 * static_cast<double>(ms.size())));
  f.p99 = ms[std::max<size_t>(rank, 1) - 1];
  return f;
}

// Snaps `camera` back to back on its own control connection while running.
class SnapLoop {
 public:
  SnapLoop(zmq::context_t& context, const std::string& control, const std::string& camera)
      : thread_([this, &context, control, camera] {
          picksight::transport::ControlClient client(context, control, 5000ms);
          picksight::proto::ControlRequest snap;
          snap.mutable_snap()->set_camera(camera);
          while (!stop_) {
            if (client.call(snap)) {
              ++snaps_;
            } else {
              ++failures_;
            }
          }
        }) {}
  ~SnapLoop() {
    stop_ = true;
    thread_.join();
  }
  SnapLoop(const SnapLoop&) = delete;
  SnapLoop& operator=(const SnapLoop&) = delete;
  int snaps() const { return snaps_; }
  int failures() const { return failures_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<int> snaps_{0};
  std::atomic<int> failures_{0};
  std::thread thread_;
};
}  // namespace

int main(int argc, char** argv) {
  // --requests: LOCATEs per condition, spread over kRounds rounds.
  const auto args = picksight::bench::parseLocateArgs(argc, argv, {240, 1920, 1080, 20});
  constexpr int kRounds = 6;
  const int per_round = std::max(1, args.requests / kRounds);
  auto server = picksight::bench::startVideoServer(picksight::bench::syntheticCamera(args));
  const std::string data_dir = picksight::bench::makeDataDir();
  if (!server || data_dir.empty()) return 1;
  auto vision = picksight::bench::startVision(*server, data_dir);
  if (!vision) return 1;
  picksight::tool_support::LineClient* robot = &vision->robot;

  zmq::context_t context;
  int failures = 0;
  const auto locate = [&](std::vector<double>& into) {
    const auto t0 = Clock::now();
    auto reply = robot->request("LOCATE 1", 10s);
    into.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (!reply || reply->rfind("OK", 0) != 0) ++failures;
  };

  // Warm-up: caches, page faults, TCP and ZeroMQ connections.
  std::vector<double> ignored;
  for (int i = 0; i < 10; ++i) locate(ignored);
  {
    SnapLoop warm(context, server->control, "cam0");
    for (int i = 0; i < 5; ++i) locate(ignored);
  }

  std::vector<double> alone;
  std::vector<double> snapping;
  int snaps = 0;
  int snap_failures = 0;
  double snapping_s = 0;
  for (int round = 0; round < kRounds; ++round) {
    for (int i = 0; i < per_round; ++i) locate(alone);
    SnapLoop loop(context, server->control, "cam0");
    // Measure only once the loop is snapping.
    const auto deadline = Clock::now() + 10s;
    while (loop.snaps() == 0 && loop.failures() == 0 && Clock::now() < deadline) {
      std::this_thread::sleep_for(1ms);
    }
    const auto t0 = Clock::now();
    const int before = loop.snaps();
    for (int i = 0; i < per_round; ++i) locate(snapping);
    snapping_s += std::chrono::duration<double>(Clock::now() - t0).count();
    snaps += loop.snaps() - before;
    snap_failures += loop.failures();
  }
  robot->close();
  vision->process->terminate();
  server->process->terminate();
  std::error_code ec;
  std::filesystem::remove_all(data_dir, ec);

  const Figures a = figures(alone);
  const Figures s = figures(snapping);
  std::printf(
      "Control plane benchmark: LOCATE at %dx%d, %d parts, %d rounds of %d requests per "
      "condition (%d LOCATE failed, %d snaps failed)\n",
      args.width, args.height, args.parts, kRounds, per_round, failures, snap_failures);
  std::printf("  %-40s %8s %8s\n", "ms", "median", "p99");
  std::printf("  %-40s %8.2f %8.2f\n", "LOCATE alone", a.median, a.p99);
  std::printf("  %-40s %8.2f %8.2f\n", "LOCATE while a client snaps in a loop", s.median, s.p99);
  std::printf("  %-40s %7.2fx %7.2fx\n", "ratio (during snaps / alone)",
              a.median > 0 ? s.median / a.median : 0.0, a.p99 > 0 ? s.p99 / a.p99 : 0.0);
  std::printf("  (%.1f snaps/s of %dx%d during the loaded rounds)\n",
              snapping_s > 0 ? snaps / snapping_s : 0.0, args.width, args.height);
  return 0;
}
