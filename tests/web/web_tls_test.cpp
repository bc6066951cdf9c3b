// picksight-web over HTTPS (--tls-cert, --tls-key): a client that verifies
// the server's certificate (cpp-httplib's, with OpenSSL) logs in and gets a
// Secure cookie, a client trusting another certificate is refused, plain
// HTTP on the HTTPS port is told so, and --http-redirect only redirects.
// Certificates are made by the openssl tool for each test.
#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <memory>
#include <thread>
#include <vector>

#include <openssl/ssl.h>

#include "picksight/web/web_options.hpp"
#include "raw_http.hpp"
#include "temp_dir.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using e2e::VideoServerProcess;
using tool_support::Subprocess;

struct Certificate {
  std::string cert;
  std::string key;
};

// A self-signed certificate for localhost and 127.0.0.1, as the package's
// postinst makes one; the key 0600.
Certificate makeCertificate(const test::TempDir& dir, const std::string& name) {
  Certificate c{(dir.path() / (name + ".crt")).string(), (dir.path() / (name + ".key")).string()};
  Subprocess openssl({"/usr/bin/openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt",
                      "ec_paramgen_curve:prime256v1", "-nodes", "-days", "2", "-subj",
                      "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1",
                      "-keyout", c.key, "-out", c.cert});
  const auto status = openssl.wait(std::chrono::seconds(30));
  REQUIRE(status);
  REQUIRE(WIFEXITED(*status));
  REQUIRE(WEXITSTATUS(*status) == 0);
  REQUIRE(::chmod(c.key.c_str(), 0600) == 0);
  return c;
}

int portOf(const std::string& url) {
  auto p = parseInt(url.substr(url.rfind(':') + 1));
  REQUIRE(p);
  return static_cast<int>(*p);
}

}  // namespace

TEST_CASE("over HTTPS a verifying client logs in and gets a Secure cookie and changes the camera",
          "[web][tls]") {
  test::TempDir dir;
  const Certificate cert = makeCertificate(dir, "web");
  const Certificate other = makeCertificate(dir, "other");
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(),
              {"--tls-cert", cert.cert, "--tls-key", cert.key, "--http-redirect", "127.0.0.1:0"});
  WebProcess web(args, cert.cert);
  REQUIRE(web.https);
  REQUIRE(!web.cookie.empty());  // the fixture's login, over verified HTTPS

  auto anonymous = web.anonymousClient();
  auto res =
      postJson(anonymous, "/api/login", {{"user", "admin"}, {"password", web.admin_password}});
  REQUIRE(res);
  REQUIRE(res->status == 200);
  const std::string set = res->get_header_value("Set-Cookie");
  CHECK_THAT(set, Catch::Contains("; Secure") && Catch::Contains("HttpOnly") &&
                      Catch::Contains("SameSite=Strict"));
  auto admin = web.client();
  CHECK(admin.Get("/api/cameras")->status == 200);
  res = postJson(admin, "/api/cameras/cam0/feature", {{"name", "Parts"}, {"value", "2"}});
  REQUIRE(res);
  CHECK(res->status == 200);

  // A client that trusts another certificate does not talk to this server.
  httplib::Client stranger("https://127.0.0.1:" + std::to_string(web.port));
  stranger.set_ca_cert_path(other.cert.c_str());
  stranger.enable_server_certificate_verification(true);
  auto refused = stranger.Get("/");
  CHECK(!refused);
  CHECK(refused.error() == httplib::Error::SSLServerVerification);

  // Plain HTTP on the HTTPS port: told so at once, in plain HTTP.
  std::string raw = rawRequest(web.port, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  CHECK(statusOf(raw) == 400);
  CHECK_THAT(bodyOf(raw), Catch::Contains("HTTPS"));

  // The plain port redirects to the same name and path, and does nothing else.
  REQUIRE(!web.redirect_url.empty());
  const int plain = portOf(web.redirect_url);
  const std::string host = "Host: 127.0.0.1:" + std::to_string(plain) + "\r\n";
  raw =
      rawRequest(plain, "GET /static/app.js?v=2 HTTP/1.1\r\n" + host + "Connection: close\r\n\r\n");
  CHECK(statusOf(raw) == 301);
  const std::string location = headerOf(raw, "Location");
  CHECK(location == "https://127.0.0.1:" + std::to_string(web.port) + "/static/app.js?v=2");
  res = anonymous.Get("/static/app.js?v=2");
  REQUIRE(res);
  CHECK(res->status == 200);
  raw = rawRequest(plain, "GET / HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n");
  CHECK(headerOf(raw, "Location") == "https://localhost:" + std::to_string(web.port) + "/");
  raw = rawRequest(plain, "GET / HTTP/1.1\r\nHost: attacker.example\r\nConnection: close\r\n\r\n");
  CHECK(statusOf(raw) == 403);
  CHECK(headerOf(raw, "Location").empty());
  raw = rawRequest(plain, "POST /api/login HTTP/1.1\r\n" + host +
                              "Content-Type: application/json\r\nX-PickSight: 1\r\n"
                              "Content-Length: 2\r\nConnection: close\r\n\r\n{}");
  CHECK(statusOf(raw) == 403);
  CHECK(headerOf(raw, "Set-Cookie").empty());
}

TEST_CASE("TLS options go together and a key others may read is refused", "[web][tls]") {
  test::TempDir dir;
  const Certificate cert = makeCertificate(dir, "web");
  CHECK(web::parseWebArgs({"--tls-cert", cert.cert, "--tls-key", cert.key}, nullptr));
  auto alone = web::parseWebArgs({"--tls-cert", cert.cert}, nullptr);
  REQUIRE_FALSE(alone);
  CHECK_THAT(alone.error().message, Catch::Contains("--tls-key"));
  auto redirect = web::parseWebArgs({"--http-redirect", "127.0.0.1:0"}, nullptr);
  REQUIRE_FALSE(redirect);
  CHECK_THAT(redirect.error().message, Catch::Contains("--tls-cert"));
  // The file's TLS settings and the line's redirect together (the
  // package's unit: web.yaml, and a port given on the line).
  const std::string yaml =
      dir.write("web.yaml", "tls-cert: " + cert.cert + "\ntls-key: " + cert.key + "\n");
  auto merged = web::parseWebArgs({"--config", yaml, "--http-redirect", "127.0.0.1:0"}, nullptr);
  INFO((merged ? std::string() : merged.error().message));
  CHECK(merged);
  REQUIRE(::chmod(cert.key.c_str(), 0644) == 0);
  auto open = web::parseWebArgs({"--tls-cert", cert.cert, "--tls-key", cert.key}, nullptr);
  REQUIRE_FALSE(open);
  CHECK_THAT(open.error().message, Catch::Contains("others"));
  // A file that is no certificate: the server does not start.
  REQUIRE(::chmod(cert.key.c_str(), 0600) == 0);
  const std::string bogus = dir.write("bogus.crt", "not a certificate\n");
  Subprocess web({e2e::binPath("picksight-web"), "--listen", "127.0.0.1:0", "--tls-cert", bogus,
                  "--tls-key", cert.key});
  const auto status = web.wait(std::chrono::seconds(10));
  REQUIRE(status);
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 1);
}

TEST_CASE("over HTTPS a request not complete by the header timeout is cut but a stream is not",
          "[web][tls]") {
  test::TempDir dir;
  const Certificate cert = makeCertificate(dir, "web");
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(),
              {"--tls-cert", cert.cert, "--tls-key", cert.key, "--header-timeout", "1"});
  WebProcess web(args, cert.cert);
  REQUIRE(!web.cookie.empty());
  std::signal(SIGPIPE, SIG_IGN);  // writes to a socket the server shut down

  // A client that completes the handshake, then sends its header a byte
  // at a time: each byte would restart httplib's own read timeout.
  std::unique_ptr<SSL_CTX, decltype(&SSL_CTX_free)> context(SSL_CTX_new(TLS_client_method()),
                                                            SSL_CTX_free);
  REQUIRE(context);
  RawSocket socket(web.port);
  REQUIRE(socket.valid());
  std::unique_ptr<SSL, decltype(&SSL_free)> ssl(SSL_new(context.get()), SSL_free);
  SSL_set_fd(ssl.get(), socket.fd());
  REQUIRE(SSL_connect(ssl.get()) == 1);
  const std::string head = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  REQUIRE(SSL_write(ssl.get(), head.data(), static_cast<int>(head.size())) > 0);
  // Non-blocking from here: TLS 1.3 sends session tickets after the
  // handshake, which make the socket readable without a byte for us.
  ::fcntl(socket.fd(), F_SETFL, ::fcntl(socket.fd(), F_GETFL) | O_NONBLOCK);
  bool closed = false;
  for (int i = 0; i < 30 && !closed; ++i) {  // 6 s of trickling, at most
    pollfd p{socket.fd(), POLLIN, 0};
    if (::poll(&p, 1, 200) > 0) {
      char buffer[256];
      const int n = SSL_read(ssl.get(), buffer, sizeof(buffer));
      const int error = SSL_get_error(ssl.get(), n);
      closed = n <= 0 && error != SSL_ERROR_WANT_READ && error != SSL_ERROR_WANT_WRITE;
      continue;
    }
    const int n = SSL_write(ssl.get(), "X", 1);
    closed = n <= 0 && SSL_get_error(ssl.get(), n) != SSL_ERROR_WANT_WRITE;
  }
  CHECK(closed);

  // A stream's request arrived whole: it goes on past the deadline.
  auto client = web.client();
  client.set_read_timeout(std::chrono::seconds(5));
  int events = 0;
  auto res = client.Get("/events", [&](const char* data, size_t length) {
    const std::string chunk(data, length);
    for (size_t at = chunk.find("event: cameras"); at != std::string::npos;
         at = chunk.find("event: cameras", at + 1))
      ++events;
    return events < 4;  // 3 s of a stream that sends one a second
  });
  CHECK(events >= 4);
  // And the page is served as always.
  CHECK(web.client().Get("/api/cameras")->status == 200);
}

}  // namespace picksight::webtest

namespace picksight::webtest {

TEST_CASE("over HTTPS the page is served while more slow clients than server threads trickle",
          "[web][tls][security]") {
  test::TempDir dir;
  const Certificate cert = makeCertificate(dir, "web");
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  // 17 pool threads (--max-streams + 16); the slow clients are not cut
  // for a minute.
  args.insert(args.end(), {"--tls-cert", cert.cert, "--tls-key", cert.key, "--max-streams", "1",
                           "--header-timeout", "60"});
  WebProcess web(args, cert.cert);
  REQUIRE(!web.cookie.empty());
  std::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<SSL_CTX, decltype(&SSL_CTX_free)> context(SSL_CTX_new(TLS_client_method()),
                                                            SSL_CTX_free);
  REQUIRE(context);
  // 40 clients from two addresses (under the per-address cap), each past
  // its handshake with its request begun: a server thread reads each (the
  // request is encrypted: the gate cannot wait for it). On the pool's 17
  // threads the 18th handshake waited for a thread for the minute.
  struct Slow {
    std::unique_ptr<RawSocket> socket;
    std::unique_ptr<SSL, decltype(&SSL_free)> ssl{nullptr, SSL_free};
    bool started = false;
  };
  std::vector<Slow> slow(40);
  for (size_t i = 0; i < slow.size(); ++i) {
    slow[i].socket = std::make_unique<RawSocket>(web.port, "127.0.0." + std::to_string(2 + i % 2));
    REQUIRE(slow[i].socket->valid());
    const int fd = slow[i].socket->fd();
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
    slow[i].ssl.reset(SSL_new(context.get()));
    SSL_set_fd(slow[i].ssl.get(), fd);
    SSL_set_connect_state(slow[i].ssl.get());
  }
  const std::string head = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  size_t started = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (started < slow.size() && std::chrono::steady_clock::now() < give_up) {
    for (auto& s : slow) {
      if (s.started) continue;
      const int rc = SSL_do_handshake(s.ssl.get());
      if (rc == 1) {
        REQUIRE(SSL_write(s.ssl.get(), head.data(), static_cast<int>(head.size())) > 0);
        s.started = true;
        ++started;
        continue;
      }
      const int error = SSL_get_error(s.ssl.get(), rc);
      REQUIRE((error == SSL_ERROR_WANT_READ || error == SSL_ERROR_WANT_WRITE));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  CHECK(started == slow.size());
  // The page and the API answer while every slow client still holds its
  // connection.
  auto client = web.client();
  client.set_read_timeout(std::chrono::seconds(30));
  auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  auto cameras = client.Get("/api/cameras");
  REQUIRE(cameras);
  CHECK(cameras->status == 200);
  size_t open = 0;
  for (auto& s : slow) {
    char buffer[256];
    const int n = SSL_read(s.ssl.get(), buffer, sizeof buffer);
    open += n <= 0 && SSL_get_error(s.ssl.get(), n) == SSL_ERROR_WANT_READ;
  }
  CHECK(open == slow.size());
}

}  // namespace picksight::webtest
