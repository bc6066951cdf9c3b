// The users file of the web HMI, with argon2id hashes (user_store.hpp).
#include "picksight/web/user_store.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "picksight/common/atomic_file.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {

constexpr size_t kMaxUsers = 256;

bool validName(const std::string& name) {
  if (name.empty() || name.size() > 32) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

// libsodium must be initialised once before use; idempotent and thread-safe.
bool sodiumReady() {
  static const bool ready = sodium_init() >= 0;
  return ready;
}

// argon2id takes 64 MiB a hash: one at a time in the process, so that
// logins from many addresses at once cost 64 MiB, not 64 MiB each.
std::mutex& hashing() {
  static std::mutex m;
  return m;
}

std::string hashPassword(const std::string& password) {
  std::lock_guard<std::mutex> lock(hashing());
  char out[crypto_pwhash_STRBYTES];
  if (crypto_pwhash_str(out, password.data(), password.size(), crypto_pwhash_OPSLIMIT_INTERACTIVE,
                        crypto_pwhash_MEMLIMIT_INTERACTIVE) != 0)
    return "";  // out of memory
  return out;
}

// A hash of no one's password, checked against when the name is unknown so
// that the answer takes as long as for a known name.
const std::string& decoyHash() {
  static const std::string hash = hashPassword(UserStore::randomPassword(24));
  return hash;
}

}  // namespace

const char* roleName(Role role) {
  switch (role) {
    case Role::kOperator:
      return "operator";
    case Role::kEngineer:
      return "engineer";
    case Role::kAdmin:
      return "admin";
  }
  return "operator";
}

std::optional<Role> parseRole(const std::string& name) {
  for (Role r : {Role::kOperator, Role::kEngineer, Role::kAdmin})
    if (name == roleName(r)) return r;
  return std::nullopt;
}

UserStore::UserStore(UserStore&& other) noexcept : path_(std::move(other.path_)) {
  std::lock_guard<std::mutex> lock(other.mutex_);
  users_ = std::move(other.users_);
}

Result<UserStore> UserStore::open(const std::string& path) {
  if (!sodiumReady()) return makeError(WebErrc::kBadConfig, "libsodium cannot be initialised");
  UserStore store(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return store;
  auto text = readFile(path);
  if (!text) return makeError(WebErrc::kBadConfig, path + ": " + text.error().message);
  const auto json = nlohmann::json::parse(*text, nullptr, false);
  if (!json.is_object() || !json.contains("users") || !json["users"].is_array())
    return makeError(WebErrc::kBadConfig, path + ": expected {\"users\": [...]}");
  for (const auto& u : json["users"]) {
    Entry e;
    if (!u.is_object() || !u.value("name", nlohmann::json()).is_string() ||
        !u.value("role", nlohmann::json()).is_string() ||
        !u.value("hash", nlohmann::json()).is_string())
      return makeError(WebErrc::kBadConfig, path + ": each user needs name, role and hash");
    e.name = u["name"].get<std::string>();
    auto role = parseRole(u["role"].get<std::string>());
    e.hash = u["hash"].get<std::string>();
    if (!validName(e.name) || !role || e.hash.rfind("$argon2id$", 0) != 0 ||
        e.hash.size() >= crypto_pwhash_STRBYTES)
      return makeError(WebErrc::kBadConfig, path + ": user '" + e.name +
                                                "': bad name, role (operator, engineer, admin) "
                                                "or hash (argon2id)");
    e.role = *role;
    store.users_.push_back(std::move(e));
    if (store.users_.size() > kMaxUsers)
      return makeError(WebErrc::kBadConfig, path + ": more than 256 users");
  }
  return store;
}

Result<bool> UserStore::makeFirstAdmin(const std::string& users_file,
                                       const std::string& password_file) {
  if (users_file.empty()) return makeError(WebErrc::kBadConfig, "no users file (--users)");
  auto store = open(users_file);
  if (!store) return store.error();
  if (!store->empty()) return false;
  const std::string password = randomPassword(20);
  // O_EXCL: a password file that exists is someone's; 0600: root's alone.
  const int fd =
      ::open(password_file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0)
    return makeError(WebErrc::kBadConfig,
                     password_file + ": cannot create (" + std::strerror(errno) + ")");
  const std::string line = password + "\n";
  const bool written = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size()) &&
                       ::fsync(fd) == 0;
  ::close(fd);
  if (!written) {
    ::unlink(password_file.c_str());
    return makeError(WebErrc::kBadConfig, password_file + ": cannot write");
  }
  if (auto set = store->set("admin", Role::kAdmin, password); !set) {
    ::unlink(password_file.c_str());
    return set.error();
  }
  return true;
}

Result<void> UserStore::save() const {
  if (path_.empty()) return {};  // users in memory only
  nlohmann::json users = nlohmann::json::array();
  for (const auto& e : users_)
    users.push_back({{"name", e.name}, {"role", roleName(e.role)}, {"hash", e.hash}});
  return writeFileAtomically(path_, nlohmann::json{{"users", users}}.dump(1) + "\n");
}

Result<void> UserStore::set(const std::string& name, Role role, const std::string& password) {
  return change(name, role, password, Mode::kAddOrReplace);
}

Result<void> UserStore::add(const std::string& name, Role role, const std::string& password) {
  return change(name, role, password, Mode::kAdd);
}

Result<void> UserStore::setRole(const std::string& name, Role role) {
  return change(name, role, std::nullopt, Mode::kChange);
}

Result<void> UserStore::setPassword(const std::string& name, const std::string& password) {
  return change(name, std::nullopt, password, Mode::kChange);
}

Result<void> UserStore::change(const std::string& name, std::optional<Role> role,
                               const std::optional<std::string>& password, Mode mode) {
  if (!validName(name))
    return makeError(WebErrc::kBadRequest, "a user name is 1 to 32 of A-Z a-z 0-9 _ - .");
  if (password && (password->size() < 8 || password->size() > 256))
    return makeError(WebErrc::kBadRequest, "a password is 8 to 256 bytes");
  std::string hash;
  if (password) {
    hash = hashPassword(*password);  // outside the lock: ~50 ms, 64 MiB
    if (hash.empty()) return makeError(WebErrc::kBadRequest, "out of memory hashing the password");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  auto it =
      std::find_if(users_.begin(), users_.end(), [&](const Entry& e) { return e.name == name; });
  const auto old = users_;
  if (it == users_.end()) {
    if (mode == Mode::kChange) return makeError(WebErrc::kNotFound, "no user '" + name + "'");
    if (!role || !password)
      return makeError(WebErrc::kBadRequest, "a new user needs a role and a password");
    if (users_.size() >= kMaxUsers) return makeError(WebErrc::kBadRequest, "256 users already");
    users_.push_back({name, *role, hash});
  } else {
    if (mode == Mode::kAdd)
      return makeError(WebErrc::kConflict, "user '" + name + "' exists already");
    const bool last_admin = it->role == Role::kAdmin && role && *role != Role::kAdmin &&
                            std::count_if(users_.begin(), users_.end(), [](const Entry& e) {
                              return e.role == Role::kAdmin;
                            }) == 1;
    if (last_admin)
      return makeError(
          WebErrc::kConflict,
          "'" + name + "' is the last admin and stays an admin: make another admin first");
    if (role) it->role = *role;
    if (password) it->hash = hash;
  }
  if (auto saved = save(); !saved) {
    users_ = old;  // nothing changed, in memory either
    return saved.error();
  }
  return {};
}

Result<void> UserStore::remove(const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it =
      std::find_if(users_.begin(), users_.end(), [&](const Entry& e) { return e.name == name; });
  if (it == users_.end()) return makeError(WebErrc::kNotFound, "no user '" + name + "'");
  if (it->role == Role::kAdmin && std::count_if(users_.begin(), users_.end(), [](const Entry& e) {
                                    return e.role == Role::kAdmin;
                                  }) == 1)
    return makeError(
        WebErrc::kConflict,
        "'" + name + "' is the last admin and cannot be removed: make another admin first");
  const auto old = users_;
  users_.erase(it);
  if (auto saved = save(); !saved) {
    users_ = old;
    return saved.error();
  }
  return {};
}

std::optional<Role> UserStore::verify(const std::string& name, const std::string& password) const {
  std::string hash;
  std::optional<Role> role;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& e : users_)
      if (e.name == name) {
        hash = e.hash;
        role = e.role;
      }
  }
  const std::string& against = role ? hash : decoyHash();
  std::unique_lock<std::mutex> hashing_lock(hashing());
  const bool ok = crypto_pwhash_str_verify(against.c_str(), password.data(), password.size()) == 0;
  hashing_lock.unlock();
  return ok && role ? role : std::nullopt;
}

std::vector<UserInfo> UserStore::list() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<UserInfo> out;
  for (const auto& e : users_) out.push_back({e.name, e.role});
  return out;
}

bool UserStore::empty() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return users_.empty();
}

std::string UserStore::randomPassword(size_t length) {
  static const char kAlphabet[] = "abcdefghijkmnpqrstuvwxyzABCDEFGHJKLMNPQRSTUVWXYZ23456789";
  sodiumReady();
  std::string out;
  for (size_t i = 0; i < length; ++i)
    out += kAlphabet[randombytes_uniform(static_cast<uint32_t>(sizeof(kAlphabet) - 1))];
  return out;
}

}  // namespace picksight::web
