// CURVE server keys and the ZAP handler (ZAP 1.0, ZeroMQ RFC 27): ZeroMQ
// asks it about every CURVE handshake on the context's server sockets.
#include "picksight/transport/curve_server.hpp"

#include <zmq.h>

#include <vector>

#include "picksight/common/log.hpp"

namespace picksight::transport {
namespace {

constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";
constexpr const char* kZapDomain = "picksight";
// Distinct refused keys remembered for the log; beyond it the memory starts
// over (an attacker cycling keys cannot grow it).
constexpr size_t kMaxRememberedKeys = 1024;

std::string z85(const std::string& binary_key) {
  if (binary_key.size() != 32) return "(not a CURVE key)";
  char text[kZ85KeyLength + 1];
  zmq_z85_encode(text, reinterpret_cast<const uint8_t*>(binary_key.data()), 32);
  return text;
}

// Logs the 1st, 10th, 100th... refusal of a key: a refused client retries
// every reconnect interval and must not flood the log.
bool worthLogging(uint64_t count) {
  while (count >= 10 && count % 10 == 0) count /= 10;
  return count == 1;
}

}  // namespace

Result<std::unique_ptr<CurveServer>> CurveServer::start(zmq::context_t& context,
                                                        const std::string& secret_key_file,
                                                        const std::string& allow_list) {
  auto keys = loadKeyPair(secret_key_file);
  if (!keys) return keys.error();
  std::optional<std::set<std::string>> allowed;
  if (!allow_list.empty()) {
    auto list = loadAllowList(allow_list);
    if (!list) return list.error();
    allowed = std::move(*list);
  }
  std::unique_ptr<CurveServer> server(new CurveServer(std::move(*keys), std::move(allowed)));
  if (server->allowed_) {
    zmq::socket_t socket(context, zmq::socket_type::rep);
    socket.set(zmq::sockopt::linger, 0);
    try {
      socket.bind(kZapEndpoint);
    } catch (const zmq::error_t& e) {
      return makeError(CurveErrc::kZapHandlerTaken,
                       std::string("cannot start the ZAP handler: ") + e.what());
    }
    server->thread_ = std::thread(
        [s = server.get(), socket = std::move(socket)]() mutable { s->run(std::move(socket)); });
  }
  return server;
}

CurveServer::CurveServer(CurveKeyPair keys, std::optional<std::set<std::string>> allowed)
    : keys_(std::move(keys)), allowed_(std::move(allowed)) {}

CurveServer::~CurveServer() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void CurveServer::secure(zmq::socket_t& socket) const {
  socket.set(zmq::sockopt::curve_server, true);
  socket.set(zmq::sockopt::curve_secretkey, keys_.secret_key);
  socket.set(zmq::sockopt::zap_domain, kZapDomain);
}

bool CurveServer::admit(const std::string& mechanism, const std::string& credentials,
                        const std::string& address) {
  // Only CURVE sockets are secured; a NULL or PLAIN handshake reaching the
  // handler is not ours to admit.
  const std::string key = z85(credentials);
  if (mechanism == "CURVE" && allowed_->count(key) > 0) {
    ++admitted_;
    return true;
  }
  ++refused_;
  if (refusals_by_key_.size() >= kMaxRememberedKeys) refusals_by_key_.clear();
  const uint64_t count = ++refusals_by_key_[key];
  if (worthLogging(count)) {
    logWarning("CURVE: refused client key ", key, " from ", address, " (", mechanism,
               "): not in the allow-list (", count, count == 1 ? " time)" : " times)");
  }
  return false;
}

void CurveServer::run(zmq::socket_t socket) {
  while (!stop_) {
    zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
    try {
      if (zmq::poll(&item, 1, std::chrono::milliseconds(100)) == 0) continue;
      std::vector<std::string> parts;
      for (;;) {
        zmq::message_t part;
        if (!socket.recv(part, zmq::recv_flags::dontwait)) break;
        parts.push_back(part.to_string());
        if (!part.more()) break;
      }
      // Request: version, request id, domain, address, routing id,
      // mechanism, credentials...
      const bool well_formed = parts.size() >= 6 && parts[0] == "1.0";
      const bool ok = well_formed && admit(parts[5], parts.size() > 6 ? parts[6] : "", parts[3]);
      const char* status = !well_formed ? "500" : ok ? "200" : "400";
      const std::vector<std::string> reply = {"1.0",
                                              parts.size() > 1 ? parts[1] : "",
                                              status,
                                              !well_formed ? "malformed ZAP request"
                                              : ok         ? "OK"
                                                           : "not in the allow-list",
                                              ok ? z85(parts[6]) : "",
                                              ""};
      for (size_t i = 0; i < reply.size(); ++i) {
        socket.send(zmq::buffer(reply[i]),
                    i + 1 < reply.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
      }
    } catch (const zmq::error_t& e) {
      // Never let an exception leave the thread: log and go on, unless the
      // context is going away.
      if (e.num() == ETERM) return;
      logError("CURVE: ZAP handler: ", e.what());
    }
  }
}

}  // namespace picksight::transport
