// Frame distribution benchmark: one 1920x1080 mono8 camera at 60 fps to 1, 4
// and 8 subscriber processes over TCP loopback, through
// picksight-video-server, beside a bare ZeroMQ PUB/SUB of the same payloads
// at the same rate in the same run. Prints delivered fps per subscriber,
// frames lost and one-way latency (median and 99th percentile).
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "picksight/common/clock.hpp"
#include "picksight/common/command_line.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/subprocess.hpp"

namespace {
using namespace std::chrono_literals;

std::string binDir() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  std::string p(path, n > 0 ? static_cast<size_t>(n) : 0);
  return p.substr(0, p.find_last_of('/'));
}

struct Summary {
  double fps_min = 1e9, fps_mean = 0;
  uint64_t lost = 0, received = 0;
  double median_mean = 0, p99_max = 0;
};

// Starts `count` subscribers, waits until each subscribed, lets them run.
Summary runSubscribers(const std::string& dir, const std::string& endpoint, int count,
                       double seconds, bool bare) {
  std::vector<std::unique_ptr<picksight::Subprocess>> subs;
  for (int i = 0; i < count; ++i) {
    std::vector<std::string> argv = {
        dir + "/picksight-bench-subscriber", "--frames", endpoint, "--camera", "cam0", "--seconds",
        picksight::formatFixed(seconds, 1)};
    if (bare) argv.push_back("--bare");
    subs.push_back(std::make_unique<picksight::Subprocess>(argv));
    subs.back()->waitForLine("subscribed", 5s);
  }
  Summary s;
  for (auto& p : subs) {
    auto line = p->waitForLine("result ",
                               std::chrono::milliseconds(static_cast<int>(seconds * 1000) + 10000));
    if (!line) continue;
    unsigned long long received = 0, lost = 0;
    double fps = 0, median = 0, p99 = 0;
    if (std::sscanf(line->c_str(), "%llu %llu %lf %lf %lf", &received, &lost, &fps, &median,
                    &p99) != 5)
      continue;
    s.received += received;
    s.lost += lost;
    s.fps_min = std::min(s.fps_min, fps);
    s.fps_mean += fps / count;
    s.median_mean += median / count;
    s.p99_max = std::max(s.p99_max, p99);
  }
  return s;
}

// A bare PUB sending 1920x1080 payloads at `fps` until stopped.
void barePublisher(zmq::context_t& context, const std::string& endpoint, double fps,
                   std::atomic<bool>& stop, std::string* bound) {
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::sndhwm, 12);
  pub.bind(endpoint);
  *bound = pub.get(zmq::sockopt::last_endpoint);
  std::vector<uint8_t> payload(1920 * 1080, 128);
  const auto period = std::chrono::duration<double>(1.0 / fps);
  auto next = std::chrono::steady_clock::now();
  uint64_t seq = 0;
  while (!stop) {
    std::this_thread::sleep_until(next);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    ++seq;
    const uint64_t now = picksight::realtimeNs();
    char stamp[16];
    std::memcpy(stamp, &seq, 8);
    std::memcpy(stamp + 8, &now, 8);
    pub.send(zmq::buffer(std::string("cam0")), zmq::send_flags::sndmore);
    pub.send(zmq::buffer(stamp, 16), zmq::send_flags::sndmore);
    pub.send(zmq::buffer(payload), zmq::send_flags::none);
  }
}

void row(const char* what, int n, const Summary& s) {
  std::printf("  %-28s %3d %10.1f %10.1f %8llu %10.2f %10.2f\n", what, n, s.fps_mean, s.fps_min,
              static_cast<unsigned long long>(s.lost), s.median_mean, s.p99_max);
}
}  // namespace

int main(int argc, char** argv) {
  double seconds = 5;
  CLI::App app("Frame distribution benchmark: PickSight against bare ZeroMQ.",
               "picksight-bench-distribution");
  app.set_help_flag("-h,--help", "print this help");
  app.add_option("--seconds", seconds, "length of each run")
      ->type_name("S")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  if (auto exit_code = picksight::parseMainArgs(app, argc, argv)) return *exit_code;
  const std::string dir = binDir();
  std::printf("Distribution benchmark: 1920x1080 mono8 at 60 fps, %.0f s per run, TCP loopback\n",
              seconds);
  std::printf("  %-28s %3s %10s %10s %8s %10s %10s\n", "publisher", "subs", "fps mean", "fps min",
              "lost", "lat med ms", "lat p99 ms");
  for (int n : {1, 4, 8}) {
    {
      zmq::context_t context;
      std::atomic<bool> stop{false};
      std::string bound;
      std::thread pub([&] { barePublisher(context, "tcp://127.0.0.1:*", 60, stop, &bound); });
      while (bound.empty()) std::this_thread::sleep_for(10ms);
      const Summary s = runSubscribers(dir, bound, n, seconds, true);
      stop = true;
      pub.join();
      row("bare ZeroMQ PUB/SUB", n, s);
    }
    {
      picksight::Subprocess server({dir + "/picksight-video-server", "--source",
                                    "cam0=synthetic:width=1920,height=1080,parts=20", "--fps", "60",
                                    "--frames", "tcp://127.0.0.1:*", "--control",
                                    "tcp://127.0.0.1:*"});
      auto frames = server.waitForLine("frames ", 10s);
      if (!frames) return 1;
      const Summary s = runSubscribers(dir, *frames, n, seconds, false);
      row("picksight-video-server", n, s);
    }
  }
  return 0;
}
