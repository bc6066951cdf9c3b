// A subscriber process for the distribution benchmark: receives frames for a
// while and prints what it got, lost and how late (one-way latency from the
// frame's host timestamp to its arrival, same host clock).
//   picksight-bench-subscriber --frames E --camera C --seconds S [--bare]
//                              [--curve-server-key FILE [--curve-key FILE] --control E]
// --bare reads the benchmark's plain ZeroMQ messages (topic, 16-byte
// sequence + timestamp, payload) instead of PickSight frames.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight/cli/command_line.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"
#include "picksight/transport/frame_message.hpp"

int main(int argc, char** argv) {
  std::string endpoint;
  std::string camera = "cam0";
  double seconds = 5;
  bool bare = false;
  std::string curve_server_key;
  std::string curve_key;
  std::string control;
  picksight::cli::App app("Receives frames for a while; prints what it got, lost and how late.",
                          "picksight-bench-subscriber");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--frames", endpoint, "the frame PUB endpoint")->typeName("E")->required();
  app.addOption("--camera", camera, "camera to subscribe to")->typeName("C")->showDefault();
  app.addOption("--seconds", seconds, "how long to receive")
      ->typeName("S")
      ->check(picksight::cli::positiveNumber())
      ->showDefault();
  app.addFlag("--bare", bare, "read the benchmark's plain ZeroMQ messages");
  app.addOption("--curve-server-key", curve_server_key, "the server's public key: talk CURVE")
      ->typeName("FILE");
  app.addOption("--curve-key", curve_key, "this client's secret key file")->typeName("FILE");
  app.addOption("--control", control, "the control endpoint (with CURVE: the frames' key)")
      ->typeName("E");
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  std::optional<picksight::transport::CurveClientKeys> curve;
  if (!curve_server_key.empty()) {
    auto keys = picksight::transport::loadClientKeys(curve_key, curve_server_key);
    if (!keys) {
      std::fprintf(stderr, "picksight-bench-subscriber: %s\n", keys.error().message.c_str());
      return 2;
    }
    curve = std::move(*keys);
  }
  zmq::context_t context;
  std::vector<double> latency_ms;
  uint64_t received = 0;
  uint64_t lost = 0;
  uint64_t first_ns = 0;
  uint64_t last_ns = 0;
  std::printf("subscribed\n");
  std::fflush(stdout);
  const uint64_t end = picksight::monotonicNs() + static_cast<uint64_t>(seconds * 1e9);
  if (bare) {
    zmq::socket_t sub(context, zmq::socket_type::sub);
    sub.set(zmq::sockopt::rcvhwm, 12);
    sub.set(zmq::sockopt::subscribe, camera);
    sub.connect(endpoint);
    uint64_t last_seq = 0;
    while (picksight::monotonicNs() < end) {
      zmq::pollitem_t item{sub.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq::poll(&item, 1, std::chrono::milliseconds(100)) == 0) continue;
      zmq::message_t topic, stamp, payload;
      if (!sub.recv(topic) || !sub.recv(stamp) || !sub.recv(payload) || stamp.size() != 16)
        continue;
      uint64_t seq = 0, sent_ns = 0;
      std::memcpy(&seq, stamp.data(), 8);
      std::memcpy(&sent_ns, static_cast<const char*>(stamp.data()) + 8, 8);
      const uint64_t now = picksight::realtimeNs();
      if (received > 0 && seq > last_seq + 1) lost += seq - last_seq - 1;
      last_seq = seq;
      if (received == 0) first_ns = now;
      last_ns = now;
      ++received;
      latency_ms.push_back(static_cast<double>(now - sent_ns) / 1e6);
    }
  } else {
    picksight::transport::FrameSubscriber sub(context, endpoint, camera, 4, curve, control);
    while (picksight::monotonicNs() < end) {
      auto f = sub.receive(std::chrono::milliseconds(100));
      if (!f) continue;
      const uint64_t now = picksight::realtimeNs();
      if (received == 0) first_ns = now;
      last_ns = now;
      ++received;
      latency_ms.push_back(static_cast<double>(now - f->info.host_timestamp_ns) / 1e6);
    }
    lost = sub.framesLost();
  }
  std::sort(latency_ms.begin(), latency_ms.end());
  const double fps =
      received > 1 ? (received - 1) * 1e9 / static_cast<double>(last_ns - first_ns) : 0;
  const double median = latency_ms.empty() ? 0 : latency_ms[latency_ms.size() / 2];
  const double p99 =
      latency_ms.empty()
          ? 0
          : latency_ms[std::min(latency_ms.size() - 1, latency_ms.size() * 99 / 100)];
  std::printf("result %llu %llu %.2f %.3f %.3f\n", static_cast<unsigned long long>(received),
              static_cast<unsigned long long>(lost), fps, median, p99);
  return 0;
}
