// The web HMI's users: a name, a role and an argon2id password hash
// (libsodium's crypto_pwhash_str) each, kept in one JSON file that is
// replaced atomically on every change (docs/SECURITY.md).
//
// Roles, each including the one before: an operator watches, locates and
// runs jobs; an engineer also teaches, sets tolerances, calibrates and
// changes camera settings; an admin also manages the users.
//
// Threading: every member may be called from any thread (one mutex; a
// password check runs outside it, since argon2id takes tens of ms).
#pragma once

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "picksight/common/result.hpp"

namespace picksight::web {

enum class Role { kOperator = 0, kEngineer = 1, kAdmin = 2 };
const char* roleName(Role role);
std::optional<Role> parseRole(const std::string& name);

struct UserInfo {
  std::string name;
  Role role = Role::kOperator;
};

class UserStore {
 public:
  // Reads `path` (a missing file is no users yet); errors name the file.
  static Result<UserStore> open(const std::string& path);
  UserStore(UserStore&& other) noexcept;

  // Adds or replaces a user (name: 1..32 of A-Z a-z 0-9 _ - .; password:
  // 8..256 bytes) and writes the file.
  Result<void> set(const std::string& name, Role role, const std::string& password);
  // Adds a user; one of that name already is a conflict (WebErrc::kConflict).
  Result<void> add(const std::string& name, Role role, const std::string& password);
  // Changes an existing user's role, or password, keeping the rest
  // (WebErrc::kNotFound for an unknown name).
  Result<void> setRole(const std::string& name, Role role);
  Result<void> setPassword(const std::string& name, const std::string& password);
  // Removes a user and writes the file. The last admin can neither be
  // removed nor lose the role (WebErrc::kConflict): nobody could manage the
  // users any more.
  Result<void> remove(const std::string& name);
  // The user's role when `password` is theirs. An unknown name costs the
  // same time as a wrong password.
  std::optional<Role> verify(const std::string& name, const std::string& password) const;
  std::vector<UserInfo> list() const;
  bool empty() const;

  // A random password of `length` letters and digits (first start).
  static std::string randomPassword(size_t length = 16);

  // At install (the package's postinst): when `users_file` holds no user,
  // makes 'admin' with a random password and writes that password to
  // `password_file`, created with mode 0600 (never over an existing file);
  // true when it did, false when there were users already.
  static Result<bool> makeFirstAdmin(const std::string& users_file,
                                     const std::string& password_file);

 private:
  explicit UserStore(std::string path) : path_(std::move(path)) {}
  struct Entry {
    std::string name;
    Role role = Role::kOperator;
    std::string hash;
  };
  Result<void> save() const;  // under mutex_
  // What add, set, setRole and setPassword share: `role` and `password`
  // (either may be absent for an existing user) applied to user `name`,
  // who must not exist (kAdd), may (kAddOrReplace) or must (kChange).
  enum class Mode { kAdd, kAddOrReplace, kChange };
  Result<void> change(const std::string& name, std::optional<Role> role,
                      const std::optional<std::string>& password, Mode mode);

  std::string path_;
  mutable std::mutex mutex_;
  std::vector<Entry> users_;  // under mutex_
};

}  // namespace picksight::web
