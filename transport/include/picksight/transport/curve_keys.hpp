// ZeroMQ CURVE keys as files, and the client side of an encrypted socket.
//
// Key files use ZeroMQ's certificate text (as czmq and pyzmq's zmq.auth write
// and read them): `public-key = "<Z85>"` in NAME.key, and both
// `public-key` and `secret-key` in NAME.key_secret; lines starting with '#'
// are comments. Keys are 40 Z85 characters (32 bytes).
//
// Threading: plain functions and values; a socket is secured by the thread
// that owns it, before it connects or binds.
#pragma once

#include <optional>
#include <set>
#include <string>

#include <zmq.hpp>

#include "picksight/common/result.hpp"

namespace picksight::transport {

enum class CurveErrc {
  kBadKeyFile = 1,   // missing, unreadable or malformed key or allow-list file
  kKeyFileTooOpen,   // a secret key file that group or others may read
  kNotSupported,     // libzmq built without CURVE
  kZapHandlerTaken,  // the context already has a ZAP handler
};
const char* errorName(CurveErrc e);
PICKSIGHT_ERROR_DOMAIN(CurveErrc, "curve")

constexpr size_t kZ85KeyLength = 40;

// A key pair in Z85 text.
struct CurveKeyPair {
  std::string public_key;
  std::string secret_key;
};

// An error unless this libzmq has CURVE.
Result<void> curveAvailable();

// A fresh key pair (zmq_curve_keypair).
Result<CurveKeyPair> generateKeyPair();

// The texts of NAME.key (public only) and NAME.key_secret (both keys).
std::string publicKeyFileText(const CurveKeyPair& keys);
std::string secretKeyFileText(const CurveKeyPair& keys);

// The public key of a key file (NAME.key, or a NAME.key_secret). Errors name
// the file.
Result<std::string> loadPublicKey(const std::string& path);

// The pair of a secret key file. Refused, like ssh refuses a private key,
// when group or others have any access to it; the public key must be the
// secret key's. Errors name the file.
Result<CurveKeyPair> loadKeyPair(const std::string& path);

// The client public keys an allow-list admits: a directory (every *.key file
// in it, one key each) or one file (every public-key line in it). An empty
// list is an error: it would admit nobody, surely not what was meant.
Result<std::set<std::string>> loadAllowList(const std::string& path);

// What a client needs to talk to a CURVE server.
struct CurveClientKeys {
  CurveKeyPair own;
  std::string server_public_key;
};

// Loads the client's keys: `server_key_file` (the server's public key) is
// required; without `key_file` the client makes itself a fresh pair, which
// is enough for a server without an allow-list.
Result<CurveClientKeys> loadClientKeys(const std::string& key_file,
                                       const std::string& server_key_file);

// Makes `socket` a CURVE client of the server (before connect). With
// nullopt it stays plain: callers pass their optional keys through.
void secureClientSocket(zmq::socket_t& socket, const std::optional<CurveClientKeys>& keys);

}  // namespace picksight::transport

PICKSIGHT_ERROR_ENUM(picksight::transport::CurveErrc)
