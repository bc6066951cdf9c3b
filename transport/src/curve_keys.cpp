// CURVE key files: reading them with their checks, writing their text, and
// the client options of a socket.
#include "picksight/transport/curve_keys.hpp"

#include <sys/stat.h>
#include <zmq.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "picksight/common/atomic_file.hpp"

namespace picksight::transport {
namespace {

// Bounds what is read: a key file is a few hundred bytes, an allow-list file
// holds one line per client.
constexpr off_t kMaxKeyFileBytes = 64 * 1024;
constexpr off_t kMaxAllowListBytes = 4 * 1024 * 1024;

struct KeyFileContent {
  std::vector<std::string> public_keys;
  std::vector<std::string> secret_keys;
};

bool isZ85Key(const std::string& text) {
  if (text.size() != kZ85KeyLength) return false;
  uint8_t bytes[32];
  return zmq_z85_decode(bytes, text.c_str()) != nullptr;
}

std::string trimmed(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(" \t\r") + 1 - begin);
}

// The value of `name = "value"` (quotes optional) on a trimmed line, or
// nullopt when the line sets something else.
std::optional<std::string> valueOf(const std::string& line, const std::string& name) {
  if (line.compare(0, name.size(), name) != 0) return std::nullopt;
  std::string rest = trimmed(line.substr(name.size()));
  if (rest.empty() || rest[0] != '=') return std::nullopt;
  rest = trimmed(rest.substr(1));
  if (rest.size() >= 2 && rest.front() == '"' && rest.back() == '"') {
    rest = rest.substr(1, rest.size() - 2);
  }
  return rest;
}

// Reads a regular file of at most `max_bytes`; with `secret`, refuses one
// that group or others may access.
Result<std::string> readKeyFile(const std::string& path, off_t max_bytes, bool secret) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return makeError(CurveErrc::kBadKeyFile, path + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) return makeError(CurveErrc::kBadKeyFile, path + ": not a file");
  if (st.st_size > max_bytes) {
    return makeError(CurveErrc::kBadKeyFile, path + ": too large for a key file (" +
                                                 std::to_string(st.st_size) + " bytes)");
  }
  if (secret && (st.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return makeError(CurveErrc::kKeyFileTooOpen,
                     std::string("permissions ") + mode + " for secret key file " + path +
                         " are too open: group and others must have no access (chmod 600 " + path +
                         ")");
  }
  auto text = readFile(path);
  if (!text) return makeError(CurveErrc::kBadKeyFile, path + ": " + text.error().message);
  return text;
}

Result<KeyFileContent> parseKeyFile(const std::string& path, const std::string& text) {
  KeyFileContent content;
  size_t line_number = 0;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = trimmed(text.substr(begin, end - begin));
    begin = end + 1;
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    for (const char* name : {"public-key", "secret-key"}) {
      auto value = valueOf(line, name);
      if (!value) continue;
      if (!isZ85Key(*value)) {
        return makeError(CurveErrc::kBadKeyFile,
                         path + ": line " + std::to_string(line_number) + ": " + name +
                             " is not a " + std::to_string(kZ85KeyLength) + "-character Z85 key");
      }
      (name[0] == 'p' ? content.public_keys : content.secret_keys).push_back(*value);
    }
  }
  return content;
}

Result<std::string> onlyPublicKey(const std::string& path, const KeyFileContent& content) {
  if (content.public_keys.size() != 1) {
    return makeError(CurveErrc::kBadKeyFile, path + ": expected one public-key line, found " +
                                                 std::to_string(content.public_keys.size()) +
                                                 " (is it a key file?)");
  }
  return content.public_keys.front();
}

std::string keyFileText(const CurveKeyPair& keys, bool secret) {
  std::string text =
      "#   ZeroMQ CURVE " + std::string(secret ? "**secret**" : "public") +
      " key, made by picksight-keygen\n" +
      (secret ? "#   Keep it secret: never copy it to another host or loosen its permissions.\n"
              : "#   Give it to the peers that must know this host.\n") +
      "\nmetadata\ncurve\n    public-key = \"" + keys.public_key + "\"\n";
  if (secret) text += "    secret-key = \"" + keys.secret_key + "\"\n";
  return text;
}

}  // namespace

const char* errorName(CurveErrc e) {
  switch (e) {
    case CurveErrc::kBadKeyFile:
      return "bad key file";
    case CurveErrc::kKeyFileTooOpen:
      return "key file too open";
    case CurveErrc::kNotSupported:
      return "curve not supported";
    case CurveErrc::kZapHandlerTaken:
      return "zap handler taken";
  }
  return "unknown";
}

Result<void> curveAvailable() {
  if (zmq_has("curve") == 0) {
    return makeError(CurveErrc::kNotSupported, "this libzmq was built without CURVE");
  }
  return {};
}

Result<CurveKeyPair> generateKeyPair() {
  if (auto ok = curveAvailable(); !ok) return ok.error();
  char public_key[kZ85KeyLength + 1];
  char secret_key[kZ85KeyLength + 1];
  if (zmq_curve_keypair(public_key, secret_key) != 0) {
    return makeError(CurveErrc::kNotSupported,
                     std::string("zmq_curve_keypair: ") + zmq_strerror(zmq_errno()));
  }
  return CurveKeyPair{public_key, secret_key};
}

std::string publicKeyFileText(const CurveKeyPair& keys) { return keyFileText(keys, false); }
std::string secretKeyFileText(const CurveKeyPair& keys) { return keyFileText(keys, true); }

Result<std::string> loadPublicKey(const std::string& path) {
  auto text = readKeyFile(path, kMaxKeyFileBytes, false);
  if (!text) return text.error();
  auto content = parseKeyFile(path, *text);
  if (!content) return content.error();
  return onlyPublicKey(path, *content);
}

Result<CurveKeyPair> loadKeyPair(const std::string& path) {
  if (auto ok = curveAvailable(); !ok) return ok.error();
  auto text = readKeyFile(path, kMaxKeyFileBytes, true);
  if (!text) return text.error();
  auto content = parseKeyFile(path, *text);
  if (!content) return content.error();
  auto public_key = onlyPublicKey(path, *content);
  if (!public_key) return public_key.error();
  if (content->secret_keys.size() != 1) {
    return makeError(CurveErrc::kBadKeyFile,
                     path + ": expected one secret-key line, found " +
                         std::to_string(content->secret_keys.size()) +
                         " (a public NAME.key given where NAME.key_secret is needed?)");
  }
  const std::string& secret_key = content->secret_keys.front();
  char derived[kZ85KeyLength + 1];
  if (zmq_curve_public(derived, secret_key.c_str()) != 0 || *public_key != derived) {
    return makeError(CurveErrc::kBadKeyFile,
                     path + ": the public key is not the secret key's (a damaged file?)");
  }
  return CurveKeyPair{*public_key, secret_key};
}

Result<std::set<std::string>> loadAllowList(const std::string& path) {
  std::set<std::string> keys;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(path, ec)) {
      if (entry.path().extension() == ".key") files.push_back(entry.path().string());
    }
    if (ec) return makeError(CurveErrc::kBadKeyFile, path + ": " + ec.message());
    std::sort(files.begin(), files.end());  // the first bad file named is always the same
    for (const std::string& file : files) {
      auto key = loadPublicKey(file);
      if (!key) return key.error();
      keys.insert(*key);
    }
  } else {
    auto text = readKeyFile(path, kMaxAllowListBytes, false);
    if (!text) return text.error();
    auto content = parseKeyFile(path, *text);
    if (!content) return content.error();
    keys.insert(content->public_keys.begin(), content->public_keys.end());
  }
  if (keys.empty()) {
    return makeError(CurveErrc::kBadKeyFile,
                     path +
                         ": the allow-list holds no public key (*.key files or public-key "
                         "lines): it would admit nobody");
  }
  return keys;
}

Result<CurveClientKeys> loadClientKeys(const std::string& key_file,
                                       const std::string& server_key_file) {
  CurveClientKeys keys;
  auto server = loadPublicKey(server_key_file);
  if (!server) return server.error();
  keys.server_public_key = std::move(*server);
  auto own = key_file.empty() ? generateKeyPair() : loadKeyPair(key_file);
  if (!own) return own.error();
  keys.own = std::move(*own);
  return keys;
}

void secureClientSocket(zmq::socket_t& socket, const std::optional<CurveClientKeys>& keys) {
  if (!keys) return;
  socket.set(zmq::sockopt::curve_serverkey, keys->server_public_key);
  socket.set(zmq::sockopt::curve_publickey, keys->own.public_key);
  socket.set(zmq::sockopt::curve_secretkey, keys->own.secret_key);
}

}  // namespace picksight::transport
