// The web HMI's cost to a cell, against the real processes: a video server
// with two synthetic cameras (cam0 in trigger mode for the vision app, cam1
// free-running at 30 fps), picksight-vision and picksight-web.
//   1. LOCATE median and p99 with no viewer and with 4 browsers on every
//      camera (each an MJPEG stream and the page's /events stream of
//      results), after a warm-up of both, in rounds that alternate which goes
//      first so machine noise hits both (goal: p99 with viewers <= 1.1x
//      without); beside them, with no viewer but one thread of arithmetic
//      at the web server's idle priority: what any work sharing the cores
//      with the cell costs on this machine;
//   2. camera-to-client latency at the camera's size: from the frame's host
//      timestamp to a client's receipt and turbojpeg decode of the JPEG
//      (goal: median <= 100 ms at 1920x1080, 30 fps);
//   3. the JPEG encoding's CPU per camera (the server's own counter) and the
//      web server's CPU per extra viewer (getrusage of the process, /proc).
// Prints figures, never fails on them.
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include <httplib.h>
#include <zmq.hpp>

#include "bench_cell.hpp"
#include "locate_args.hpp"
#include "opencv_baseline.hpp"
#include "picksight.pb.h"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/control_client.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using picksight::bench::nearestRank;

uint64_t realtimeNs() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

// CPU seconds (user + system) a process has used so far, from /proc.
double processCpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t end = text.rfind(')');
  if (end == std::string::npos) return 0;
  std::istringstream fields(text.substr(end + 2));
  std::string skip;
  for (int i = 0; i < 11; ++i) fields >> skip;  // state .. cmajflt (fields 3..13)
  double utime = 0;
  double stime = 0;
  fields >> utime >> stime;
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// One MJPEG viewer on its own thread: reads the stream of `camera`, and
// with `decode` decodes every JPEG and records its latency (ms from the
// frame's host timestamp to the end of the decode).
class Viewer {
 public:
  // `cookie`: the session a browser's login gave it ("name=value").
  Viewer(int port, std::string cookie, std::string camera, bool decode)
      : client_("127.0.0.1", port),
        thread_([this, cookie = std::move(cookie), camera = std::move(camera), decode] {
          client_.set_default_headers({{"Cookie", cookie}});
          run(camera, decode);
        }) {}
  // Closes the connection at once: a viewer of the triggered camera waits
  // for its next frame, which may not come for seconds.
  ~Viewer() {
    stop_ = true;
    client_.stop();
    thread_.join();
  }
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;
  int frames() const { return frames_.load(); }
  std::vector<double> latencies() {
    std::lock_guard<std::mutex> lock(mutex_);
    return latencies_;
  }

 private:
  void run(const std::string& camera, bool decode) {
    httplib::Client& client = client_;
    client.set_read_timeout(5s);
    tjhandle decoder = tjInitDecompress();
    std::vector<unsigned char> pixels;
    std::string buffer;
    size_t need = 0;  // bytes the frame being received takes, once its head is read
    // In a cell the browsers are other machines: here they share the
    // cell's cores, so the LOCATE rounds' viewers run at the lowest
    // priority (the latency viewer, alone, does not), and every viewer reads
    // without scanning a frame again for each piece of it that arrives.
    if (!decode) setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
    while (!stop_) {
      buffer.clear();
      need = 0;
      client.Get(("/stream/" + camera + ".mjpg").c_str(), [&](const char* data, size_t size) {
        buffer.append(data, size);
        while (buffer.size() >= need) {
          const size_t start = buffer.find("--picksightframe\r\n");
          const size_t head_end = buffer.find("\r\n\r\n", start == std::string::npos ? 0 : start);
          if (start == std::string::npos || head_end == std::string::npos) break;
          const std::string head = buffer.substr(start, head_end - start);
          const auto field = [&](const std::string& name) {
            const size_t at = head.find(name + ": ");
            return at == std::string::npos ? 0ull : std::stoull(head.substr(at + name.size() + 2));
          };
          const size_t length = field("Content-Length");
          need = head_end + 4 + length;
          if (buffer.size() < need) break;
          if (decode) {
            int w = 0, h = 0, sub = 0, space = 0;
            const auto* jpeg = reinterpret_cast<const unsigned char*>(buffer.data() + head_end + 4);
            if (tjDecompressHeader3(decoder, jpeg, length, &w, &h, &sub, &space) == 0) {
              pixels.resize(static_cast<size_t>(w) * h * 3);
              tjDecompress2(decoder, jpeg, length, pixels.data(), w, 0, h, TJPF_BGR,
                            TJFLAG_FASTDCT);
              const double ms = (static_cast<double>(realtimeNs()) -
                                 static_cast<double>(field("X-Frame-Timestamp-Ns"))) /
                                1e6;
              std::lock_guard<std::mutex> lock(mutex_);
              latencies_.push_back(ms);
            }
          }
          ++frames_;
          buffer.erase(0, head_end + 4 + length);
          need = 0;
        }
        return !stop_;
      });
    }
    tjDestroy(decoder);
  }

  httplib::Client client_;  // its thread's, but for stop()
  std::atomic<bool> stop_{false};
  std::atomic<int> frames_{0};
  std::mutex mutex_;
  std::vector<double> latencies_;  // under mutex_
  std::thread thread_;
};

// One thread of pure arithmetic at SCHED_IDLE, the priority the web
// server's encoders and converters run at: it only ever gets a core the
// cell leaves free. The LOCATE figures beside it are the floor that any
// work at all sharing the machine with the cell costs here (two virtual
// cores), against which the viewers' cost is read.
class IdleBusyThread {
 public:
  IdleBusyThread()
      : thread_([this] {
          sched_param param{};
          // Left at normal priority, the row would overstate the floor.
          if (const int error = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param)) {
            std::fprintf(stderr,
                         "the busy thread stays at normal priority (SCHED_IDLE: %s): the "
                         "floor row is not the idle priority's\n",
                         std::strerror(error));
          }
          double x = 1.0;
          while (!stop_) {
            for (int i = 0; i < 100000; ++i) x = x * 1.0000001 + 1e-9;
          }
          sink_ = x;
        }) {}
  ~IdleBusyThread() {
    stop_ = true;
    thread_.join();
  }
  IdleBusyThread(const IdleBusyThread&) = delete;
  IdleBusyThread& operator=(const IdleBusyThread&) = delete;

 private:
  std::atomic<bool> stop_{false};
  double sink_ = 0;
  std::thread thread_;
};

// One page's event stream (/events) on its own thread, as every browser
// keeps open beside its MJPEG stream: counts the results received, at the
// viewers' low priority.
class EventsClient {
 public:
  EventsClient(int port, std::string cookie)
      : client_("127.0.0.1", port), thread_([this, cookie = std::move(cookie)] {
          client_.set_default_headers({{"Cookie", cookie}});
          run();
        }) {}
  ~EventsClient() {
    stop_ = true;
    client_.stop();
    thread_.join();
  }
  EventsClient(const EventsClient&) = delete;
  EventsClient& operator=(const EventsClient&) = delete;
  int results() const { return results_.load(); }

 private:
  void run() {
    client_.set_read_timeout(30s);  // a keepalive comes every 15 s
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
    std::string buffer;
    while (!stop_) {
      buffer.clear();
      client_.Get("/events", [&](const char* data, size_t size) {
        buffer.append(data, size);
        for (size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
          if (buffer.rfind("event: result\n", 0) == 0) ++results_;
          buffer.erase(0, end + 2);
        }
        return !stop_;
      });
    }
  }

  httplib::Client client_;  // its thread's, but for stop()
  std::atomic<bool> stop_{false};
  std::atomic<int> results_{0};
  std::thread thread_;
};

// The value of a metric line "name{labels} value" in /metrics, or -1.
double metric(int port, const std::string& cookie, const std::string& series) {
  httplib::Client client("127.0.0.1", port);
  auto res = client.Get("/metrics", {{"Cookie", cookie}});
  if (!res) return -1;
  const size_t at = res->body.find(series + " ");
  return at == std::string::npos ? -1 : std::stod(res->body.substr(at + series.size() + 1));
}

}  // namespace

int main(int argc, char** argv) {
  // A connection the server closed is a failed write, not the end of the
  // bench (and of its processes' cleanup).
  std::signal(SIGPIPE, SIG_IGN);
  // --requests: LOCATEs per condition, over kRounds rounds.
  const auto args = picksight::bench::parseLocateArgs(argc, argv, {240, 1920, 1080, 20});
  constexpr int kRounds = 6;
  constexpr int kViewersPerCamera = 4;
  const int per_round = std::max(1, args.requests / kRounds);
  const std::string bin = picksight::bench::binDir();

  picksight::bench::VideoServerRun server;
  server.process = std::make_unique<picksight::tool_support::Subprocess>(std::vector<std::string>{
      bin + "/picksight-video-server", "--source", picksight::bench::syntheticCamera(args),
      "--source",
      "cam1=synthetic:width=" + std::to_string(args.width) +
          ",height=" + std::to_string(args.height) + ",parts=8,seed=7",
      "--frames", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*", "--mode", "trigger"});
  const auto frames = server.process->waitForLine("frames ", 10s);
  const auto control = server.process->waitForLine("control ", 10s);
  const std::string data_dir = picksight::bench::makeDataDir();
  if (!frames || !control || data_dir.empty()) return 1;
  server.frames = *frames;
  server.control = *control;
  zmq::context_t context;
  {
    // cam1 free-runs at 30 fps: the full-rate camera the viewers watch.
    picksight::transport::ControlClient client(context, server.control, 5000ms);
    picksight::proto::ControlRequest mode;
    mode.mutable_set_mode()->set_camera("cam1");
    mode.mutable_set_mode()->set_mode(picksight::proto::FREERUN);
    mode.mutable_set_mode()->set_fps(30);
    if (!client.call(mode)) return 1;
  }
  // The results stream on a known endpoint, so that the web server follows
  // it as in a cell (the page draws every result over the frame).
  const std::string results = "ipc://" + data_dir + "/results";
  auto vision = picksight::bench::startVision(server, data_dir, {"--results-bind", results});
  if (!vision) return 1;
  // The page's commands would go to the third field; the bench sends none.
  picksight::tool_support::Subprocess web({bin + "/picksight-web", "--listen", "127.0.0.1:0",
                                           "--video-server", server.frames + "," + server.control,
                                           "--vision-app", "cam0," + results + ",127.0.0.1:9"});
  const auto password = web.waitForLine("admin-password ", 10s);
  const auto url = web.waitForLine("web http://127.0.0.1:", 10s);
  if (!password || !url) return 1;
  const int port = std::stoi(*url);
  // Every browser logs in (the page is served to sessions only): one
  // session for all of them, the first user's.
  std::string cookie;
  {
    httplib::Client client("127.0.0.1", port);
    auto res =
        client.Post("/api/login", {{"X-PickSight", "1"}},
                    "{\"user\":\"admin\",\"password\":\"" + *password + "\"}", "application/json");
    if (!res || res->status != 200) {
      std::fprintf(stderr, "web: login refused\n");
      return 1;
    }
    const std::string set = res->get_header_value("Set-Cookie");
    cookie = set.substr(0, set.find(';'));
  }
  {
    // Wait until the web server knows both cameras.
    httplib::Client client("127.0.0.1", port);
    const auto deadline = Clock::now() + 10s;
    while (Clock::now() < deadline) {
      auto res = client.Get("/api/cameras", {{"Cookie", cookie}});
      if (res && res->body.find("\"cam1\"") != std::string::npos &&
          res->body.find("\"cam0\"") != std::string::npos)
        break;
      std::this_thread::sleep_for(50ms);
    }
  }
  picksight::tool_support::LineClient* robot = &vision->robot;
  int failures = 0;
  const auto locate = [&](std::vector<double>& into) {
    const auto t0 = Clock::now();
    auto reply = robot->request("LOCATE 1", 10s);
    into.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    if (!reply || reply->rfind("OK", 0) != 0) ++failures;
  };
  std::printf("Web HMI benchmark: cam0 %dx%d trigger (LOCATE), cam1 %dx%d free-run 30 fps\n",
              args.width, args.height, args.width, args.height);

  // 1. LOCATE with and without viewers.
  std::vector<double> ignored;
  // A model, so that LOCATE does its whole pass: taught from one part alone
  // on the table, as an integrator would.
  const auto setParts = [&](int parts) {
    picksight::transport::ControlClient client(context, server.control, 5000ms);
    picksight::proto::ControlRequest request;
    request.mutable_set_feature()->set_camera("cam0");
    request.mutable_set_feature()->set_name("Parts");
    request.mutable_set_feature()->set_value(std::to_string(parts));
    return client.call(request).ok();
  };
  setParts(1);
  if (auto learned = robot->request("LEARN 1", 30s); !learned || learned->rfind("OK", 0) != 0)
    std::printf("LEARN failed: LOCATE finds no part\n");
  setParts(args.parts);
  // A browser: an MJPEG viewer and the page's event stream.
  struct Browser {
    Browser(int port, const std::string& cookie, const char* camera)
        : viewer(port, cookie, camera, false), events(port, cookie) {}
    Viewer viewer;
    EventsClient events;
  };
  const auto openViewers = [&] {
    std::vector<std::unique_ptr<Browser>> browsers;
    for (const char* camera : {"cam0", "cam1"})
      for (int v = 0; v < kViewersPerCamera; ++v)
        browsers.push_back(std::make_unique<Browser>(port, cookie, camera));
    // Measure once the free-running camera's viewers receive frames.
    const auto deadline = Clock::now() + 10s;
    while (browsers.back()->viewer.frames() < 2 && Clock::now() < deadline)
      std::this_thread::sleep_for(1ms);
    return browsers;
  };
  // The server learns that a viewer left only when it next writes to it,
  // which for the triggered camera is at its next frame: without this the
  // first LOCATE of a no-viewer phase would pay for encoding a JPEG nobody
  // reads. One trigger, then wait until /metrics counts no viewer. An event
  // stream, likewise, ends at the first result that cannot be written: two
  // LOCATEs outside the measures.
  const auto settle = [&] {
    for (int i = 0; i < 2; ++i) locate(ignored);
    picksight::transport::ControlClient client(context, server.control, 5000ms);
    picksight::proto::ControlRequest trigger;
    trigger.mutable_trigger()->set_camera("cam0");
    (void)client.call(trigger);
    const auto deadline = Clock::now() + 10s;
    while (Clock::now() < deadline &&
           (metric(port, cookie, "picksight_web_viewers{camera=\"cam0\"}") != 0 ||
            metric(port, cookie, "picksight_web_viewers{camera=\"cam1\"}") != 0))
      std::this_thread::sleep_for(20ms);
  };
  // Warm-up of both conditions: the first requests after start are slower
  // (allocations, caches, the new processes' first connections), and
  // measured in the first no-viewer phase they made its p99 alone.
  for (int i = 0; i < per_round; ++i) locate(ignored);
  {
    const auto viewers = openViewers();
    for (int i = 0; i < per_round / 2; ++i) locate(ignored);
  }
  settle();
  std::vector<double> alone;
  std::vector<double> watched;
  std::vector<double> busy;
  int viewer_frames = 0;
  int event_results = 0;
  double watched_s = 0;
  const auto watchedPhase = [&] {
    const auto browsers = openViewers();
    int before = 0;
    int results_before = 0;
    for (const auto& b : browsers) before += b->viewer.frames();
    for (const auto& b : browsers) results_before += b->events.results();
    const auto t0 = Clock::now();
    for (int i = 0; i < per_round; ++i) locate(watched);
    watched_s += std::chrono::duration<double>(Clock::now() - t0).count();
    for (const auto& b : browsers) viewer_frames += b->viewer.frames();
    for (const auto& b : browsers) event_results += b->events.results();
    viewer_frames -= before;
    event_results -= results_before;
  };
  // Rounds alternate which condition goes first, so that a drift of the
  // machine over a round falls on both.
  for (int round = 0; round < kRounds; ++round) {
    if (round % 2 == 1) {
      watchedPhase();
      settle();
    }
    for (int i = 0; i < per_round; ++i) locate(alone);
    if (round % 2 == 0) {
      watchedPhase();
      settle();
    }
    // No viewer, one idle-priority busy thread: half a round, between the
    // two conditions of the next.
    const IdleBusyThread busy_thread;
    for (int i = 0; i < per_round / 2; ++i) locate(busy);
  }
  const double a50 = nearestRank(alone, 50), a99 = nearestRank(alone, 99);
  const double w50 = nearestRank(watched, 50), w99 = nearestRank(watched, 99);
  std::printf("\n1. LOCATE 1 round trip, %d parts, %d rounds of %d per condition (%d failed)\n",
              args.parts, kRounds, per_round, failures);
  std::printf("  %-52s %8s %8s\n", "ms", "median", "p99");
  std::printf("  %-52s %8.2f %8.2f\n", "no viewer", a50, a99);
  std::printf("  %-52s %8.2f %8.2f\n", "4 browsers on each camera (8 MJPEG + 8 /events)", w50, w99);
  std::printf("  %-52s %7.2fx %7.2fx   (goal p99 <= 1.10x)\n", "ratio (viewers / none)",
              a50 > 0 ? w50 / a50 : 0.0, a99 > 0 ? w99 / a99 : 0.0);
  const double b50 = nearestRank(busy, 50), b99 = nearestRank(busy, 99);
  std::printf("  %-52s %8.2f %8.2f\n", "no viewer, one SCHED_IDLE arithmetic thread", b50, b99);
  std::printf("  %-52s %7.2fx %7.2fx   (the machine's floor for any work beside the cell)\n",
              "ratio (busy thread / none)", a50 > 0 ? b50 / a50 : 0.0, a99 > 0 ? b99 / a99 : 0.0);
  std::printf(
      "  (the viewers received %.1f frames/s in all during the watched rounds, and %d results "
      "as events)\n",
      watched_s > 0 ? viewer_frames / watched_s : 0.0, event_results);
  // Where the slowest requests fell: a systematic one (the same place in
  // every round) shows in its index.
  const auto slowest = [&](const char* what, const std::vector<double>& times) {
    std::vector<size_t> order(times.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    const size_t n = std::min<size_t>(6, order.size());
    std::partial_sort(order.begin(), order.begin() + static_cast<long>(n), order.end(),
                      [&](size_t a, size_t b) { return times[a] > times[b]; });
    std::printf("  slowest %s (ms, round.index in round):", what);
    for (size_t k = 0; k < n; ++k) {
      std::printf(" %.1f (%zu.%zu)", times[order[k]], order[k] / static_cast<size_t>(per_round),
                  order[k] % static_cast<size_t>(per_round));
    }
    std::printf("\n");
  };
  slowest("no viewer", alone);
  slowest("with viewers", watched);

  // 2. Latency, and 3. CPU: the free-running camera with 1, then 4 viewers.
  const auto encode_series =
      std::string("picksight_web_jpeg_encode_seconds_total{camera=\"cam1\"}");
  const auto cpuDuring = [&](int viewers_count, double seconds, std::vector<double>* latencies,
                             int* frames_out) {
    std::vector<std::unique_ptr<Viewer>> viewers;
    for (int v = 0; v < viewers_count; ++v)
      viewers.push_back(
          std::make_unique<Viewer>(port, cookie, "cam1", latencies != nullptr && v == 0));
    std::this_thread::sleep_for(1s);  // settle: connections, first frames
    const double encode0 = metric(port, cookie, encode_series);
    const double cpu0 = processCpuSeconds(web.pid());
    const int frames0 = viewers[0]->frames();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    const double cpu = processCpuSeconds(web.pid()) - cpu0;
    const double encode = metric(port, cookie, encode_series) - encode0;
    if (frames_out) *frames_out = viewers[0]->frames() - frames0;
    if (latencies) *latencies = viewers[0]->latencies();
    return std::make_pair(cpu / seconds, encode / seconds);
  };
  constexpr double kSeconds = 10;
  std::vector<double> latencies;
  int frames_one = 0;
  const auto one = cpuDuring(1, kSeconds, &latencies, &frames_one);
  const auto four = cpuDuring(4, kSeconds, nullptr, nullptr);
  std::printf(
      "\n2. Camera-to-client latency, cam1 %dx%d at 30 fps, one viewer decoding with "
      "turbojpeg\n",
      args.width, args.height);
  std::printf(
      "  frame host timestamp -> JPEG received and decoded: median %.1f ms, p90 %.1f ms, "
      "p99 %.1f ms over %zu frames (%.1f fps received; goal median <= 100 ms)\n",
      nearestRank(latencies, 50), nearestRank(latencies, 90), nearestRank(latencies, 99),
      latencies.size(), frames_one / kSeconds);
  std::printf("\n3. CPU of the web server (cores = CPU seconds per second), cam1 %dx%d at 30 fps\n",
              args.width, args.height);
  std::printf(
      "  JPEG encoding of the camera (server's counter):  %.3f cores with 1 viewer, "
      "%.3f with 4 (encoded once for all)\n",
      one.second, four.second);
  std::printf("  whole web process: %.3f cores with 1 viewer, %.3f with 4: %.3f per extra viewer\n",
              one.first, four.first, (four.first - one.first) / 3);

  robot->close();
  web.terminate();
  vision->process->terminate();
  server.process->terminate();
  std::error_code ec;
  std::filesystem::remove_all(data_dir, ec);
  return 0;
}
