// The facade of codecs.hpp: opens the module once, then calls through its
// table.
#include "picksight/codecs/codecs.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "module_table.hpp"

namespace picksight::codecs {

namespace {

const ModuleTable& table() {
  // Opened once per process (a function-local static is initialized by one
  // thread while others wait; one that threw is tried again at the next
  // call) and never closed: a VideoStream it made runs its code for as long
  // as the stream lives.
  static const ModuleTable* const loaded = [] {
    const std::string path = modulePath();
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = dlerror();
      throw std::runtime_error("cannot open the image and video codecs (" + path +
                               "): " + (why ? why : "unknown reason"));
    }
    using Entry = const ModuleTable* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(handle, kModuleEntry));
    if (!entry)
      throw std::runtime_error("the image and video codecs (" + path + ") have no " + kModuleEntry);
    const ModuleTable* t = entry();
    if (!t || t->version != kModuleVersion)
      throw std::runtime_error("the image and video codecs (" + path +
                               ") are from another build of PickSight");
    return t;
  }();
  return *loaded;
}

}  // namespace

std::string modulePath() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec)
    throw std::runtime_error("cannot find this program's directory (/proc/self/exe): " +
                             ec.message());
  return (exe.parent_path() / ".." / "lib" / "picksight" / "libpicksight_codecs.so")
      .lexically_normal()
      .string();
}

cv::Mat imread(const std::string& path, int flags) { return table().imread(path, flags); }

bool imwrite(const std::string& path, cv::InputArray image, const std::vector<int>& params) {
  return table().imwrite(path, image, params);
}

cv::Mat imdecode(cv::InputArray bytes, int flags) { return table().imdecode(bytes, flags); }

bool imencode(const std::string& ext, cv::InputArray image, std::vector<uchar>& bytes,
              const std::vector<int>& params) {
  return table().imencode(ext, image, bytes, params);
}

bool haveImageWriter(const std::string& path) { return table().haveImageWriter(path); }

std::unique_ptr<VideoStream> newVideoStream() {
  return std::unique_ptr<VideoStream>(table().newVideoStream());
}

}  // namespace picksight::codecs
