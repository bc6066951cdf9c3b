// The server side of ZeroMQ CURVE: the server's key pair, applied to any
// socket in one call, and a ZAP handler that admits only allow-listed client
// public keys. Without an allow-list CURVE only encrypts: every client that
// knows the server's public key gets in.
//
// Threading: secure() may be called from any thread (it only reads the keys)
// on a socket owned by the caller, before bind. The ZAP handler runs on a
// thread of its own, which owns its REP socket; the counters are atomic.
// The context must outlive this object.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight/transport/curve_keys.hpp"

namespace picksight::transport {

class CurveServer {
 public:
  // Loads the server's secret key file and, when `allow_list` is not empty,
  // the allow-list, and then starts the ZAP handler on `context` (one per
  // context: ZeroMQ asks inproc://zeromq.zap.01). Errors name the file.
  static Result<std::unique_ptr<CurveServer>> start(zmq::context_t& context,
                                                    const std::string& secret_key_file,
                                                    const std::string& allow_list);
  ~CurveServer();
  CurveServer(const CurveServer&) = delete;
  CurveServer& operator=(const CurveServer&) = delete;

  // Makes `socket` a CURVE server with this key pair (before bind).
  void secure(zmq::socket_t& socket) const;

  const std::string& publicKey() const { return keys_.public_key; }
  // True when only allow-listed clients get in (a ZAP handler runs).
  bool restricted() const { return allowed_.has_value(); }
  uint64_t admitted() const { return admitted_.load(); }
  uint64_t refused() const { return refused_.load(); }

 private:
  CurveServer(CurveKeyPair keys, std::optional<std::set<std::string>> allowed);
  void run(zmq::socket_t socket);
  // Decides one ZAP request (credentials: the client's 32-byte public key),
  // counting it and logging refusals.
  bool admit(const std::string& mechanism, const std::string& credentials,
             const std::string& address);

  const CurveKeyPair keys_;
  const std::optional<std::set<std::string>> allowed_;  // Z85 public keys
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> admitted_{0};
  std::atomic<uint64_t> refused_{0};
  std::map<std::string, uint64_t> refusals_by_key_;  // ZAP thread only; bounds the log
  std::thread thread_;
};

// Makes `socket` a CURVE server when `curve` is given, else leaves it plain.
inline void secureServerSocket(zmq::socket_t& socket, const CurveServer* curve) {
  if (curve) curve->secure(socket);
}

}  // namespace picksight::transport
