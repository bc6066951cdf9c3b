// Atomic replace through write-temp, fsync, rename, fsync-directory.
#include "picksight/common/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace picksight {
namespace {
std::string errnoText(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

// Closes the descriptor on every path out of writeFileAtomically.
struct FdGuard {
  int fd;
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
};

constexpr std::string_view kTemporaryMark = ".tmp.";

// "<name>.tmp.<digits>", as writeFileAtomically names its temporary file.
bool isTemporaryName(const std::string& name) {
  const size_t mark = name.rfind(kTemporaryMark);
  if (mark == std::string::npos || mark == 0) return false;
  const size_t digits = mark + kTemporaryMark.size();
  if (digits == name.size()) return false;
  for (size_t i = digits; i < name.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return false;
  }
  return true;
}
}  // namespace

Result<std::vector<std::string>> removeStaleTemporaries(const std::string& directory) {
  namespace fs = std::filesystem;
  std::vector<std::string> removed;
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) return removed;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!isTemporaryName(name) || !it->is_regular_file(ec)) continue;
    if (fs::remove(it->path(), ec)) removed.push_back(name);
    if (ec) break;
  }
  if (ec) return systemError(ec.value(), directory + ": " + ec.message());
  if (!removed.empty()) (void)syncDirectory(directory);
  return removed;
}

Result<void> writeFileAtomically(const std::string& path, const std::string& content) {
  return writeFileAtomically(path, content, [](std::string_view) {});
}

Result<void> writeFileAtomically(const std::string& path, const std::string& content,
                                 const std::function<void(std::string_view step)>& before_step) {
  const std::string tmp = path + std::string(kTemporaryMark) + std::to_string(::getpid());
  {
    before_step("create");
    FdGuard file{::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)};
    if (file.fd < 0) return systemError(errno, errnoText("cannot create", tmp));
    const char* p = content.data();
    size_t left = content.size();
    while (left > 0) {
      before_step("write");
      ssize_t n = ::write(file.fd, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        Error e = systemError(errno, errnoText("cannot write", tmp));
        ::unlink(tmp.c_str());
        return e;
      }
      p += n;
      left -= static_cast<size_t>(n);
    }
    before_step("sync");
    if (::fsync(file.fd) != 0) {
      Error e = systemError(errno, errnoText("cannot sync", tmp));
      ::unlink(tmp.c_str());
      return e;
    }
    before_step("close");
  }
  before_step("rename");
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    Error e = systemError(errno, errnoText("cannot rename over", path));
    ::unlink(tmp.c_str());
    return e;
  }
  // The rename itself is only durable once the directory entry is on disk.
  const size_t slash = path.find_last_of('/');
  before_step("sync-dir");
  (void)syncDirectory(slash == std::string::npos ? "." : path.substr(0, slash + 1));
  return {};
}

Result<void> syncDirectory(const std::string& directory) {
  FdGuard dir{::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)};
  if (dir.fd < 0) return systemError(errno, errnoText("cannot open", directory));
  if (::fsync(dir.fd) != 0) return systemError(errno, errnoText("cannot sync", directory));
  return {};
}

Result<std::string> readFile(const std::string& path) {
  // An ifstream opens a directory and reads it as an empty file.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    return systemError(EISDIR, "cannot read " + path + ": is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return systemError(ENOENT, "cannot open " + path);
  std::ostringstream out;
  out << in.rdbuf();
  if (in.bad()) return systemError(EIO, "cannot read " + path);
  return out.str();
}

}  // namespace picksight
