// The HTTP routes of picksight-web over cpp-httplib.
#include "picksight/web/web_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <strings.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include <httplib.h>
#include <sodium.h>

#include <opencv2/imgproc.hpp>
#include <zmq.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/web/access_policy.hpp"
#include "picksight/web/audit_trail.hpp"
#include "picksight/web/camera_actions.hpp"
#include "picksight/web/camera_monitor.hpp"
#include "picksight/web/event_hub.hpp"
#include "picksight/web/filmstrip_view.hpp"
#include "picksight/web/http_gate.hpp"
#include "picksight/web/idle_worker.hpp"
#include "picksight/web/metrics_text.hpp"
#include "picksight/web/proto_json.hpp"
#include "picksight/web/refusal_log.hpp"
#include "picksight/web/request_guard.hpp"
#include "picksight/web/result_feed.hpp"
#include "picksight/web/sessions.hpp"
#include "picksight/web/user_store.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {

using transport::ControlErrc;

namespace {
using namespace std::chrono_literals;

constexpr size_t kMaxBodyBytes = 64 * 1024;
// A login lasts a working day at most, however busy.
constexpr std::chrono::seconds kSessionMaxAge{12 * 3600};
constexpr const char* kSessionCookie = "picksight_session";
constexpr auto kKeepalive = 15s;
constexpr const char* kBoundary = "picksightframe";
// The page's own scripts, styles, images, streams and requests only; no
// inline script, no frames, no plugins, no form posting elsewhere.
constexpr const char* kContentSecurityPolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
    "connect-src 'self'; font-src 'self'; form-action 'self'; frame-ancestors 'none'; "
    "base-uri 'none'";

// The one table from errors to HTTP statuses.
int httpStatus(const Error& error) {
  const auto& code = error.code;
  if (code == WebErrc::kBadRequest) return 400;
  if (code == WebErrc::kNotFound) return 404;
  if (code == WebErrc::kConflict) return 409;
  if (code == WebErrc::kUnreachable) return 502;
  if (code == ControlErrc::kBadRequest || code == ControlErrc::kOutOfRange ||
      code == ControlErrc::kUnknownFeature || code == ControlErrc::kNotSupported)
    return 400;
  if (code == ControlErrc::kUnknownCamera) return 404;
  if (code == ControlErrc::kCameraUnavailable || code == ControlErrc::kBusy) return 503;
  if (code == ControlErrc::kTimeout) return 504;
  if (code == ControlErrc::kNoReply) return 502;
  return 500;
}

void sendJson(httplib::Response& res, const nlohmann::json& body, int status = 200) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  // Messages may quote what a client sent: bytes that are not UTF-8 are
  // replaced, never a reason to fail the response.
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                  "application/json");
}

// The words of the statuses httplib answers by itself.
std::string statusText(int status) {
  switch (status) {
    case 400:
      return "bad request";
    case 404:
      return "not found";
    case 405:
      return "method not allowed";
    case 413:
      return "request body too large";
    case 414:
      return "request URI too long";
    case 416:
      return "range not satisfiable";
    default:
      return "HTTP " + std::to_string(status);
  }
}

void sendError(httplib::Response& res, const Error& error) {
  sendJson(res, {{"error", error.message}}, httpStatus(error));
}

void sendError(httplib::Response& res, WebErrc code, const std::string& message) {
  sendError(res, makeError(code, message));
}

std::string contentType(const std::string& path) {
  static const std::map<std::string, std::string> types = {
      {"html", "text/html; charset=utf-8"},
      {"js", "text/javascript; charset=utf-8"},
      {"mjs", "text/javascript; charset=utf-8"},
      {"css", "text/css; charset=utf-8"},
      {"json", "application/json"},
      {"svg", "image/svg+xml"},
      {"png", "image/png"},
      {"jpg", "image/jpeg"},
      {"ico", "image/x-icon"},
      {"txt", "text/plain; charset=utf-8"},
      {"woff2", "font/woff2"}};
  const size_t dot = path.rfind('.');
  auto it = dot == std::string::npos ? types.end() : types.find(path.substr(dot + 1));
  return it == types.end() ? "application/octet-stream" : it->second;
}

// Whether the HTTP peer may talk to us (its address as httplib reports it).
bool peerAllowed(const AllowList& allow, const std::string& address) {
  if (allow.allowsEveryone()) return true;
  sockaddr_in v4{};
  if (inet_pton(AF_INET, address.c_str(), &v4.sin_addr) == 1) {
    v4.sin_family = AF_INET;
    return allow.allows(reinterpret_cast<const sockaddr*>(&v4));
  }
  sockaddr_in6 v6{};
  if (inet_pton(AF_INET6, address.c_str(), &v6.sin6_addr) == 1) {
    v6.sin6_family = AF_INET6;
    return allow.allows(reinterpret_cast<const sockaddr*>(&v6));
  }
  return false;
}

// Debian's cpp-httplib (0.11.4) serves only the sockets it accepts itself,
// and restarts its read timeout at every byte; HttpGate accepts instead and
// hands over complete requests. Serving a given socket is httplib's
// private virtual process_and_close_socket, and keep-alive loops look at its
// protected listening socket: named here through explicit instantiation,
// which the language exempts from access checks (the only way to reach
// them without patching the library). On an SSLServer the virtual call
// does the TLS handshake.
using ProcessSocket = bool (httplib::Server::*)(::socket_t);
using ListenSocket = std::atomic<::socket_t> httplib::Server::*;
ProcessSocket processSocketOf();
ListenSocket listenSocketOf();
template <ProcessSocket Process, ListenSocket Listen>
struct HttplibInternals {
  friend ProcessSocket processSocketOf() { return Process; }
  friend ListenSocket listenSocketOf() { return Listen; }
};
template struct HttplibInternals<&httplib::Server::process_and_close_socket,
                                 &httplib::Server::svr_sock_>;

// Whether an Authorization header is "Bearer <token>", compared in a time
// that does not depend on where they differ.
bool bearerMatches(const std::string& authorization, const std::string& token) {
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization.size() <= kScheme.size() ||
      strncasecmp(authorization.c_str(), kScheme.data(), kScheme.size()) != 0)
    return false;
  const std::string given = authorization.substr(kScheme.size());
  // Hashes of equal length, so that neither the length nor the content of
  // the token shows in the time.
  unsigned char a[32];
  unsigned char b[32];
  crypto_generichash(a, sizeof(a), reinterpret_cast<const unsigned char*>(given.data()),
                     given.size(), nullptr, 0);
  crypto_generichash(b, sizeof(b), reinterpret_cast<const unsigned char*>(token.data()),
                     token.size(), nullptr, 0);
  return sodium_memcmp(a, b, sizeof(a)) == 0;
}

void setFrameHeaders(httplib::Response& res, uint64_t sequence, uint64_t timestamp_ns) {
  res.set_header("X-Frame-Sequence", std::to_string(sequence));
  res.set_header("X-Frame-Timestamp-Ns", std::to_string(timestamp_ns));
  res.set_header("Cache-Control", "no-store");
}

}  // namespace

class WebServer::Impl {
 public:
  explicit Impl(WebOptions options)
      : options_(std::move(options)),
        hosts_(options_.allow_hosts.empty() ? HostNames::defaults(options_.listen_host)
                                            : options_.allow_hosts) {
    if (options_.assets_dir.empty()) options_.assets_dir = defaultAssetsDir();
  }
  ~Impl() { stop(); }

  Result<void> start();
  void stop();

  WebOptions options_;
  const HostNames hosts_;
  zmq::context_t context_;
  EventHub events_;
  std::unique_ptr<CameraMonitor> cameras_;
  std::map<std::string, std::unique_ptr<ResultFeed>> apps_;
  RefusalLog refusals_{"HTTP"};
  // An httplib::SSLServer with --tls-cert.
  std::unique_ptr<httplib::Server> http_ = std::make_unique<httplib::Server>();
  std::unique_ptr<HttpGate> gate_;
  // --http-redirect: plain HTTP that only redirects to the HTTPS port.
  std::unique_ptr<httplib::Server> redirect_http_;
  std::unique_ptr<HttpGate> redirect_gate_;
  int redirect_port_ = 0;
  std::optional<UserStore> users_;
  std::unique_ptr<AuditTrail> audit_;
  std::unique_ptr<Sessions> sessions_;
  LoginLimiter logins_;
  // Snapshots' PNGs and binarized images, made on request at SCHED_IDLE.
  IdleWorker images_{"snapshot and binarized images"};
  int port_ = 0;
  bool tls() const { return !options_.tls_cert.empty(); }
  std::atomic<bool> stopping_{false};
  std::atomic<int> streams_{0};

 private:
  void routes();
  // The login, logout and session routes, and the admin's user list.
  void userRoutes();
  void loginRoutes();
  void userAdminRoutes();
  // Runs `change` on the users, records it (before: the user's role; after:
  // `after`, or the same role when null) and answers the request; ends the
  // user's sessions when it is done.
  void changeUser(const httplib::Request& req, httplib::Response& res, AuditRecord record,
                  nlohmann::json after, const std::function<Result<void>()>& change);
  void auditRoutes();
  // The filmstrip's entries and frames, read through a vision app's port.
  void filmstripRoutes();
  // http_->Post(pattern, handler), telling the gate (with TLS) that the
  // request has arrived whole before the handler runs.
  void post(const std::string& pattern, httplib::Server::Handler handler);
  // start()'s steps: the HTTPS server (--tls-cert), the users, sessions
  // and audit trail, the handlers every request meets, and the gate's
  // listening port.
  Result<void> startTls();
  Result<void> openAccounts();
  void setHandlers();
  Result<void> listen();
  // Before any route: the allow-list, the request's facts, the metrics
  // scraper's way in, then the session and its role (a refusal is
  // answered and handled here).
  httplib::Server::HandlerResponse admit(const httplib::Request& req, httplib::Response& res);
  // The plain-HTTP port that redirects to HTTPS (--http-redirect).
  Result<void> startRedirect();
  // Records a change or login of `session` (or of nobody) from the request's
  // client in the audit trail.
  void audit(const httplib::Request& req, const std::optional<Session>& session,
             AuditRecord record);
  // A change a robot, a PLC or the set-up port made in vision app `app`
  // (its results stream says so), recorded with the client as the user.
  void recordAppChange(const std::string& app, const proto::VisionResult& change);
  // A robot line from the page: sent, and recorded when it changes
  // something, with what its read-back line says before and after.
  void command(ResultFeed& app, const std::string& line, const httplib::Request& req,
               httplib::Response& res);
  // A camera action (POST /api/cameras/<camera>/<action>), recorded unless
  // it is a trigger.
  void cameraAction(const std::string& camera, const std::string& action,
                    const httplib::Request& req, httplib::Response& res);
  // What the audit trail keeps as a camera's state before `action`.
  nlohmann::json cameraBefore(const std::string& camera, const std::string& action,
                              const nlohmann::json& body);
  // The session of the request's cookie, if any is valid.
  std::optional<Session> sessionOf(const httplib::Request& req);
  // The role a request needs; nullopt: none (the page, login).
  std::optional<Role> roleNeeded(const httplib::Request& req);
  void serveFile(const std::string& relative, httplib::Response& res);
  std::shared_ptr<CameraFeed> feedOr404(const std::string& camera, httplib::Response& res);
  ResultFeed* appOr404(const std::string& name, httplib::Response& res);
  void snapshot(const std::string& camera, httplib::Response& res);
  // Runs `job` on images_; false (and a 503) when it was refused.
  bool onIdle(const std::function<void()>& job, httplib::Response& res);
  void frameJpeg(const std::string& camera, httplib::Response& res);
  void stream(const std::string& camera, httplib::Response& res);
  // The binarized newest frame of `app`'s camera, with the app's latest
  // settings or those the query gives (the Vision panel's live preview).
  void binary(const std::string& app, const httplib::Request& req, httplib::Response& res);
  void events(httplib::Response& res);
  void apps(httplib::Response& res);
  std::string metrics();
  // Claims one of max_streams slots; false (and a 503) when all are taken.
  bool claimStream(httplib::Response& res);
};

Result<void> WebServer::Impl::start() {
  if (auto ok = startTls(); !ok) return ok;
  if (auto ok = openAccounts(); !ok) return ok;
  cameras_ = std::make_unique<CameraMonitor>(context_, options_.video_servers, events_,
                                             options_.jpeg_quality);
  for (const auto& app : options_.vision_apps)
    apps_[app.name] = std::make_unique<ResultFeed>(
        context_, app, events_, [this, name = app.name](const proto::VisionResult& change) {
          recordAppChange(name, change);
        });
  setHandlers();
  routes();
  userRoutes();
  auditRoutes();
  if (auto ok = listen(); !ok) return ok;
  if (options_.redirect) return startRedirect();
  return {};
}

Result<void> WebServer::Impl::startTls() {
  if (tls()) {
    for (const auto& file : {options_.tls_cert, options_.tls_key})
      if (auto read = readFile(file); !read) return read.error();
    auto https =
        std::make_unique<httplib::SSLServer>(options_.tls_cert.c_str(), options_.tls_key.c_str());
    if (!https->is_valid())
      return makeError(WebErrc::kBadConfig, "TLS: " + options_.tls_cert + " and " +
                                                options_.tls_key +
                                                " are not a PEM certificate and its private key");
    // TLS 1.2 at least, whatever the system's OpenSSL configuration says.
    SSL_CTX_set_min_proto_version(https->ssl_context(), TLS1_2_VERSION);
    http_ = std::move(https);
  }
  return {};
}

Result<void> WebServer::Impl::openAccounts() {
  auto users = UserStore::open(options_.users_file);
  if (!users) return users.error();
  users_.emplace(std::move(*users));
  sessions_ = std::make_unique<Sessions>(options_.session_timeout, kSessionMaxAge);
  auto trail =
      AuditTrail::open({options_.audit_file, options_.audit_max_bytes, options_.audit_files});
  if (!trail) return trail.error();
  audit_ = std::move(*trail);
  logInfo("audit trail: ", options_.audit_file.empty() ? "in memory (no --users or --audit-file)"
                                                       : options_.audit_file);
  if (users_->empty()) {
    // Never a fixed default: a random password, said once.
    const std::string password = UserStore::randomPassword();
    if (auto set = users_->set("admin", Role::kAdmin, password); !set) return set.error();
    std::cout << "admin-password " << password << std::endl;
    logInfo("no users yet", options_.users_file.empty() ? " (no --users file: kept in memory)" : "",
            ": made 'admin' with the password printed on stdout (an admin changes it in the "
            "page's Users tab)");
  }
  return {};
}

void WebServer::Impl::setHandlers() {
  http_->set_payload_max_length(kMaxBodyBytes);
  // A viewer whose socket takes no bytes for this long is dropped: it held
  // one HTTP thread, never a camera or another viewer.
  http_->set_write_timeout(5s);
  http_->set_read_timeout(10s);
  http_->set_keep_alive_timeout(5);
  // On every response, refusals and errors too: no page may frame this one
  // (clickjacking) nor run anything but the page's own files.
  http_->set_default_headers({{"X-Frame-Options", "DENY"},
                              {"Content-Security-Policy", kContentSecurityPolicy},
                              {"X-Content-Type-Options", "nosniff"},
                              {"Referrer-Policy", "no-referrer"},
                              {"Cross-Origin-Opener-Policy", "same-origin"},
                              {"Cross-Origin-Resource-Policy", "same-origin"}});
  // A handler's exception is a bug: logged here, and the client gets a
  // plain 500 (httplib's default would quote the exception in a header).
  http_->set_exception_handler(
      [](const httplib::Request& req, httplib::Response& res, std::exception_ptr error) {
        std::string what = "unknown exception";
        try {
          if (error) std::rethrow_exception(error);
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
        }
        logError("HTTP ", req.method, " ", req.path.substr(0, 120), ": ", what);
        sendJson(res, {{"error", "internal error (logged by picksight-web)"}}, 500);
      });
  // Errors httplib answers itself (no route, a malformed request line, a
  // body over the limit) get a message too, in the API's form.
  http_->set_error_handler(
      httplib::Server::HandlerWithResponse([](const httplib::Request&, httplib::Response& res) {
        if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
        sendJson(res, {{"error", statusText(res.status)}}, res.status);
        return httplib::Server::HandlerResponse::Handled;
      }));
  http_->set_pre_routing_handler(
      [this](const httplib::Request& req, httplib::Response& res) { return admit(req, res); });
}

httplib::Server::HandlerResponse WebServer::Impl::admit(const httplib::Request& req,
                                                        httplib::Response& res) {
  // httplib calls this once the request's header is read, before its
  // body: with TLS, the gate's deadline ends here for a request without
  // a body, in post() after the body for the others.
  const std::string length = req.get_header_value("Content-Length");
  if (tls() && (length.empty() || length == "0") && !req.has_header("Transfer-Encoding"))
    gate_->arrived(req.remote_addr, req.remote_port);
  const auto refuse = [&](int status, const std::string& message) {
    refusals_.refused(req.remote_addr, req.method + " " + req.path + ": " + message);
    sendJson(res, {{"error", message}}, status);
    return httplib::Server::HandlerResponse::Handled;
  };
  if (!peerAllowed(options_.allow, req.remote_addr))
    return refuse(403, "forbidden: " + req.remote_addr + " is not in the allow-list");
  RequestFacts facts;
  facts.method = req.method;
  facts.host = req.get_header_value("Host");
  facts.has_origin = req.has_header("Origin");
  facts.origin = req.get_header_value("Origin");
  facts.content_type = req.get_header_value("Content-Type");
  facts.request_header = req.get_header_value(kRequestHeader);
  if (auto refusal = checkRequest(hosts_, facts)) return refuse(refusal->status, refusal->message);
  if (req.path == "/metrics" && !changesState(req.method)) {
    // A scraper's way in, besides a login.
    const std::string authorization = req.get_header_value("Authorization");
    if (!options_.metrics_token.empty() && !authorization.empty()) {
      if (bearerMatches(authorization, options_.metrics_token))
        return httplib::Server::HandlerResponse::Unhandled;
      return refuse(401, "wrong metrics token (--metrics-token)");
    }
    if (options_.metrics_allow_set && peerAllowed(options_.metrics_allow, req.remote_addr))
      return httplib::Server::HandlerResponse::Unhandled;
  }
  const auto needed = roleNeeded(req);
  if (!needed) return httplib::Server::HandlerResponse::Unhandled;
  const auto session = sessionOf(req);
  if (!session) {
    sendJson(res, {{"error", "log in first (POST /api/login)"}}, 401);
    return httplib::Server::HandlerResponse::Handled;
  }
  if (session->role < *needed) {
    // A change refused for the role is recorded: who tried what.
    if (changesState(req.method) && req.path != "/api/logout") {
      AuditRecord record;
      record.action = "request";
      record.target = req.path.substr(0, 128);
      record.outcome = "refused";
      record.status = 403;
      record.reply = std::string("needs the ") + roleName(*needed) + " role";
      audit(req, session, std::move(record));
    }
    sendJson(res,
             {{"error", std::string("this needs the ") + roleName(*needed) + " role; " +
                            session->user + " is " + roleName(session->role)}},
             403);
    return httplib::Server::HandlerResponse::Handled;
  }
  return httplib::Server::HandlerResponse::Unhandled;
}

Result<void> WebServer::Impl::listen() {
  GateOptions gate;
  gate.header_timeout = options_.header_timeout;
  gate.per_address = options_.per_address;
  gate.max_body_bytes = kMaxBodyBytes;
  // Every stream holds a thread; the rest serve the page and the API.
  gate.threads = static_cast<size_t>(options_.max_streams) + 16;
  // With TLS the gate can only wait for the ClientHello: the handshake and
  // the request are read by the serving thread (http_gate.hpp).
  gate.tls = tls();
  gate_ = std::make_unique<HttpGate>(gate, refusals_);
  auto port = gate_->listen(options_.listen_host, options_.listen_port);
  if (!port) return port.error();
  port_ = *port;
  // httplib serves the requests the gate found complete, one per
  // connection: a kept-alive connection's next request would be read by
  // httplib's per-byte timeouts, past the gate.
  http_->set_keep_alive_max_count(1);
  http_.get()->*listenSocketOf() = gate_->listeningSocket();
  logInfo("requests must name one of these hosts (--allow-host): ", hosts_.describe());
  if (!options_.metrics_token.empty() || options_.metrics_allow_set)
    logInfo("GET /metrics without a login:",
            options_.metrics_token.empty() ? "" : " with the --metrics-token bearer token",
            options_.metrics_allow_set ? " from " + options_.metrics_allow.describe() : "");
  gate_->start([this](int fd) { (http_.get()->*processSocketOf())(fd); });
  return {};
}

Result<void> WebServer::Impl::startRedirect() {
  redirect_http_ = std::make_unique<httplib::Server>();
  redirect_http_->set_default_headers({{"X-Frame-Options", "DENY"},
                                       {"Content-Security-Policy", kContentSecurityPolicy},
                                       {"X-Content-Type-Options", "nosniff"},
                                       {"Referrer-Policy", "no-referrer"}});
  redirect_http_->set_read_timeout(10s);
  redirect_http_->set_write_timeout(5s);
  redirect_http_->set_keep_alive_max_count(1);
  // Every request is answered here: a redirect to the same name and path
  // on the HTTPS port, for a name this server answers to.
  redirect_http_->set_pre_routing_handler(
      [this](const httplib::Request& req, httplib::Response& res) {
        const auto refuse = [&](int status, const std::string& message) {
          refusals_.refused(req.remote_addr, "HTTP redirect: " + message);
          sendJson(res, {{"error", message}}, status);
          return httplib::Server::HandlerResponse::Handled;
        };
        if (!peerAllowed(options_.allow, req.remote_addr))
          return refuse(403, "forbidden: " + req.remote_addr + " is not in the allow-list");
        const std::string host = req.get_header_value("Host");
        if (host.empty()) return refuse(400, "a request needs a Host header");
        if (!hosts_.allowsHost(host)) return refuse(403, "Host '" + host + "' is not one of ours");
        if (req.method != "GET" && req.method != "HEAD")
          return refuse(403, "this port only redirects to HTTPS: send the request there");
        // The name without its port ("[v6]" kept whole).
        std::string name = host;
        if (name.front() == '[') {
          name = name.substr(0, name.find(']') + 1);
        } else if (std::count(name.begin(), name.end(), ':') == 1) {
          name = name.substr(0, name.find(':'));
        }
        const std::string target = req.target.empty() || req.target[0] != '/' ? "/" : req.target;
        res.status = 301;
        res.set_header("Location", "https://" + name + ":" + std::to_string(port_) + target);
        res.set_header("Cache-Control", "no-store");
        res.set_content("{\"redirect\":\"https\"}", "application/json");
        return httplib::Server::HandlerResponse::Handled;
      });
  GateOptions gate;
  gate.header_timeout = options_.header_timeout;
  gate.per_address = options_.per_address;
  gate.max_body_bytes = kMaxBodyBytes;
  gate.threads = 4;
  redirect_gate_ = std::make_unique<HttpGate>(gate, refusals_);
  auto port = redirect_gate_->listen(options_.redirect_host, options_.redirect_port);
  if (!port) return port.error();
  redirect_port_ = *port;
  redirect_http_.get()->*listenSocketOf() = redirect_gate_->listeningSocket();
  redirect_gate_->start([this](int fd) { (redirect_http_.get()->*processSocketOf())(fd); });
  return {};
}

void WebServer::Impl::stop() {
  if (stopping_.exchange(true)) return;
  events_.closeAll();
  if (gate_) gate_->stop();
  if (redirect_gate_) redirect_gate_->stop();
  // httplib's keep-alive loops end when its listening socket is invalid.
  if (http_) http_.get()->*listenSocketOf() = INVALID_SOCKET;
  if (redirect_http_) redirect_http_.get()->*listenSocketOf() = INVALID_SOCKET;
  if (cameras_) cameras_->stop();  // wakes the streams waiting on frames
  if (gate_) gate_->join();
  if (redirect_gate_) redirect_gate_->join();
  for (auto& [name, app] : apps_) app->stop();
}

void WebServer::Impl::serveFile(const std::string& relative, httplib::Response& res) {
  if (relative.empty() || relative.find("..") != std::string::npos || relative[0] == '/') {
    sendError(res, WebErrc::kNotFound, "no file '" + relative + "'");
    return;
  }
  std::ifstream in(options_.assets_dir + "/" + relative, std::ios::binary);
  if (!in) {
    sendError(res, WebErrc::kNotFound, "no file '" + relative + "'");
    return;
  }
  std::ostringstream bytes;
  bytes << in.rdbuf();
  res.set_header("Cache-Control", "no-cache");
  res.set_content(bytes.str(), contentType(relative).c_str());
}

std::shared_ptr<CameraFeed> WebServer::Impl::feedOr404(const std::string& camera,
                                                       httplib::Response& res) {
  auto feed = cameras_->feed(camera);
  if (!feed) sendError(res, WebErrc::kNotFound, "no camera '" + camera + "'");
  return feed;
}

ResultFeed* WebServer::Impl::appOr404(const std::string& name, httplib::Response& res) {
  auto it = apps_.find(name);
  if (it != apps_.end()) return it->second.get();
  sendError(res, WebErrc::kNotFound, "no vision app '" + name + "'");
  return nullptr;
}

void WebServer::Impl::snapshot(const std::string& camera, httplib::Response& res) {
  auto feed = feedOr404(camera, res);
  if (!feed) return;
  auto frame = feed->latest();
  if (!frame) return sendError(res, WebErrc::kNotFound, "no frame from '" + camera + "' yet");
  std::vector<unsigned char> png;
  bool encoded = false;
  // Fast compression: lossless all the same, and a 1920x1080 frame takes
  // tens of milliseconds instead of hundreds.
  if (!onIdle(
          [&] {
            encoded = picksight::codecs::imencode(".png", frame->image, png,
                                                  {cv::IMWRITE_PNG_COMPRESSION, 1});
          },
          res))
    return;
  if (!encoded) return sendError(res, WebErrc::kEncode, "PNG encoding failed");
  setFrameHeaders(res, frame->info.sequence, frame->info.host_timestamp_ns);
  res.set_content(std::string(png.begin(), png.end()), "image/png");
}

bool WebServer::Impl::onIdle(const std::function<void()>& job, httplib::Response& res) {
  if (images_.run(job) != IdleWorker::Outcome::kRefused) return true;
  sendJson(res,
           {{"error",
             "busy: images are made only on cores the vision leaves free, and all are "
             "taken; try again"}},
           503);
  res.set_header("Retry-After", "1");
  return false;
}

void WebServer::Impl::frameJpeg(const std::string& camera, httplib::Response& res) {
  auto feed = feedOr404(camera, res);
  if (!feed) return;
  if (!feed->latest())
    return sendError(res, WebErrc::kNotFound, "no frame from '" + camera + "' yet");
  auto jpeg = feed->jpeg();
  // A frame that cannot be encoded (or a server stopping): a clear refusal.
  if (!jpeg)
    return sendJson(res, {{"error", "no JPEG of the newest frame of '" + camera + "'"}}, 503);
  setFrameHeaders(res, jpeg->sequence, jpeg->host_timestamp_ns);
  res.set_content(jpeg->bytes, "image/jpeg");
}

bool WebServer::Impl::claimStream(httplib::Response& res) {
  if (++streams_ <= options_.max_streams) return true;
  --streams_;
  sendJson(res,
           {{"error",
             "too many streams open (--max-streams " + std::to_string(options_.max_streams) + ")"}},
           503);
  return false;
}

void WebServer::Impl::stream(const std::string& camera, httplib::Response& res) {
  auto feed = feedOr404(camera, res);
  if (!feed || !claimStream(res)) return;
  struct Viewer {
    Viewer(std::shared_ptr<CameraFeed> f, std::atomic<int>& s)
        : feed(std::move(f)), count(*feed), streams(s) {}
    ~Viewer() { --streams; }
    std::shared_ptr<CameraFeed> feed;
    ViewerCount count;
    std::atomic<int>& streams;
    uint64_t seen = 0;
  };
  auto viewer = std::make_shared<Viewer>(feed, streams_);
  res.set_header("Cache-Control", "no-store");
  res.set_chunked_content_provider(
      std::string("multipart/x-mixed-replace; boundary=") + kBoundary,
      [this, viewer](size_t, httplib::DataSink& sink) {
        // Always the newest frame: what this viewer could not take in time
        // is skipped for it alone.
        const uint64_t now = viewer->feed->waitNewer(viewer->seen, 1s);
        if (stopping_) return false;
        if (now == viewer->seen) return true;  // no new frame: asked again
        auto jpeg = viewer->feed->jpeg(now);
        // A frame that could not be encoded in time is skipped, for this
        // viewer alone.
        viewer->seen = jpeg ? jpeg->generation : now;
        if (!jpeg) return true;
        const std::string head =
            std::string("--") + kBoundary + "\r\nContent-Type: image/jpeg\r\nContent-Length: " +
            std::to_string(jpeg->bytes.size()) +
            "\r\nX-Frame-Sequence: " + std::to_string(jpeg->sequence) +
            "\r\nX-Frame-Timestamp-Ns: " + std::to_string(jpeg->host_timestamp_ns) + "\r\n\r\n";
        return sink.write(head.data(), head.size()) &&
               sink.write(jpeg->bytes.data(), jpeg->bytes.size()) && sink.write("\r\n", 2);
      },
      [viewer](bool) {});
}

namespace {
// The query's binarize settings over `options` (polarity=dark|light,
// threshold=adaptive|otsu|fixed, level=0-255, window=0|8-16384: VISION's
// keys and bounds); an error names the parameter and what it accepts.
Result<void> binarizeQuery(const httplib::Request& req, vision::BinarizeOptions& options) {
  const auto bad = [](const std::string& key, const std::string& accepts) {
    return makeError(WebErrc::kBadRequest, key + " must be " + accepts);
  };
  if (req.has_param("polarity")) {
    const std::string v = req.get_param_value("polarity");
    if (v != "dark" && v != "light") return bad("polarity", "dark or light");
    options.polarity =
        v == "dark" ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
  }
  if (req.has_param("threshold")) {
    const std::string v = req.get_param_value("threshold");
    if (v == "adaptive") {
      options.method = vision::ThresholdMethod::kAdaptive;
    } else if (v == "otsu") {
      options.method = vision::ThresholdMethod::kOtsu;
    } else if (v == "fixed") {
      options.method = vision::ThresholdMethod::kFixed;
    } else {
      return bad("threshold", "adaptive, otsu or fixed");
    }
  }
  if (req.has_param("level")) {
    const auto n = parseInt(req.get_param_value("level"));
    if (!n || *n < 0 || *n > 255) return bad("level", "an integer in [0, 255]");
    options.fixed_threshold = static_cast<int>(*n);
  }
  if (req.has_param("window")) {
    const auto n = parseInt(req.get_param_value("window"));
    if (!n || (*n != 0 && (*n < 8 || *n > 16384)))
      return bad("window", "0 or an integer in [8, 16384]");
    options.adaptive_window = static_cast<int>(*n);
  }
  return {};
}
}  // namespace

void WebServer::Impl::binary(const std::string& name, const httplib::Request& req,
                             httplib::Response& res) {
  ResultFeed* app = appOr404(name, res);
  if (!app) return;
  auto result = app->latest();
  // The app's camera: from its latest result, else the camera of its name.
  const std::string camera = result && !result->camera().empty() ? result->camera() : name;
  auto feed = feedOr404(camera, res);
  if (!feed) return;
  auto frame = feed->latest();
  if (!frame) return sendError(res, WebErrc::kNotFound, "no frame from '" + camera + "' yet");
  vision::BinarizeOptions options;
  if (result && result->has_binarize()) {
    const auto& b = result->binarize();
    options.method = b.method() == "otsu"    ? vision::ThresholdMethod::kOtsu
                     : b.method() == "fixed" ? vision::ThresholdMethod::kFixed
                                             : vision::ThresholdMethod::kAdaptive;
    options.fixed_threshold = static_cast<int>(b.threshold());
    options.polarity =
        b.dark_parts() ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
    options.adaptive_window = static_cast<int>(b.window());
  }
  if (auto query = binarizeQuery(req, options); !query) return sendError(res, query.error());
  std::vector<unsigned char> png;
  bool encoded = false;
  if (!onIdle(
          [&] {
            cv::Mat grey = frame->image;
            if (grey.channels() == 3) cv::cvtColor(frame->image, grey, cv::COLOR_BGR2GRAY);
            const cv::Mat mask = vision::binarize(grey, options);
            encoded =
                picksight::codecs::imencode(".png", mask, png, {cv::IMWRITE_PNG_COMPRESSION, 1});
          },
          res))
    return;
  if (!encoded) return sendError(res, WebErrc::kEncode, "PNG encoding failed");
  setFrameHeaders(res, frame->info.sequence, frame->info.host_timestamp_ns);
  res.set_content(std::string(png.begin(), png.end()), "image/png");
}

void WebServer::Impl::events(httplib::Response& res) {
  if (!claimStream(res)) return;
  struct Client {
    Client(std::shared_ptr<EventQueue> q, std::atomic<int>& s) : queue(std::move(q)), streams(s) {}
    ~Client() { --streams; }
    std::shared_ptr<EventQueue> queue;
    std::atomic<int>& streams;
    bool greeted = false;
    std::chrono::steady_clock::time_point next_keepalive =
        std::chrono::steady_clock::now() + kKeepalive;
  };
  auto client = std::make_shared<Client>(events_.subscribe(), streams_);
  res.set_header("Cache-Control", "no-store");
  res.set_header("X-Accel-Buffering", "no");
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, client](size_t, httplib::DataSink& sink) {
        if (!client->greeted) {
          // The camera list at once, so the page need not wait a second.
          client->greeted = true;
          const std::string first =
              "retry: 2000\nevent: cameras\ndata: " + cameras_->cameras().dump() + "\n\n";
          return sink.write(first.data(), first.size());
        }
        // A comment every kKeepalive whatever the traffic: proxies and
        // browsers see the connection alive, and a dead peer is noticed.
        const auto now = std::chrono::steady_clock::now();
        if (now >= client->next_keepalive) {
          client->next_keepalive = now + kKeepalive;
          return sink.write(": keepalive\n\n", 13);
        }
        auto event = client->queue->pop(
            std::chrono::duration_cast<std::chrono::milliseconds>(client->next_keepalive - now));
        if (stopping_ || client->queue->closed()) return false;
        if (!event) return true;  // keepalive time: written on the next call
        return sink.write(event->data(), event->size());
      },
      [client](bool) {});
}

void WebServer::Impl::apps(httplib::Response& res) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [name, app] : apps_) {
    std::string camera = app->camera();
    if (camera.empty() && cameras_->feed(name)) camera = name;  // default: app named as its camera
    list.push_back({{"name", name},
                    {"camera", camera},
                    {"connected", app->connected()},
                    {"last_result_id", app->lastResultId()}});
  }
  sendJson(res, list);
}

std::string WebServer::Impl::metrics() {
  std::vector<AppFigures> apps;
  for (const auto& [name, app] : apps_) apps.push_back({name, app->figures()});
  return metricsText(cameras_->figures(), apps);
}

std::optional<Session> WebServer::Impl::sessionOf(const httplib::Request& req) {
  const std::string cookies = req.get_header_value("Cookie");
  const std::string key = std::string(kSessionCookie) + "=";
  size_t at = 0;
  while ((at = cookies.find(key, at)) != std::string::npos) {
    if (at == 0 || cookies[at - 1] == ' ' || cookies[at - 1] == ';') {
      const size_t start = at + key.size();
      const size_t end = cookies.find(';', start);
      return sessions_->find(cookies.substr(start, end == std::string::npos ? end : end - start));
    }
    at += key.size();
  }
  return std::nullopt;
}

std::optional<Role> WebServer::Impl::roleNeeded(const httplib::Request& req) {
  const std::string& path = req.path;
  if (path == "/" || path.rfind("/static/", 0) == 0 || path == "/api/login" ||
      path == "/api/session")
    return std::nullopt;
  if (path.rfind("/api/users", 0) == 0) return Role::kAdmin;
  // The trail is read by engineers (who changed the cell) and exported by
  // admins.
  if (path == "/api/audit.jsonl") return Role::kAdmin;
  if (path == "/api/audit") return Role::kEngineer;
  if (!changesState(req.method)) return Role::kOperator;
  // POST /api/apps/<app>/command: a session here; the role its line needs
  // is checked by the route, since httplib reads the body after this.
  static const std::regex camera(R"(/api/cameras/[^/]+/([a-z]+))");
  std::smatch match;
  if (std::regex_match(path, match, camera)) return roleForCameraAction(match[1].str());
  return Role::kOperator;  // logout
}

void WebServer::Impl::userRoutes() {
  loginRoutes();
  userAdminRoutes();
}

void WebServer::Impl::loginRoutes() {
  post("/api/login", [this](const httplib::Request& req, httplib::Response& res) {
    if (auto wait = logins_.blocked(req.remote_addr)) {
      res.set_header("Retry-After", std::to_string(wait->count()));
      return sendJson(
          res, {{"error", "too many failed logins: wait " + std::to_string(wait->count()) + " s"}},
          429);
    }
    auto body = parseJsonBody(req.body);
    if (!body) return sendError(res, body.error());
    const auto user = body->find("user");
    const auto password = body->find("password");
    if (user == body->end() || !user->is_string() || password == body->end() ||
        !password->is_string())
      return sendError(res, WebErrc::kBadRequest, "\"user\" and \"password\": strings");
    const std::string name = user->get<std::string>();
    const auto role = users_->verify(name, password->get<std::string>());
    if (!role) {
      logins_.failed(req.remote_addr);
      refusals_.refused(req.remote_addr, "failed login as '" + name.substr(0, 32) + "'");
      // The name only when it is a user's: an unknown one may be a
      // password typed in the wrong field.
      bool known = false;
      for (const auto& u : users_->list()) known = known || u.name == name;
      AuditRecord record;
      record.action = "login";
      record.user = known ? name : "";
      record.arguments = {{"user", known ? name : "(not a user)"}};
      record.outcome = "refused";
      record.status = 401;
      record.reply = "wrong user or password";
      audit(req, std::nullopt, std::move(record));
      return sendJson(res, {{"error", "wrong user or password"}}, 401);
    }
    logins_.succeeded(req.remote_addr);
    const std::string token = sessions_->create({name, *role});
    // HttpOnly: no script reads it; SameSite=Strict: no other site's page
    // sends it; Secure with TLS: never sent over plain HTTP (without TLS
    // the browser would not send a Secure cookie back: plain HTTP is for
    // loopback and SSH tunnels).
    res.set_header("Set-Cookie", std::string(kSessionCookie) + "=" + token +
                                     "; Path=/; HttpOnly; SameSite=Strict; Max-Age=" +
                                     std::to_string(sessions_->maxAge().count()) +
                                     (tls() ? "; Secure" : ""));
    AuditRecord record;
    record.action = "login";
    record.outcome = "ok";
    record.status = 200;
    audit(req, Session{name, *role}, std::move(record));
    sendJson(res, {{"user", name}, {"role", roleName(*role)}});
  });
  post("/api/logout", [this](const httplib::Request& req, httplib::Response& res) {
    if (const auto session = sessionOf(req)) {
      AuditRecord record;
      record.action = "logout";
      record.outcome = "ok";
      record.status = 200;
      audit(req, session, std::move(record));
    }
    const std::string cookies = req.get_header_value("Cookie");
    const size_t at = cookies.find(std::string(kSessionCookie) + "=");
    if (at != std::string::npos)
      sessions_->remove(cookies.substr(at + std::strlen(kSessionCookie) + 1, 64));
    res.set_header("Set-Cookie", std::string(kSessionCookie) +
                                     "=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0" +
                                     (tls() ? "; Secure" : ""));
    sendJson(res, {{"ok", true}});
  });
  http_->Get("/api/session", [this](const httplib::Request& req, httplib::Response& res) {
    const auto session = sessionOf(req);
    // Not an error: the page asks before it shows its login form.
    if (!session) return sendJson(res, {{"user", nullptr}});
    sendJson(res, {{"user", session->user}, {"role", roleName(session->role)}});
  });
}

void WebServer::Impl::userAdminRoutes() {
  http_->Get("/api/users", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& u : users_->list())
      list.push_back({{"name", u.name}, {"role", roleName(u.role)}});
    sendJson(res, list);
  });
  // Adds a user, or with "new": false (the default, as before the page's
  // Users panel) adds or replaces one.
  post("/api/users", [this](const httplib::Request& req, httplib::Response& res) {
    auto body = parseJsonBody(req.body);
    if (!body) return sendError(res, body.error());
    const auto name = body->value("name", nlohmann::json());
    const auto role = parseRole(body->value("role", std::string()));
    const auto password = body->value("password", nlohmann::json());
    const auto fresh = body->value("new", nlohmann::json(false));
    if (!name.is_string() || !role || !password.is_string() || !fresh.is_boolean())
      return sendError(res, WebErrc::kBadRequest,
                       "\"name\", \"password\" and \"role\" (operator, engineer, admin); "
                       "\"new\": true or false");
    AuditRecord record;
    record.action = fresh.get<bool>() ? "user.add" : "user.set";
    record.target = name.get<std::string>();
    // Never the password: only that one was set.
    record.arguments = {{"name", record.target}, {"role", roleName(*role)}, {"password", "(set)"}};
    const std::string user = record.target;  // record is moved into changeUser
    const std::string& secret = password.get_ref<const std::string&>();
    changeUser(req, res, std::move(record), {{"role", roleName(*role)}}, [&] {
      return fresh.get<bool>() ? users_->add(user, *role, secret)
                               : users_->set(user, *role, secret);
    });
  });
  // An existing user's role, password or removal (the Users panel).
  post(R"(/api/users/([^/]+)/(role|password|delete))",
       [this](const httplib::Request& req, httplib::Response& res) {
         const std::string user = req.matches[1];
         const std::string what = req.matches[2];
         AuditRecord record;
         record.action = "user." + what;
         record.target = user;
         if (what == "delete")
           return changeUser(req, res, std::move(record), "(removed)",
                             [&] { return users_->remove(user); });
         auto body = parseJsonBody(req.body);
         if (!body) return sendError(res, body.error());
         if (what == "role") {
           const auto role = parseRole(body->value("role", std::string()));
           if (!role)
             return sendError(res, WebErrc::kBadRequest, "\"role\": operator, engineer or admin");
           record.arguments = {{"role", roleName(*role)}};
           return changeUser(req, res, std::move(record), {{"role", roleName(*role)}},
                             [&] { return users_->setRole(user, *role); });
         }
         const auto password = body->value("password", nlohmann::json());
         if (!password.is_string())
           return sendError(res, WebErrc::kBadRequest, "\"password\": a string of 8 to 256 bytes");
         record.arguments = {{"password", "(set)"}};
         changeUser(req, res, std::move(record), nlohmann::json(), [&] {
           return users_->setPassword(user, password.get_ref<const std::string&>());
         });
       });
}

void WebServer::Impl::changeUser(const httplib::Request& req, httplib::Response& res,
                                 AuditRecord record, nlohmann::json after,
                                 const std::function<Result<void>()>& change) {
  for (const auto& u : users_->list())
    if (u.name == record.target) record.before = {{"role", roleName(u.role)}};
  if (record.before.is_null()) record.before = "(no such user)";
  auto done = change();
  record.outcome = done ? "ok" : "error";
  record.status = done ? 200 : httpStatus(done.error());
  if (done)
    record.after = after.is_null() ? record.before : std::move(after);
  else
    record.reply = done.error().message;
  const std::string user = record.target;
  audit(req, sessionOf(req), std::move(record));
  if (!done) return sendError(res, done.error());
  // The old password or role ends here: its sessions log in again.
  sessions_->removeUser(user);
  sendJson(res, {{"ok", true}});
}

void WebServer::Impl::routes() {
  http_->Get("/", [this](const httplib::Request&, httplib::Response& res) {
    serveFile("index.html", res);
  });
  http_->Get(R"(/static/(.+))", [this](const httplib::Request& req, httplib::Response& res) {
    serveFile(req.matches[1], res);
  });
  http_->Get("/api/cameras", [this](const httplib::Request&, httplib::Response& res) {
    sendJson(res, cameras_->cameras());
  });
  http_->Get("/api/apps", [this](const httplib::Request&, httplib::Response& res) { apps(res); });
  http_->Get(R"(/snapshot/([^/]+)\.png)",
             [this](const httplib::Request& req, httplib::Response& res) {
               snapshot(req.matches[1], res);
             });
  http_->Get(R"(/frame/([^/]+)\.jpg)", [this](const httplib::Request& req, httplib::Response& res) {
    frameJpeg(req.matches[1], res);
  });
  http_->Get(
      R"(/stream/([^/]+)\.mjpg)",
      [this](const httplib::Request& req, httplib::Response& res) { stream(req.matches[1], res); });
  http_->Get(R"(/binary/([^/]+)\.png)",
             [this](const httplib::Request& req, httplib::Response& res) {
               binary(req.matches[1], req, res);
             });
  http_->Get("/events", [this](const httplib::Request&, httplib::Response& res) { events(res); });
  http_->Get(R"(/api/results/([^/]+)/latest)", [this](const httplib::Request& req,
                                                      httplib::Response& res) {
    ResultFeed* app = appOr404(req.matches[1], res);
    if (!app) return;
    const std::string json = app->latestJson();
    if (json.empty())
      return sendError(res, WebErrc::kNotFound, "no result from '" + app->name() + "' yet");
    res.set_header("Cache-Control", "no-store");
    res.set_content(json, "application/json");
  });
  http_->Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(metrics(), "text/plain; version=0.0.4; charset=utf-8");
  });
  post(R"(/api/apps/([^/]+)/command)", [this](const httplib::Request& req, httplib::Response& res) {
    ResultFeed* app = appOr404(req.matches[1], res);
    if (!app) return;
    auto body = parseJsonBody(req.body);
    if (!body) return sendError(res, body.error());
    auto line = body->find("line");
    if (line == body->end() || !line->is_string())
      return sendError(res, WebErrc::kBadRequest, "\"line\": must be a string");
    command(*app, line->get<std::string>(), req, res);
  });
  filmstripRoutes();
  http_->Get(R"(/api/cameras/([^/]+)/features)",
             [this](const httplib::Request& req, httplib::Response& res) {
               proto::ControlRequest request;
               request.mutable_list_features()->set_camera(req.matches[1]);
               auto reply = cameras_->control(req.matches[1], request);
               if (!reply) return sendError(res, reply.error());
               nlohmann::json list = nlohmann::json::array();
               for (const auto& f : reply->list_features().features())
                 list.push_back(protoJson(f, true));
               sendJson(res, list);
             });
  post(R"(/api/cameras/([^/]+)/([a-z]+))",
       [this](const httplib::Request& req, httplib::Response& res) {
         cameraAction(req.matches[1], req.matches[2], req, res);
       });
}

void WebServer::Impl::filmstripRoutes() {
  // Reads for operators; REPLAY and FILMSTRIP EXPORT go through the
  // command route (the role each line needs: access_policy).
  http_->Get(R"(/api/apps/([^/]+)/filmstrip)", [this](const httplib::Request& req,
                                                      httplib::Response& res) {
    ResultFeed* app = appOr404(req.matches[1], res);
    if (!app) return;
    size_t count = 24;
    if (req.has_param("n")) {
      const auto n = parseInt(req.get_param_value("n"));
      if (!n || *n < 1 || *n > static_cast<int64_t>(kMaxFilmstripEntries))
        return sendError(res, WebErrc::kBadRequest,
                         "n: a number of entries, 1.." + std::to_string(kMaxFilmstripEntries));
      count = static_cast<size_t>(*n);
    }
    auto entries = filmstripEntries(*app, count, req.get_param_value("failures") == "1");
    if (!entries) return sendError(res, entries.error());
    sendJson(res, *entries);
  });
  http_->Get(R"(/api/apps/([^/]+)/filmstrip/([0-9]{1,10})\.png)",
             [this](const httplib::Request& req, httplib::Response& res) {
               ResultFeed* app = appOr404(req.matches[1], res);
               if (!app) return;
               int side = 1024;
               if (req.has_param("side")) {
                 const auto n = parseInt(req.get_param_value("side"));
                 if (!n || *n < 16 || *n > 2048)
                   return sendError(res, WebErrc::kBadRequest, "side: pixels, 16..2048");
                 side = static_cast<int>(*n);
               }
               auto png = filmstripPng(*app, std::stoull(req.matches[2].str()), side);
               if (!png) return sendError(res, png.error());
               res.set_header("Cache-Control", "no-store");
               res.set_content(*png, "image/png");
             });
}

void WebServer::Impl::post(const std::string& pattern, httplib::Server::Handler handler) {
  http_->Post(pattern, [this, handler = std::move(handler)](const httplib::Request& req,
                                                            httplib::Response& res) {
    if (tls()) gate_->arrived(req.remote_addr, req.remote_port);
    handler(req, res);
  });
}

void WebServer::Impl::audit(const httplib::Request& req, const std::optional<Session>& session,
                            AuditRecord record) {
  if (session) {
    record.user = session->user;
    record.role = roleName(session->role);
  }
  record.address = req.remote_addr;
  audit_->record(std::move(record));
}

void WebServer::Impl::recordAppChange(const std::string& app, const proto::VisionResult& change) {
  // client: "robot 10.0.0.5:41234", "setup 127.0.0.1:50112", "plc ...".
  const std::string& client = change.client();
  const size_t space = client.find(' ');
  const std::string port = space == std::string::npos ? std::string() : client.substr(0, space);
  std::string address = space == std::string::npos ? client : client.substr(space + 1);
  address = address.substr(0, address.rfind(':'));
  AuditRecord record;
  record.user = client.empty() ? "(vision app)" : client;
  record.role = port == "setup" ? "set-up port" : port.empty() ? "" : port + " port";
  record.address = address;
  record.action = "command";
  record.target = app;
  record.arguments = {{"line", change.request_line()}};
  record.outcome = "ok";  // only changes answered OK are published
  record.reply = change.reply();
  audit_->record(std::move(record));
}

void WebServer::Impl::command(ResultFeed& app, const std::string& line, const httplib::Request& req,
                              httplib::Response& res) {
  const auto session = sessionOf(req);
  const Role needed = roleForCommand(line);
  // Reads, LOCATEs and teach previews are not changes: not recorded.
  const bool change = changesCell(line);
  AuditRecord record;
  record.action = "command";
  record.target = app.name();
  record.arguments = {{"line", line}};
  if (!session || session->role < needed) {
    if (change && session) {
      record.outcome = "refused";
      record.status = 403;
      record.reply = std::string("needs the ") + roleName(needed) + " role";
      audit(req, session, std::move(record));
    }
    return sendJson(
        res, {{"error", std::string("this line needs the ") + roleName(needed) + " role"}}, 403);
  }
  const bool piece = isJobImportPiece(line);
  // A piece's base64 is no part of the trail: its name, offset and size are.
  if (piece) record.arguments = {{"line", line.substr(0, line.rfind(' ')) + " ..."}};
  const auto read_back = change && !piece ? readBackLine(line) : std::nullopt;
  const auto ask = [&](const std::string& read) -> nlohmann::json {
    auto r = app.command(read);
    return r ? nlohmann::json(*r) : nlohmann::json("(" + r.error().message + ")");
  };
  if (read_back) record.before = ask(*read_back);
  auto reply = app.command(line, piece ? kMaxJobPieceBytes : kMaxCommandBytes);
  // Pieces before the last change nothing yet: the import is recorded once.
  const bool more = piece && reply && reply->rfind("MORE ", 0) == 0;
  if (change && !more) {
    if (!reply) {
      record.outcome = "error";
      record.status = httpStatus(reply.error());
      record.reply = reply.error().message;
    } else {
      const bool ok = reply->rfind("ERROR", 0) != 0;
      record.outcome = ok ? "ok" : "error";
      record.status = 200;
      record.reply = *reply;
      if (!ok) record.code = std::atoi(reply->c_str() + 5);
      if (ok && read_back) record.after = ask(*read_back);
    }
    audit(req, session, std::move(record));
  }
  if (!reply) return sendError(res, reply.error());
  sendJson(res, {{"reply", *reply}});
}

nlohmann::json WebServer::Impl::cameraBefore(const std::string& camera, const std::string& action,
                                             const nlohmann::json& body) {
  if (action == "feature") {
    const auto name = body.find("name");
    if (name == body.end() || !name->is_string()) return nullptr;
    proto::ControlRequest request;
    request.mutable_get_feature()->set_camera(camera);
    request.mutable_get_feature()->set_name(name->get<std::string>());
    auto reply = cameras_->control(camera, request);
    if (!reply || !reply->has_feature()) return nullptr;
    return {{"name", reply->feature().feature().name()},
            {"value", reply->feature().feature().value()}};
  }
  // The rest from the camera list the poller keeps (refreshed every second).
  for (const auto& c : cameras_->cameras()) {
    if (c.value("name", "") != camera) continue;
    nlohmann::json out = nlohmann::json::object();
    const auto copy = [&](std::initializer_list<const char*> keys) {
      for (const char* key : keys)
        if (c.contains(key)) out[key] = c[key];
    };
    if (action == "roi") copy({"roi"});
    if (action == "size") copy({"width", "height", "scale_x", "scale_y"});
    if (action == "mode")
      copy({"mode", "fps", "trigger_line", "trigger_activation", "trigger_timeout_ms"});
    if (action == "open" || action == "close") copy({"state"});
    if (action == "target") copy({"simulated_robot"});
    return out.empty() ? nlohmann::json() : out;
  }
  return nullptr;
}

void WebServer::Impl::cameraAction(const std::string& camera, const std::string& action,
                                   const httplib::Request& req, httplib::Response& res) {
  if (!cameras_->feed(camera))
    return sendError(res, WebErrc::kNotFound, "no camera '" + camera + "'");
  auto body = parseJsonBody(req.body);
  if (!body) return sendError(res, body.error());
  auto request = web::cameraAction(camera, action, *body);
  if (!request) return sendError(res, request.error());
  // A trigger takes a frame as LOCATE does: not a change of the cell.
  const bool change = action != "trigger";
  AuditRecord record;
  if (change) {
    record.action = "camera." + action;
    record.target = camera;
    record.arguments = *body;
    record.before = cameraBefore(camera, action, *body);
  }
  auto reply = cameras_->control(camera, *request);
  if (change) {
    record.outcome = reply ? "ok" : "error";
    record.status = reply ? 200 : httpStatus(reply.error());
    if (!reply)
      record.reply = reply.error().message;
    else if (reply->has_feature())
      record.after = {{"name", reply->feature().feature().name()},
                      {"value", reply->feature().feature().value()}};
    audit(req, sessionOf(req), std::move(record));
  }
  if (!reply) return sendError(res, reply.error());
  sendJson(res, actionReplyJson(*reply));
}

void WebServer::Impl::auditRoutes() {
  http_->Get("/api/audit", [this](const httplib::Request& req, httplib::Response& res) {
    size_t limit = 100;
    if (req.has_param("limit")) {
      const auto n = parseInt(req.get_param_value("limit"));
      if (!n || *n < 1 || *n > 1000)
        return sendError(res, WebErrc::kBadRequest, "limit: a number of records, 1..1000");
      limit = static_cast<size_t>(*n);
    }
    auto read = audit_->newest(limit);
    // The notes go to the reader only: the log would repeat them at every
    // refresh of the panel.
    sendJson(res, {{"records", read.records},
                   {"notes", read.notes},
                   {"file", options_.audit_file.empty() ? nlohmann::json(nullptr)
                                                        : nlohmann::json(options_.audit_file)}});
  });
  http_->Get("/api/audit.jsonl", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_header("Content-Disposition", "attachment; filename=\"picksight-audit.jsonl\"");
    res.set_content(audit_->exportAll(), "application/jsonl");
  });
}

WebServer::WebServer(WebOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
WebServer::~WebServer() = default;
Result<void> WebServer::start() { return impl_->start(); }
void WebServer::stop() { impl_->stop(); }
uint16_t WebServer::port() const { return static_cast<uint16_t>(impl_->port_); }

namespace {
std::string urlOf(const std::string& scheme, const std::string& host, int port) {
  const bool v6 = host.find(':') != std::string::npos;
  return scheme + "://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}
}  // namespace

std::string WebServer::url() const {
  return urlOf(impl_->tls() ? "https" : "http", impl_->options_.listen_host, impl_->port_);
}

std::string WebServer::redirectUrl() const {
  if (!impl_->redirect_gate_) return "";
  return urlOf("http", impl_->options_.redirect_host, impl_->redirect_port_);
}

}  // namespace picksight::web
