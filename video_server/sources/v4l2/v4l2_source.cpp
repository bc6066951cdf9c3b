// V4L2 camera source.
#include "v4l2_source.hpp"

#include <fcntl.h>
#include <sys/mman.h>

#include <strings.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <tuple>

#include "lib_v4l2_device.hpp"
#include "picksight/common/log.hpp"

namespace picksight::video {
namespace {

struct FormatInfo {
  uint32_t fourcc;
  const char* option;  // the URI's format= value
  PixelLayout layout;
  int cv_type;  // -1: compressed, one row of bytesused bytes
};

// In order of preference when the URI names no format: YUYV is exact and
// cheap; MJPEG is what USB 2 webcams need for large sizes at full rate.
constexpr FormatInfo kFormats[] = {
    {V4L2_PIX_FMT_YUYV, "yuyv", PixelLayout::kYUYV, CV_8UC2},
    {V4L2_PIX_FMT_MJPEG, "mjpeg", PixelLayout::kMJPEG, -1},
    {V4L2_PIX_FMT_JPEG, "jpeg", PixelLayout::kMJPEG, -1},
    {V4L2_PIX_FMT_UYVY, "uyvy", PixelLayout::kUYVY, CV_8UC2},
    {V4L2_PIX_FMT_GREY, "grey", PixelLayout::kMono8, CV_8UC1},
    {V4L2_PIX_FMT_Y16, "y16", PixelLayout::kMono16, CV_16UC1},
    {V4L2_PIX_FMT_Y12, "y12", PixelLayout::kMono12, CV_16UC1},
    {V4L2_PIX_FMT_Y10, "y10", PixelLayout::kMono10, CV_16UC1},
    {V4L2_PIX_FMT_BGR24, "bgr24", PixelLayout::kBGR8, CV_8UC3},
    {V4L2_PIX_FMT_RGB24, "rgb24", PixelLayout::kRGB8, CV_8UC3},
    // V4L2 names Bayer orders like GenICam: by the first row's first two pixels.
    {V4L2_PIX_FMT_SRGGB8, "rggb", PixelLayout::kBayerRG8, CV_8UC1},
    {V4L2_PIX_FMT_SGRBG8, "grbg", PixelLayout::kBayerGR8, CV_8UC1},
    {V4L2_PIX_FMT_SBGGR8, "bggr", PixelLayout::kBayerBG8, CV_8UC1},
    {V4L2_PIX_FMT_SGBRG8, "gbrg", PixelLayout::kBayerGB8, CV_8UC1},
};

const FormatInfo* formatInfo(uint32_t fourcc) {
  for (const auto& f : kFormats) {
    if (f.fourcc == fourcc) return &f;
  }
  return nullptr;
}

int formatRank(uint32_t fourcc) {
  for (size_t i = 0; i < std::size(kFormats); ++i) {
    if (kFormats[i].fourcc == fourcc) return static_cast<int>(i);
  }
  return std::numeric_limits<int>::max();
}

std::string fourccName(uint32_t fourcc) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xFF);
    if (c != ' ') s += c;
  }
  return s;
}

// A fixed-size, maybe unterminated kernel string.
template <size_t N>
std::string kernelString(const uint8_t (&bytes)[N]) {
  const auto* chars = reinterpret_cast<const char*>(bytes);
  return std::string(chars, strnlen(chars, N));
}

// "Exposure Time, Absolute" -> "exposure_time_absolute", as v4l2-ctl names them.
std::string controlName(const std::string& label) {
  std::string name;
  for (char c : label) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!name.empty() && name.back() != '_') {
      name += '_';
    }
  }
  while (!name.empty() && name.back() == '_') name.pop_back();
  return name;
}

uint64_t monotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}

bool parseInt(const std::string& text, long long& out) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtoll(text.c_str(), &end, 10);
  return errno == 0 && end != nullptr && *end == '\0';
}

std::string range(const v4l2_queryctrl& c) {
  return "[" + std::to_string(c.minimum) + ", " + std::to_string(c.maximum) + "]";
}

// Errnos that mean the device is gone or broken, not that a request was wrong.
bool deviceLost(int err) { return err == ENODEV || err == EIO || err == ENXIO || err == EBADF; }

}  // namespace

Result<V4l2Options> parseV4l2Options(const std::string& text) {
  V4l2Options o;
  const size_t q = text.find('?');
  o.path = text.substr(0, q);
  if (o.path.empty())
    return makeError(SourceErrc::kBadConfig, "v4l2: needs a device, as in v4l2:/dev/video0");
  std::string query = q == std::string::npos ? "" : text.substr(q + 1);
  size_t pos = 0;
  while (pos < query.size()) {
    const size_t amp = std::min(query.find('&', pos), query.size());
    const std::string pair = query.substr(pos, amp - pos);
    pos = amp + 1;
    if (pair.empty()) continue;
    const size_t eq = pair.find('=');
    const std::string key = pair.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : pair.substr(eq + 1);
    long long n = 0;
    if (key == "width" || key == "height" || key == "buffers") {
      const bool buffers = key == "buffers";
      if (!parseInt(value, n) || n < (buffers ? 2 : 1) || n > (buffers ? 32 : 16384)) {
        return makeError(SourceErrc::kBadConfig, "v4l2: " + key + " must be " +
                                                     (buffers ? "2..32" : "1..16384") + ", got '" +
                                                     value + "'");
      }
      (key == "width" ? o.width : key == "height" ? o.height : o.buffers) = static_cast<int>(n);
    } else if (key == "fps") {
      char* end = nullptr;
      o.fps = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !(o.fps > 0 && o.fps <= 1000)) {
        return makeError(SourceErrc::kBadConfig,
                         "v4l2: fps must be in (0, 1000], got '" + value + "'");
      }
    } else if (key == "format") {
      std::string lower;
      for (char c : value) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (lower == "mjpg") lower = "mjpeg";
      if (lower == "gray" || lower == "mono8") lower = "grey";
      std::string known;
      for (const auto& f : kFormats) {
        if (lower == f.option) o.fourcc = f.fourcc;
        known += std::string(known.empty() ? "" : ", ") + f.option;
      }
      if (o.fourcc == 0) {
        return makeError(SourceErrc::kBadConfig,
                         "v4l2: unknown format '" + value + "' (known: " + known + ")");
      }
    } else {
      return makeError(
          SourceErrc::kBadConfig,
          "v4l2: unknown option '" + key + "' (known: width, height, format, fps, buffers)");
    }
  }
  if ((o.width == 0) != (o.height == 0)) {
    return makeError(SourceErrc::kBadConfig, "v4l2: width and height go together");
  }
  return o;
}

V4l2Source::V4l2Source(V4l2Options options, std::unique_ptr<V4l2Device> device)
    : options_(std::move(options)),
      device_(device ? std::move(device) : std::make_unique<LibV4l2Device>()) {}

V4l2Source::~V4l2Source() { close(); }

int V4l2Source::xioctl(unsigned long request, void* arg) {
  int r;
  do {
    r = device_->ioctl(fd_.get(), request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

Error V4l2Source::deviceError(const std::string& what, bool streaming) {
  const int err = errno;
  // While streaming every failure means reopening; before, a request the
  // device refuses (EINVAL) is a configuration it will always refuse.
  const bool lost = streaming || deviceLost(err) || err == EBUSY || err == ENOENT || err == EACCES;
  return makeError(lost ? SourceErrc::kUnavailable : SourceErrc::kBadConfig,
                   "v4l2:" + options_.path + ": " + what + ": " + std::strerror(err));
}

double V4l2Source::desiredFps() const {
  if (runtime_fps_) return *runtime_fps_;
  if (options_.fps > 0) return options_.fps;
  return camera_fps_.value_or(0);
}

Result<void> V4l2Source::open() {
  close();
  auto opened = openDevice();
  if (!opened) close();  // a half-opened device is released, so the retry starts clean
  return opened;
}

Result<void> V4l2Source::openDevice() {
  // Non-blocking, so DQBUF never waits: grab() waits in poll, with its timeout.
  const int fd = device_->open(options_.path, O_RDWR | O_NONBLOCK);
  if (fd < 0) return deviceError("cannot open");
  fd_ = V4l2Fd(*device_, fd);

  v4l2_capability cap{};
  if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) return deviceError("VIDIOC_QUERYCAP");
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
    // A UVC camera also registers a metadata node (often /dev/video1).
    return makeError(SourceErrc::kBadConfig, "v4l2:" + options_.path + " (" +
                                                 kernelString(cap.card) +
                                                 ") is not a streaming video capture device");
  }
  card_ = kernelString(cap.card);
  driver_ = kernelString(cap.driver);
  bus_ = kernelString(cap.bus_info);

  if (auto r = chooseFormat(); !r) return r;
  // A replugged device starts at its default rate.
  applied_fps_ = 0;
  if (auto r = applyFrameRate(desiredFps()); !r) return r;
  if (auto r = startStreaming(); !r) return r;
  trigger_pending_ = false;
  dropped_ = 0;
  return {};
}

Result<void> V4l2Source::chooseFormat() {
  v4l2_format current{};
  current.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_FMT, &current) < 0) return deviceError("VIDIOC_G_FMT");
  const bool size_given = options_.width > 0;
  const uint32_t want_w =
      size_given ? static_cast<uint32_t>(options_.width) : current.fmt.pix.width;
  const uint32_t want_h =
      size_given ? static_cast<uint32_t>(options_.height) : current.fmt.pix.height;

  struct Candidate {
    uint32_t fourcc;
    bool emulated;  // converted by libv4l2 in software
    uint32_t width, height;
    bool exact;
    double max_fps;  // 0 = unknown
  };
  std::vector<Candidate> candidates;
  formats_.clear();
  for (uint32_t i = 0;; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &desc) < 0) break;  // EINVAL ends the list
    formats_.push_back(fourccName(desc.pixelformat));
    if (!formatInfo(desc.pixelformat)) continue;
    if (options_.fourcc != 0 && desc.pixelformat != options_.fourcc) continue;

    // The offered size nearest the wanted one (by area, then shape).
    Candidate c{
        desc.pixelformat, (desc.flags & V4L2_FMT_FLAG_EMULATED) != 0, want_w, want_h, false, 0};
    double best = std::numeric_limits<double>::max();
    bool enumerated = false;
    for (uint32_t k = 0;; ++k) {
      v4l2_frmsizeenum size{};
      size.index = k;
      size.pixel_format = desc.pixelformat;
      if (xioctl(VIDIOC_ENUM_FRAMESIZES, &size) < 0) break;
      enumerated = true;
      if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        const auto w = size.discrete.width, h = size.discrete.height;
        const double d = std::abs(double(w) * h - double(want_w) * want_h) +
                         std::abs(double(w) - want_w) + std::abs(double(h) - want_h);
        if (d < best) {
          best = d;
          c.width = w;
          c.height = h;
        }
      } else {
        // Stepwise or continuous: one range, the driver rounds in S_FMT.
        const auto& sw = size.stepwise;
        c.width = std::clamp(want_w, sw.min_width, sw.max_width);
        c.height = std::clamp(want_h, sw.min_height, sw.max_height);
        best = (c.width == want_w && c.height == want_h) ? 0 : 1;
        break;
      }
    }
    c.exact = !enumerated || best == 0;  // a driver that lists no sizes takes what S_FMT gives
    // The fastest rate at that size, to prefer MJPEG when YUYV cannot keep up.
    v4l2_frmivalenum ival{};
    ival.pixel_format = desc.pixelformat;
    ival.width = c.width;
    ival.height = c.height;
    for (ival.index = 0; xioctl(VIDIOC_ENUM_FRAMEINTERVALS, &ival) == 0; ++ival.index) {
      const auto& f = ival.type == V4L2_FRMIVAL_TYPE_DISCRETE ? ival.discrete : ival.stepwise.min;
      if (f.numerator > 0) c.max_fps = std::max(c.max_fps, double(f.denominator) / f.numerator);
      if (ival.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;
    }
    candidates.push_back(c);
  }
  if (candidates.empty()) {
    std::string offered;
    for (const auto& f : formats_) offered += (offered.empty() ? "" : ", ") + f;
    return makeError(SourceErrc::kBadConfig,
                     "v4l2:" + options_.path + ": " +
                         (options_.fourcc ? "format " + fourccName(options_.fourcc) + " not offered"
                                          : std::string("no usable format")) +
                         " (device offers: " + (offered.empty() ? "none" : offered) + ")");
  }
  const double want_fps = desiredFps();
  // Exact size first, then the rate, then native over emulated, then our preference.
  auto key = [&](const Candidate& c) {
    const bool fast_enough = want_fps <= 0 || c.max_fps <= 0 || c.max_fps + 0.5 >= want_fps;
    return std::make_tuple(!c.exact, !fast_enough, c.emulated, formatRank(c.fourcc));
  };
  const Candidate& pick =
      *std::min_element(candidates.begin(), candidates.end(),
                        [&](const auto& a, const auto& b) { return key(a) < key(b); });

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = pick.width;
  fmt.fmt.pix.height = pick.height;
  fmt.fmt.pix.pixelformat = pick.fourcc;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(VIDIOC_S_FMT, &fmt) < 0) return deviceError("VIDIOC_S_FMT " + fourccName(pick.fourcc));
  // The driver may adjust everything: use what it set, never what we asked.
  const FormatInfo* info = formatInfo(fmt.fmt.pix.pixelformat);
  if (!info) {
    return makeError(SourceErrc::kBadConfig, "v4l2:" + options_.path + ": driver set format " +
                                                 fourccName(fmt.fmt.pix.pixelformat) +
                                                 ", which is not supported");
  }
  format_ = fmt.fmt.pix;
  layout_ = info->layout;
  if (info->cv_type >= 0) {
    const uint32_t row = format_.width * static_cast<uint32_t>(CV_ELEM_SIZE(info->cv_type));
    if (format_.bytesperline < row) format_.bytesperline = row;  // some drivers leave it 0
  }
  if (size_given && (format_.width != want_w || format_.height != want_h)) {
    logWarning("v4l2:", options_.path, ": ", want_w, "x", want_h, " not offered, using ",
               format_.width, "x", format_.height);
  }
  logInfo("v4l2:", options_.path, ": ", card_, ", ", fourccName(format_.pixelformat), " ",
          format_.width, "x", format_.height);
  return {};
}

Result<void> V4l2Source::queueBuffer(uint32_t index) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = index;
  if (xioctl(VIDIOC_QBUF, &buf) < 0) return deviceError("VIDIOC_QBUF");
  return {};
}

Result<void> V4l2Source::startStreaming() {
  if (buffers_.empty()) {
    v4l2_requestbuffers req{};
    req.count = static_cast<uint32_t>(options_.buffers);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_REQBUFS, &req) < 0) return deviceError("VIDIOC_REQBUFS");
    // The driver decides the count; with fewer than two, one buffer is
    // always being copied while the device has nowhere to write.
    if (req.count < 2) {
      return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": driver granted " +
                                                     std::to_string(req.count) +
                                                     " buffers, need 2");
    }
    for (uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      buf.index = i;
      if (xioctl(VIDIOC_QUERYBUF, &buf) < 0) return deviceError("VIDIOC_QUERYBUF");
      void* address =
          device_->mmap(buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_.get(), buf.m.offset);
      if (address == MAP_FAILED) return deviceError("mmap");
      buffers_.emplace_back(*device_, address, buf.length);
    }
  }
  for (uint32_t i = 0; i < buffers_.size(); ++i) {
    if (auto r = queueBuffer(i); !r) return r;
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_STREAMON, &type) < 0) return deviceError("VIDIOC_STREAMON");
  streaming_ = true;
  return {};
}

void V4l2Source::stopStreaming() {
  if (!streaming_) return;
  // STREAMOFF also takes every queued buffer back from the driver.
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  xioctl(VIDIOC_STREAMOFF, &type);
  streaming_ = false;
}

void V4l2Source::close() {
  if (!fd_) return;
  stopStreaming();
  const bool had_buffers = !buffers_.empty();
  buffers_.clear();  // munmap before freeing: REQBUFS(0) refuses mapped buffers
  if (had_buffers) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(VIDIOC_REQBUFS, &req);  // a gone device fails here; closing frees them anyway
  }
  fd_.reset();
}

SourceInfo V4l2Source::info() const {
  SourceInfo i;
  i.vendor = driver_;
  i.model = card_;
  i.serial = bus_;
  i.sensor_width = static_cast<int>(format_.width);
  i.sensor_height = static_cast<int>(format_.height);
  i.formats = formats_;
  return i;
}

Result<void> V4l2Source::applyFrameRate(double fps) {
  if (fps <= 0 || std::abs(fps - applied_fps_) < 1e-6) return {};
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_PARM, &parm) < 0 || !(parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    applied_fps_ = fps;  // the device has one rate; nothing to set, nothing to retry
    return {};
  }
  // Drivers refuse S_PARM while streaming (EBUSY): stop, set, restart.
  const bool was_streaming = streaming_;
  stopStreaming();
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator = static_cast<uint32_t>(std::lround(fps * 1000));
  const int set = xioctl(VIDIOC_S_PARM, &parm);
  const Error failed =
      set < 0 ? deviceError("VIDIOC_S_PARM " + std::to_string(fps) + " fps") : Error{};
  if (was_streaming) {
    if (auto r = startStreaming(); !r) return r;
  }
  if (set < 0) return failed;
  applied_fps_ = fps;
  const auto& t = parm.parm.capture.timeperframe;  // what the driver chose
  if (t.numerator > 0 && std::abs(double(t.denominator) / t.numerator - fps) > 0.5) {
    logInfo("v4l2:", options_.path, ": asked ", fps, " fps, device runs at ",
            double(t.denominator) / t.numerator);
  }
  return {};
}

Result<void> V4l2Source::configureAcquisition(AcquisitionMode mode, double fps) {
  trigger_mode_ = mode == AcquisitionMode::kTrigger;
  trigger_pending_ = false;
  // The URI's fps holds until the camera's rate changes at run time: the
  // first rate the camera passes is its configured default, not a request.
  if (camera_fps_ && std::abs(*camera_fps_ - fps) > 1e-6) runtime_fps_ = fps;
  camera_fps_ = fps;
  if (!fd_) return {};
  return applyFrameRate(desiredFps());
}

void V4l2Source::drainReadyBuffers() {
  for (size_t n = 0; n < buffers_.size(); ++n) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_DQBUF, &buf) < 0) return;  // EAGAIN: none waiting; errors show in grab()
    if (!queueBuffer(buf.index)) return;
  }
}

Result<void> V4l2Source::softwareTrigger() {
  if (!fd_) return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": not open");
  // The camera asks again after a grab timed out: the first trigger still
  // stands, and frames since then are its answer.
  if (trigger_pending_) return {};
  trigger_ns_ = monotonicNs();
  // With capture timestamps grab() skips the older frames by time; without,
  // the frames waiting now are the older ones. Draining would also throw
  // away a frame completed after the trigger, so it is only the fallback.
  if (!timestamps_monotonic_) drainReadyBuffers();
  trigger_pending_ = true;
  return {};
}

Result<SourceFrame> V4l2Source::grab(std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  if (!fd_ || !streaming_)
    return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": not open");
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    pollfd p{fd_.get(), POLLIN, 0};
    const int ready = device_->poll(&p, 1, static_cast<int>(std::max<int64_t>(0, left.count())));
    if (ready < 0) {
      if (errno == EINTR) continue;
      return deviceError("poll", true);
    }
    if (ready == 0) {
      return makeError(SourceErrc::kTimeout, "v4l2:" + options_.path + ": no frame within " +
                                                 std::to_string(timeout.count()) + " ms");
    }
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_DQBUF, &buf) < 0) {
      // EAGAIN after a readable poll: another wakeup raced us, or (POLLERR)
      // the device is in error and DQBUF has nothing to say.
      if (errno == EAGAIN && !(p.revents & POLLERR)) continue;
      if (errno == EAGAIN) errno = EIO;
      return deviceError("VIDIOC_DQBUF", true);
    }
    if (buf.index >= buffers_.size()) {
      errno = EIO;
      return deviceError("VIDIOC_DQBUF returned buffer " + std::to_string(buf.index), true);
    }
    const V4l2Mapping& mapping = buffers_[buf.index];
    timestamps_monotonic_ =
        (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    const uint64_t device_ns = timestamps_monotonic_
                                   ? static_cast<uint64_t>(buf.timestamp.tv_sec) * 1000000000ull +
                                         static_cast<uint64_t>(buf.timestamp.tv_usec) * 1000ull
                                   : 0;
    const size_t used = std::min<size_t>(buf.bytesused, mapping.length());
    const FormatInfo* info = formatInfo(format_.pixelformat);
    cv::Mat image;
    const bool before_trigger = trigger_pending_ && device_ns != 0 && device_ns < trigger_ns_;
    bool usable =
        !(buf.flags & V4L2_BUF_FLAG_ERROR) && !before_trigger;  // error flag: a corrupted transfer
    if (usable && info->cv_type < 0) {
      usable = used > 0;
      if (usable)
        image = cv::Mat(1, static_cast<int>(used), CV_8UC1, const_cast<uint8_t*>(mapping.data()))
                    .clone();
    } else if (usable) {
      const size_t needed = size_t{format_.bytesperline} * format_.height;
      // bytesused 0 from an old driver means a full buffer.
      usable = (used == 0 ? mapping.length() : used) >= needed && mapping.length() >= needed;
      if (usable) {
        image = cv::Mat(static_cast<int>(format_.height), static_cast<int>(format_.width),
                        info->cv_type, const_cast<uint8_t*>(mapping.data()), format_.bytesperline)
                    .clone();
      }
    }
    // Back to the driver at once: it owns few buffers and drops frames without them.
    if (!queueBuffer(buf.index)) return deviceError("VIDIOC_QBUF", true);
    if (!usable) {
      if (!before_trigger) ++dropped_;
      continue;
    }
    trigger_pending_ = false;
    SourceFrame frame;
    frame.image = std::move(image);
    frame.layout = layout_;
    frame.device_timestamp_ns = device_ns;
    return frame;
  }
}

// --- Controls

std::vector<v4l2_queryctrl> V4l2Source::queryControls() {
  std::vector<v4l2_queryctrl> controls;
  auto keep = [&](const v4l2_queryctrl& q) {
    if (q.flags & V4L2_CTRL_FLAG_DISABLED) return;
    switch (q.type) {
      // Types G_CTRL/S_CTRL carry; 64-bit, string and compound controls need
      // the extended API and no webcam exposes its exposure or gain that way.
      case V4L2_CTRL_TYPE_INTEGER:
      case V4L2_CTRL_TYPE_BOOLEAN:
      case V4L2_CTRL_TYPE_MENU:
      case V4L2_CTRL_TYPE_INTEGER_MENU:
      case V4L2_CTRL_TYPE_BUTTON:
        controls.push_back(q);
        break;
      default:
        break;
    }
  };
  v4l2_queryctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  bool enumerates = false;
  while (xioctl(VIDIOC_QUERYCTRL, &q) == 0) {
    enumerates = true;
    keep(q);
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  if (!enumerates) {
    // Drivers older than the NEXT_CTRL flag: ask for the user-class ids one by one.
    for (uint32_t id = V4L2_CID_BASE; id < V4L2_CID_LASTP1; ++id) {
      v4l2_queryctrl one{};
      one.id = id;
      if (xioctl(VIDIOC_QUERYCTRL, &one) == 0) keep(one);
    }
  }
  return controls;
}

std::optional<v4l2_queryctrl> V4l2Source::findControl(const std::string& name) {
  for (const auto& q : queryControls()) {
    if (controlName(kernelString(q.name)) == name) return q;
  }
  return std::nullopt;
}

std::vector<std::pair<int32_t, std::string>> V4l2Source::menuChoices(const v4l2_queryctrl& q) {
  std::vector<std::pair<int32_t, std::string>> menu;
  for (int32_t i = q.minimum; i <= q.maximum; ++i) {
    v4l2_querymenu m{};
    m.id = q.id;
    m.index = static_cast<uint32_t>(i);
    if (xioctl(VIDIOC_QUERYMENU, &m) < 0) continue;  // a hole in the menu
    menu.emplace_back(
        i, q.type == V4L2_CTRL_TYPE_MENU ? kernelString(m.name) : std::to_string(m.value));
  }
  return menu;
}

Result<Feature> V4l2Source::describeControl(const v4l2_queryctrl& q) {
  Feature f;
  f.name = controlName(kernelString(q.name));
  f.description = kernelString(q.name);
  if (q.flags & V4L2_CTRL_FLAG_INACTIVE) f.description += " (inactive: set by an automatic mode)";
  f.writable = !(q.flags & V4L2_CTRL_FLAG_READ_ONLY);
  if (q.id == V4L2_CID_EXPOSURE_ABSOLUTE) f.unit = "100us";

  int32_t value = 0;
  if (q.type != V4L2_CTRL_TYPE_BUTTON && !(q.flags & V4L2_CTRL_FLAG_WRITE_ONLY)) {
    v4l2_control c{};
    c.id = q.id;
    if (xioctl(VIDIOC_G_CTRL, &c) < 0) return deviceError("VIDIOC_G_CTRL " + f.name);
    value = c.value;
  }
  switch (q.type) {
    case V4L2_CTRL_TYPE_INTEGER:
      f.type = FeatureType::kInteger;
      f.value = std::to_string(value);
      f.has_range = true;
      f.min = q.minimum;
      f.max = q.maximum;
      f.increment = q.step > 1 ? q.step : 0;
      break;
    case V4L2_CTRL_TYPE_BOOLEAN:
      f.type = FeatureType::kBoolean;
      f.value = value ? "true" : "false";
      break;
    case V4L2_CTRL_TYPE_BUTTON:
      f.type = FeatureType::kCommand;
      break;
    default: {  // menus: choices by name (integer menus by value), gaps skipped
      f.type = FeatureType::kEnumeration;
      for (const auto& [index, choice] : menuChoices(q)) {
        f.choices.push_back(choice);
        if (index == value) f.value = choice;
      }
      break;
    }
  }
  return f;
}

std::vector<Feature> V4l2Source::features() {
  std::vector<Feature> out;
  if (!fd_) return out;
  for (const auto& q : queryControls()) {
    if (auto f = describeControl(q)) out.push_back(std::move(*f));
  }
  return out;
}

Result<Feature> V4l2Source::feature(const std::string& name) {
  if (!fd_) return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": not open");
  const auto q = findControl(name);
  if (!q)
    return makeError(SourceErrc::kUnknownFeature,
                     "unknown feature '" + name + "' (not a control of " + card_ + ")");
  return describeControl(*q);
}

Result<void> V4l2Source::setFeature(const std::string& name, const std::string& text) {
  if (!fd_) return makeError(SourceErrc::kUnavailable, "v4l2:" + options_.path + ": not open");
  const auto found = findControl(name);
  if (!found)
    return makeError(SourceErrc::kUnknownFeature,
                     "unknown feature '" + name + "' (not a control of " + card_ + ")");
  const v4l2_queryctrl& q = *found;
  if (q.flags & V4L2_CTRL_FLAG_READ_ONLY)
    return makeError(SourceErrc::kBadValue, "feature '" + name + "' is read-only");

  long long value = 0;
  switch (q.type) {
    case V4L2_CTRL_TYPE_BUTTON:
      value = 1;  // pressing it; the text does not matter
      break;
    case V4L2_CTRL_TYPE_BOOLEAN:
      if (text == "true" || text == "1" || text == "on") {
        value = 1;
      } else if (text == "false" || text == "0" || text == "off") {
        value = 0;
      } else {
        return makeError(SourceErrc::kBadValue,
                         "feature '" + name + "' is a boolean (true/false), got '" + text + "'");
      }
      break;
    case V4L2_CTRL_TYPE_INTEGER:
      if (!parseInt(text, value)) {
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' is an integer " + range(q) +
                                                    ", got '" + text + "'");
      }
      if (value < q.minimum || value > q.maximum) {
        return makeError(SourceErrc::kBadValue,
                         "feature '" + name + "' value " + text + " out of range " + range(q));
      }
      if (q.step > 1 && (value - q.minimum) % q.step != 0) {
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' value " + text +
                                                    " is not " + std::to_string(q.minimum) +
                                                    " plus a multiple of " +
                                                    std::to_string(q.step) + " in " + range(q));
      }
      break;
    default: {  // menus: a choice by its name, or by its index
      const auto menu = menuChoices(q);
      bool matched = false;
      for (const auto& [index, choice] : menu) {
        if (!matched &&
            (strcasecmp(choice.c_str(), text.c_str()) == 0 || text == std::to_string(index))) {
          value = index;
          matched = true;
        }
      }
      if (!matched) {
        std::string choices;
        for (const auto& c : menu) choices += (choices.empty() ? "" : ", ") + c.second;
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' has no choice '" + text +
                                                    "' (choices: " + choices + ")");
      }
      break;
    }
  }
  v4l2_control c{};
  c.id = q.id;
  c.value = static_cast<int32_t>(value);
  if (xioctl(VIDIOC_S_CTRL, &c) < 0) {
    const int err = errno;
    if (err == ERANGE || err == EINVAL) {
      return makeError(SourceErrc::kBadValue,
                       "feature '" + name + "' refused " + text + " (range " + range(q) + ")");
    }
    if (err == EACCES || err == EBUSY) {
      return makeError(SourceErrc::kBadValue,
                       "feature '" + name + "' cannot be set now: " + std::strerror(err) +
                           " (inactive under an automatic mode, e.g. exposure needs "
                           "auto_exposure on manual)");
    }
    errno = err;
    return deviceError("VIDIOC_S_CTRL " + name);
  }
  return {};
}

}  // namespace picksight::video
