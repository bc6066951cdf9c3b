// Frame distribution benchmark: one 1920x1080 mono8 camera at 60 fps to 1, 4
// and 8 subscriber processes over TCP loopback, through
// picksight-video-server, beside a bare ZeroMQ PUB/SUB of the same payloads
// at the same rate in the same run, and the same server with CURVE
// encryption. Prints delivered fps per subscriber, frames lost and one-way
// latency (median and 99th percentile); then the encryption cost of one
// frame (a PUB/SUB round trip, plain against CURVE, in one process).
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/curve_server.hpp"
#include "picksight/transport/frame_seal.hpp"

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
// `extra` goes on each subscriber's command line (its CURVE keys).
Summary runSubscribers(const std::string& dir, const std::string& endpoint, int count,
                       double seconds, bool bare, const std::vector<std::string>& extra = {}) {
  std::vector<std::unique_ptr<picksight::tool_support::Subprocess>> subs;
  for (int i = 0; i < count; ++i) {
    std::vector<std::string> argv = {
        dir + "/picksight-bench-subscriber", "--frames", endpoint, "--camera", "cam0", "--seconds",
        picksight::formatFixed(seconds, 1)};
    if (bare) argv.push_back("--bare");
    argv.insert(argv.end(), extra.begin(), extra.end());
    subs.push_back(std::make_unique<picksight::tool_support::Subprocess>(argv));
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

// A server and a client key pair in a fresh directory (removed by the caller).
struct BenchKeys {
  std::string dir;
  std::string server_secret, server_public, client_secret;
};

BenchKeys writeKeys() {
  char dir[] = "/tmp/picksight-bench-keys-XXXXXX";
  if (::mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp failed");
  BenchKeys k{dir, std::string(dir) + "/server.key_secret", std::string(dir) + "/server.key",
              std::string(dir) + "/client.key_secret"};
  for (const char* name : {"server", "client"}) {
    auto pair = picksight::transport::generateKeyPair();
    if (!pair) throw std::runtime_error(pair.error().message);
    const std::string base = std::string(dir) + "/" + name;
    if (!picksight::writeFileAtomically(base + ".key",
                                        picksight::transport::publicKeyFileText(*pair)) ||
        !picksight::writeFileAtomically(base + ".key_secret",
                                        picksight::transport::secretKeyFileText(*pair))) {
      throw std::runtime_error("cannot write keys in " + std::string(dir));
    }
    ::chmod((base + ".key_secret").c_str(), 0600);
  }
  return k;
}

// Milliseconds per 1920x1080 mono8 frame sent on a PUB and received on a
// SUB of another context (so each side has its own I/O thread), one at a
// time: the time of the frame's way, with CURVE its encryption and
// decryption as well.
double roundTripMs(const picksight::transport::CurveServer* curve,
                   const std::optional<picksight::transport::CurveClientKeys>& client, int frames) {
  zmq::context_t server_context;
  zmq::context_t client_context;
  zmq::socket_t pub(server_context, zmq::socket_type::pub);
  picksight::transport::secureServerSocket(pub, curve);
  pub.bind("tcp://127.0.0.1:*");
  zmq::socket_t sub(client_context, zmq::socket_type::sub);
  picksight::transport::secureClientSocket(sub, client);
  sub.set(zmq::sockopt::subscribe, "");
  sub.connect(pub.get(zmq::sockopt::last_endpoint));
  const std::vector<uint8_t> payload(1920 * 1080, 128);
  zmq::message_t received;
  // Until the subscription has arrived, frames are dropped: send until one passes.
  for (;;) {
    pub.send(zmq::buffer(payload), zmq::send_flags::none);
    zmq::pollitem_t item{sub.handle(), 0, ZMQ_POLLIN, 0};
    if (zmq::poll(&item, 1, std::chrono::milliseconds(50)) > 0) break;
  }
  while (sub.recv(received, zmq::recv_flags::dontwait)) {
  }
  const uint64_t start = picksight::monotonicNs();
  for (int i = 0; i < frames; ++i) {
    pub.send(zmq::buffer(payload), zmq::send_flags::none);
    if (!sub.recv(received)) return 0;
  }
  return static_cast<double>(picksight::monotonicNs() - start) / 1e6 / frames;
}

// As roundTripMs, the frame sealed once on the server's side and opened on
// the client's (frame_seal.hpp), on plain sockets: what a video server with
// CURVE now spends per frame, and each subscriber.
double sealedRoundTripMs(int frames) {
  zmq::context_t server_context;
  zmq::context_t client_context;
  zmq::socket_t pub(server_context, zmq::socket_type::pub);
  pub.bind("tcp://127.0.0.1:*");
  zmq::socket_t sub(client_context, zmq::socket_type::sub);
  sub.set(zmq::sockopt::subscribe, "");
  sub.connect(pub.get(zmq::sockopt::last_endpoint));
  const picksight::transport::FrameKey key = picksight::transport::newFrameKey();
  picksight::transport::FrameSealer sealer(key);
  picksight::Frame frame;
  frame.image = cv::Mat(1080, 1920, CV_8UC1, cv::Scalar(128));
  frame.info.camera = "cam0";
  const auto oneWay = [&](bool wait) {
    sealer.send(pub, frame);
    zmq::message_t topic, envelope, pixels;
    if (!wait) {
      zmq::pollitem_t item{sub.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq::poll(&item, 1, std::chrono::milliseconds(50)) == 0) return false;
    }
    if (!sub.recv(topic) || !sub.recv(envelope) || !sub.recv(pixels)) return false;
    return picksight::transport::openSealedFrame(topic, envelope, pixels, key).has_value();
  };
  // Until the subscription has arrived, frames are dropped: send until one passes.
  while (!oneWay(false)) {
  }
  const uint64_t start = picksight::monotonicNs();
  for (int i = 0; i < frames; ++i) {
    if (!oneWay(true)) return 0;
  }
  return static_cast<double>(picksight::monotonicNs() - start) / 1e6 / frames;
}

void row(const char* what, int n, const Summary& s) {
  std::printf("  %-28s %3d %10.1f %10.1f %8llu %10.2f %10.2f\n", what, n, s.fps_mean, s.fps_min,
              static_cast<unsigned long long>(s.lost), s.median_mean, s.p99_max);
}
}  // namespace

int main(int argc, char** argv) {
  double seconds = 5;
  picksight::cli::App app("Frame distribution benchmark: PickSight against bare ZeroMQ.",
                          "picksight-bench-distribution");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--seconds", seconds, "length of each run")
      ->typeName("S")
      ->check(picksight::cli::positiveNumber())
      ->showDefault();
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  const std::string dir = binDir();
  const BenchKeys keys = writeKeys();
  const std::vector<std::string> server_curve = {"--curve-secret-key", keys.server_secret};
  const std::vector<std::string> client_curve = {"--curve-server-key", keys.server_public,
                                                 "--curve-key", keys.client_secret};
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
      picksight::tool_support::Subprocess server({dir + "/picksight-video-server", "--source",
                                                  "cam0=synthetic:width=1920,height=1080,parts=20",
                                                  "--fps", "60", "--frames", "tcp://127.0.0.1:*",
                                                  "--control", "tcp://127.0.0.1:*"});
      auto frames = server.waitForLine("frames ", 10s);
      if (!frames) return 1;
      const Summary s = runSubscribers(dir, *frames, n, seconds, false);
      row("picksight-video-server", n, s);
    }
    {
      std::vector<std::string> argv = {dir + "/picksight-video-server",
                                       "--source",
                                       "cam0=synthetic:width=1920,height=1080,parts=20",
                                       "--fps",
                                       "60",
                                       "--frames",
                                       "tcp://127.0.0.1:*",
                                       "--control",
                                       "tcp://127.0.0.1:*"};
      argv.insert(argv.end(), server_curve.begin(), server_curve.end());
      picksight::tool_support::Subprocess server(argv);
      auto frames = server.waitForLine("frames ", 10s);
      auto control = server.waitForLine("control ", 10s);
      if (!frames || !control) return 1;
      std::vector<std::string> client = client_curve;
      client.insert(client.end(), {"--control", *control});
      const Summary s = runSubscribers(dir, *frames, n, seconds, false, client);
      row("video server CURVE, sealed", n, s);
    }
  }

  const int frames = 200;
  zmq::context_t keys_context;  // the CURVE server's (no allow-list: no ZAP thread)
  auto curve = picksight::transport::CurveServer::start(keys_context, keys.server_secret, "");
  auto client = picksight::transport::loadClientKeys(keys.client_secret, keys.server_public);
  if (!curve || !client) return 1;
  const double plain_ms = roundTripMs(nullptr, std::nullopt, frames);
  const double curve_ms = roundTripMs(curve->get(), *client, frames);
  std::printf(
      "Encryption cost, one 1920x1080 mono8 frame PUB -> SUB, one at a time, %d frames:\n"
      "  plain %.3f ms/frame, CURVE %.3f ms/frame: ratio %.2f, CURVE adds %.3f ms per frame "
      "(encrypt + decrypt, %.0f MB/s)\n",
      frames, plain_ms, curve_ms, curve_ms / plain_ms, curve_ms - plain_ms,
      1920.0 * 1080.0 / 1e6 / ((curve_ms - plain_ms) / 1e3));
  const double sealed_ms = sealedRoundTripMs(frames);
  std::printf(
      "  sealed once (what the video server does with CURVE): %.3f ms/frame, ratio %.2f to "
      "plain, adds %.3f ms per frame (seal + open)\n",
      sealed_ms, sealed_ms / plain_ms, sealed_ms - plain_ms);
  std::printf(
      "goals: 60 fps to 8 subscribers with CURVE, none lost (the sealed rows); the socket "
      "rows above compare what each frame costs\n");
  std::error_code ignored;
  std::filesystem::remove_all(keys.dir, ignored);
  return 0;
}
