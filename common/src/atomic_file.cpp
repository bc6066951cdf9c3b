// Atomic replace through write-temp, fsync, rename, fsync-directory.
#include "picksight/common/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
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
}  // namespace

Result<void> writeFileAtomically(const std::string& path, const std::string& content) {
  return writeFileAtomically(path, content, [](std::string_view) {});
}

Result<void> writeFileAtomically(const std::string& path, const std::string& content,
                                 const std::function<void(std::string_view step)>& before_step) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
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
