// The web HMI beside slow clients, against the real processes (a video
// server with a synthetic camera and picksight-web): the time to answer
// GET / (the page) and GET /api/cameras (with a session) on a fresh
// connection each, first with nobody else connected, then beside N sockets
// (200 by default) that each send one header byte every few seconds and
// never finish their request, as a slow-loris client does. Those come from
// 127.0.0.2, 127.0.0.3... (--per-source each, under the server's
// per-address cap of 32) and reconnect when the server closes them at its
// header deadline, so N are pending all the time. --tls: the same over
// HTTPS (a self-signed certificate from the openssl tool), each slow socket
// past its handshake before it trickles. Issue 32's goal: the page answers
// within 1 s. Prints median, p99 and max per row, and the web server's
// resident memory; never fails on them.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>
#include <openssl/ssl.h>

#include "locate_args.hpp"
#include "picksight/cli/command_line.hpp"
#include "picksight/tool_support/subprocess.hpp"

namespace {
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct Args {
  int slow = 200;           // slow sockets
  int per_source = 10;      // slow sockets per source address
  double byte_every_s = 3;  // each slow socket's byte interval
  double seconds = 20;      // per row
  int every_ms = 50;        // between two timed requests
  bool tls = false;         // HTTPS, with a self-signed certificate
};

// "https://127.0.0.1:port" or "http://..."
std::string baseUrl(int port, bool tls) {
  return std::string(tls ? "https" : "http") + "://127.0.0.1:" + std::to_string(port);
}

// nearest-rank percentile
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size(), std::max<size_t>(rank, 1)) - 1];
}

// The slow sockets, kept at their number by one thread: one header byte
// per socket every `byte_every`, staggered; a socket the server closed is
// opened again at once. With TLS each first completes its handshake (the
// server's threads do that part), without waiting for it.
class SlowClients {
 public:
  SlowClients(int port, const Args& args, SSL_CTX* tls) : port_(port), args_(args), tls_(tls) {
    const auto interval = std::chrono::duration<double>(args.byte_every_s);
    for (int i = 0; i < args.slow; ++i) {
      Slow s;
      s.from = "127.0.0." + std::to_string(2 + i / args.per_source);
      open(s);
      s.next = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                  interval * (static_cast<double>(i) / args.slow));
      slow_.push_back(s);
    }
    thread_ = std::thread([this, interval] {
      while (!stop_) {
        int open_now = 0;
        int started = 0;
        for (auto& s : slow_) {
          if (s.fd >= 0 && !step(s, interval)) {
            close(s);
            ++closed_;
          }
          if (s.fd < 0) open(s);
          open_now += s.fd >= 0;
          started += s.started;
        }
        open_ = open_now;
        started_ = started;
        std::this_thread::sleep_for(20ms);
      }
    });
  }
  ~SlowClients() {
    stop_ = true;
    thread_.join();
    for (auto& s : slow_) close(s);
  }
  int open() const { return open_; }
  int started() const { return started_; }
  int closed() const { return closed_; }
  int failed() const { return failed_; }

 private:
  struct Slow {
    std::string from;
    int fd = -1;
    SSL* ssl = nullptr;    // with TLS
    bool started = false;  // the request's first line sent (after the handshake)
    Clock::time_point next;
  };

  // A connection from `s.from` to 127.0.0.1:port, non-blocking.
  void open(Slow& s) {
    s.fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    ::inet_pton(AF_INET, s.from.c_str(), &local.sin_addr);
    sockaddr_in peer{};
    peer.sin_family = AF_INET;
    peer.sin_port = htons(static_cast<uint16_t>(port_));
    ::inet_pton(AF_INET, "127.0.0.1", &peer.sin_addr);
    if (s.fd < 0 || ::bind(s.fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0 ||
        ::connect(s.fd, reinterpret_cast<sockaddr*>(&peer), sizeof peer) != 0) {
      close(s);
      ++failed_;
      return;
    }
    ::fcntl(s.fd, F_SETFL, ::fcntl(s.fd, F_GETFL) | O_NONBLOCK);
    s.started = false;
    if (tls_) {
      s.ssl = SSL_new(tls_);
      SSL_set_fd(s.ssl, s.fd);
      SSL_set_connect_state(s.ssl);
    }
  }

  static void close(Slow& s) {
    if (s.ssl) SSL_free(s.ssl);
    if (s.fd >= 0) ::close(s.fd);
    s.ssl = nullptr;
    s.fd = -1;
    s.started = false;
  }

  static bool write(Slow& s, const std::string& bytes) {
    if (!s.ssl)
      return ::send(s.fd, bytes.data(), bytes.size(), MSG_NOSIGNAL | MSG_DONTWAIT) ==
             static_cast<ssize_t>(bytes.size());
    return SSL_write(s.ssl, bytes.data(), static_cast<int>(bytes.size())) > 0;
  }

  // Moves `s` on (handshake, first line, a byte when due); false once the
  // server has closed it (or answered it: a 408, then the close).
  bool step(Slow& s, std::chrono::duration<double> interval) {
    if (!s.started) {
      if (s.ssl) {
        const int rc = SSL_do_handshake(s.ssl);
        if (rc != 1) {
          const int error = SSL_get_error(s.ssl, rc);
          return error == SSL_ERROR_WANT_READ || error == SSL_ERROR_WANT_WRITE;
        }
      }
      if (!write(s, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")) return false;
      s.started = true;
    }
    char buffer[512];
    if (s.ssl) {
      const int n = SSL_read(s.ssl, buffer, sizeof buffer);
      if (n <= 0 && SSL_get_error(s.ssl, n) != SSL_ERROR_WANT_READ) return false;
    } else {
      const ssize_t n = ::recv(s.fd, buffer, sizeof buffer, MSG_DONTWAIT);
      if (n >= 0 || (errno != EAGAIN && errno != EWOULDBLOCK)) return false;
    }
    if (Clock::now() >= s.next) {
      if (!write(s, "X")) return false;
      s.next += std::chrono::duration_cast<Clock::duration>(interval);
    }
    return true;
  }

  const int port_;
  const Args args_;
  SSL_CTX* const tls_;
  std::vector<Slow> slow_;  // the thread's once it runs
  std::atomic<bool> stop_{false};
  std::atomic<int> open_{0};
  std::atomic<int> started_{0};
  std::atomic<int> closed_{0};
  std::atomic<int> failed_{0};
  std::thread thread_;
};

// The resident memory of process `pid` in MiB, from /proc (0 if unknown).
double residentMiB(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

struct Timings {
  std::vector<double> page_ms;
  std::vector<double> api_ms;
  int failures = 0;
};

// GET / and GET /api/cameras in turn, each on a new connection (as a
// browser opening the page would), for `seconds`.
Timings timeRequests(int port, const std::string& cookie, const Args& args) {
  const std::string url = baseUrl(port, args.tls);
  Timings t;
  const auto end = Clock::now() + std::chrono::duration<double>(args.seconds);
  while (Clock::now() < end) {
    for (const bool page : {true, false}) {
      httplib::Client client(url);
      client.enable_server_certificate_verification(false);  // the bench's own certificate
      client.set_connection_timeout(10s);
      client.set_read_timeout(10s);
      httplib::Headers headers;
      if (!page) headers.emplace("Cookie", cookie);
      const auto t0 = Clock::now();
      auto res = client.Get(page ? "/" : "/api/cameras", headers);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!res || res->status != 200) {
        ++t.failures;
        continue;
      }
      (page ? t.page_ms : t.api_ms).push_back(ms);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(args.every_ms));
  }
  return t;
}

void printRow(const char* what, const char* path, const std::vector<double>& ms) {
  const double max = ms.empty() ? 0 : *std::max_element(ms.begin(), ms.end());
  std::printf("  %-34s %-13s %6zu %9.2f %9.2f %9.2f   %s\n", what, path, ms.size(),
              percentile(ms, 50), percentile(ms, 99), max, max < 1000 ? "yes" : "NO");
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  picksight::cli::App app("picksight-web beside slow clients: page and API latency.", argv[0]);
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--slow", args.slow, "slow sockets")
      ->check(picksight::cli::range(0, 2000))
      ->showDefault();
  app.addOption("--per-source", args.per_source, "slow sockets per source address 127.0.0.x")
      ->check(picksight::cli::range(1, 1000))
      ->showDefault();
  app.addOption("--byte-every", args.byte_every_s, "seconds between a slow socket's bytes")
      ->check(picksight::cli::range(0.05, 60.0))
      ->showDefault();
  app.addOption("--seconds", args.seconds, "seconds per row")
      ->check(picksight::cli::range(1.0, 3600.0))
      ->showDefault();
  app.addFlag("--tls", args.tls,
              "HTTPS with a self-signed certificate (as the Debian package serves it); the slow "
              "sockets complete their handshake first");
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  if ((args.slow + args.per_source - 1) / args.per_source > 250) {
    std::fprintf(stderr, "--slow / --per-source: more than 250 source addresses\n");
    return 2;
  }

  const std::string bin = picksight::bench::binDir();
  picksight::tool_support::Subprocess server(
      {bin + "/picksight-video-server", "--source", "cam0=synthetic:width=640,height=480,parts=4",
       "--fps", "10", "--frames", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*"});
  const auto frames = server.waitForLine("frames ", 10s);
  const auto control = server.waitForLine("control ", 10s);
  if (!frames || !control) return 1;
  std::vector<std::string> command{bin + "/picksight-web", "--listen", "127.0.0.1:0",
                                   "--video-server", *frames + "," + *control};
  char dir[] = "/tmp/picksight-bench-tls-XXXXXX";
  if (args.tls) {
    if (!::mkdtemp(dir)) return 1;
    const std::string cert = std::string(dir) + "/web.crt";
    const std::string key = std::string(dir) + "/web.key";
    picksight::tool_support::Subprocess openssl({"/usr/bin/openssl", "req", "-x509", "-newkey",
                                                 "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                                                 "-nodes", "-days", "2", "-subj", "/CN=localhost",
                                                 "-keyout", key, "-out", cert});
    if (openssl.wait(30s) != 0) {
      std::fprintf(stderr, "openssl could not make a certificate\n");
      return 1;
    }
    command.insert(command.end(), {"--tls-cert", cert, "--tls-key", key});
  }
  picksight::tool_support::Subprocess web(command);
  const auto password = web.waitForLine("admin-password ", 10s);
  const auto url =
      web.waitForLine(args.tls ? "web https://127.0.0.1:" : "web http://127.0.0.1:", 10s);
  if (args.tls) std::filesystem::remove_all(dir);  // read at the start
  if (!password || !url) return 1;
  const int port = std::stoi(*url);
  std::unique_ptr<SSL_CTX, decltype(&SSL_CTX_free)> tls(
      args.tls ? SSL_CTX_new(TLS_client_method()) : nullptr, SSL_CTX_free);
  std::string cookie;
  {
    httplib::Client client(baseUrl(port, args.tls));
    client.enable_server_certificate_verification(false);
    auto res =
        client.Post("/api/login", {{"X-PickSight", "1"}},
                    "{\"user\":\"admin\",\"password\":\"" + *password + "\"}", "application/json");
    if (!res || res->status != 200) return 1;
    const std::string set = res->get_header_value("Set-Cookie");
    cookie = set.substr(0, set.find(';'));
  }

  std::printf(
      "picksight-web beside slow clients over %s: GET / and GET /api/cameras, a new connection "
      "each, every %d ms for %.0f s per row\n",
      args.tls ? "HTTPS" : "plain HTTP", args.every_ms, args.seconds);
  std::printf(
      "slow clients: %d sockets from %d addresses (127.0.0.2...), one header byte each "
      "every %.1f s, reopened when the server closes them\n",
      args.slow, (args.slow + args.per_source - 1) / args.per_source, args.byte_every_s);
  std::printf("  %-34s %-13s %6s %9s %9s %9s   %s\n", "row", "path", "n", "median ms", "p99 ms",
              "max ms", "goal: max < 1000 ms");
  Args warm_up = args;
  warm_up.seconds = 1;
  timeRequests(port, cookie, warm_up);
  const Timings alone = timeRequests(port, cookie, args);
  const double rss_alone = residentMiB(web.pid());
  printRow("no slow client", "/", alone.page_ms);
  printRow("no slow client", "/api/cameras", alone.api_ms);
  Timings beside;
  double rss_beside = 0;
  int open_at_end = 0;
  int closed = 0;
  int failed = 0;
  {
    SlowClients slow(port, args, tls.get());
    // Every slow socket connected and past its first byte.
    std::this_thread::sleep_for(std::chrono::duration<double>(args.byte_every_s) + 500ms);
    const int open_at_start = slow.open();
    const int started_at_start = slow.started();
    beside = timeRequests(port, cookie, args);
    rss_beside = residentMiB(web.pid());
    open_at_end = slow.open();
    closed = slow.closed();
    failed = slow.failed();
    const std::string row = "beside " + std::to_string(open_at_start) + " slow sockets";
    if (args.tls)
      std::printf("  (%d of the %d slow sockets past their handshake when the row started)\n",
                  started_at_start, open_at_start);
    printRow(row.c_str(), "/", beside.page_ms);
    printRow(row.c_str(), "/api/cameras", beside.api_ms);
  }
  std::printf("failed requests: %d alone, %d beside the slow sockets\n", alone.failures,
              beside.failures);
  std::printf("picksight-web resident memory: %.1f MiB alone, %.1f MiB beside the slow sockets\n",
              rss_alone, rss_beside);
  std::printf(
      "slow sockets: %d open at the end, %d closed by the server (header deadline, per-address "
      "cap) and "
      "reopened, %d connections refused\n",
      open_at_end, closed, failed);
  return 0;
}
