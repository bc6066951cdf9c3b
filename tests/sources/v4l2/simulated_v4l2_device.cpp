// Simulated V4L2 webcam for the V4L2 driver tests.
#include "simulated_v4l2_device.hpp"

#include <fcntl.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <thread>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"

namespace picksight::video::testing {
namespace {

constexpr int kFd = 42;
constexpr uint32_t kOffsetStride = 0x100000;  // mmap cookie of buffer i: i * stride

v4l2_queryctrl makeControl(uint32_t id, uint32_t type, const char* name, int32_t min, int32_t max,
                           int32_t step, int32_t def, uint32_t flags = 0) {
  v4l2_queryctrl q{};
  q.id = id;
  q.type = type;
  std::strncpy(reinterpret_cast<char*>(q.name), name, sizeof(q.name));
  q.minimum = min;
  q.maximum = max;
  q.step = step;
  q.default_value = def;
  q.flags = flags;
  return q;
}

int fail(int err) {
  errno = err;
  return -1;
}

}  // namespace

SimulatedV4l2Device::SimulatedV4l2Device() {
  // Like a USB 2 webcam: YUYV only reaches 10 fps at 720p, MJPEG 30.
  formats_ = {
      {V4L2_PIX_FMT_YUYV, {{640, 480}, {1280, 720}}, {{30, 15}, {10, 5}}},
      {V4L2_PIX_FMT_MJPEG, {{640, 480}, {1280, 720}}, {{30}, {30, 15}}},
  };
  // Sorted by id, as NEXT_CTRL enumeration walks them; class markers,
  // a disabled and a 64-bit control are there to be skipped.
  controls_ = {
      {makeControl(V4L2_CID_USER_CLASS, V4L2_CTRL_TYPE_CTRL_CLASS, "User Controls", 0, 0, 0, 0),
       0,
       {}},
      {makeControl(V4L2_CID_BRIGHTNESS, V4L2_CTRL_TYPE_INTEGER, "Brightness", -64, 64, 1, 0),
       0,
       {}},
      {makeControl(V4L2_CID_CONTRAST, V4L2_CTRL_TYPE_INTEGER, "Contrast", 0, 100, 10, 50), 50, {}},
      {makeControl(V4L2_CID_AUTO_WHITE_BALANCE, V4L2_CTRL_TYPE_BOOLEAN, "White Balance, Automatic",
                   0, 1, 1, 1),
       1,
       {}},
      {makeControl(V4L2_CID_GAIN, V4L2_CTRL_TYPE_INTEGER, "Gain", 0, 255, 1, 32), 32, {}},
      {makeControl(V4L2_CID_HUE, V4L2_CTRL_TYPE_INTEGER, "Hue", 0, 10, 1, 0,
                   V4L2_CTRL_FLAG_DISABLED),
       0,
       {}},
      {makeControl(V4L2_CID_CAMERA_CLASS, V4L2_CTRL_TYPE_CTRL_CLASS, "Camera Controls", 0, 0, 0, 0),
       0,
       {}},
      // UVC's menu has holes: 0 (auto) and 2 (shutter priority) are not offered.
      {makeControl(V4L2_CID_EXPOSURE_AUTO, V4L2_CTRL_TYPE_MENU, "Auto Exposure", 0, 3, 1, 3),
       3,
       {{1, "Manual Mode"}, {3, "Aperture Priority Mode"}}},
      {makeControl(V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CTRL_TYPE_INTEGER, "Exposure Time, Absolute", 3,
                   2047, 1, 250),
       250,
       {}},
      {makeControl(V4L2_CID_PIXEL_RATE, V4L2_CTRL_TYPE_INTEGER64, "Pixel Rate", 0, 0, 1, 0,
                   V4L2_CTRL_FLAG_READ_ONLY),
       0,
       {}},
  };
  pix_.pixelformat = V4L2_PIX_FMT_YUYV;
  pix_.width = 640;
  pix_.height = 480;
  setFormat(pix_);
}

const SimulatedV4l2Device::Format* SimulatedV4l2Device::format(uint32_t fourcc) const {
  for (const auto& f : formats_) {
    if (f.fourcc == fourcc) return &f;
  }
  return nullptr;
}

SimulatedV4l2Device::Control* SimulatedV4l2Device::control(uint32_t id) {
  for (auto& c : controls_) {
    if (c.query.id == id) return &c;
  }
  return nullptr;
}

void SimulatedV4l2Device::setFormat(v4l2_pix_format& pix) {
  const Format* f = format(pix.pixelformat);
  if (!f) f = &formats_[0];  // drivers substitute a format they have
  size_t best = 0;
  double best_d = 1e18;
  for (size_t i = 0; i < f->sizes.size(); ++i) {
    const double d = std::abs(double(f->sizes[i].first) - pix.width) +
                     std::abs(double(f->sizes[i].second) - pix.height);
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  pix = v4l2_pix_format{};
  pix.pixelformat = f->fourcc;
  pix.width = f->sizes[best].first;
  pix.height = f->sizes[best].second;
  pix.field = V4L2_FIELD_NONE;
  pix.bytesperline = f->fourcc == V4L2_PIX_FMT_YUYV ? pix.width * 2 : 0;
  pix.sizeimage = pix.width * pix.height * 2;
  pix.colorspace = V4L2_COLORSPACE_SRGB;
  pix_ = pix;
  // The rate nearest the current one that this size offers.
  const auto& rates = f->rates[best];
  fps_ = *std::min_element(rates.begin(), rates.end(), [&](double a, double b) {
    return std::abs(a - fps_) < std::abs(b - fps_);
  });
}

int SimulatedV4l2Device::open(const std::string& path, int /*flags*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (gone_ || path != kPath) return fail(ENOENT);
  if (open_fds_ > 0) return fail(EBUSY);  // one client, like a webcam that is streaming elsewhere
  ++open_fds_;
  return kFd;
}

int SimulatedV4l2Device::close(int fd) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (fd != kFd || open_fds_ == 0) return fail(EBADF);
  --open_fds_;
  streaming_ = false;
  queued_.clear();
  done_.clear();
  if (mapped_ == 0) buffers_.clear();  // the kernel frees them with the last reference
  return 0;
}

void* SimulatedV4l2Device::mmap(size_t length, int /*prot*/, int /*flags*/, int fd, off_t offset) {
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t index = static_cast<size_t>(offset) / kOffsetStride;
  if (fd != kFd || index >= buffers_.size() || length != buffers_[index].bytes.size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++mapped_;
  return buffers_[index].bytes.data();
}

int SimulatedV4l2Device::munmap(void* address, size_t /*length*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& b : buffers_) {
    if (b.bytes.data() == address) {
      --mapped_;
      return 0;
    }
  }
  return fail(EINVAL);
}

int SimulatedV4l2Device::poll(pollfd* fds, nfds_t count, int timeout_ms) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (count != 1 || fds[0].fd != kFd) return fail(EINVAL);
    fds[0].revents = 0;
    if (poll_eintr_ > 0) {
      --poll_eintr_;
      return fail(EINTR);
    }
    if (gone_) {
      if (poll_fails_) return fail(ENODEV);
      fds[0].revents = POLLERR;
      return 1;
    }
    if (!streaming_) {
      fds[0].revents = POLLERR;  // vb2: polling a queue that is not streaming
      return 1;
    }
    if (!done_.empty() || (!queued_.empty() && !paused_) || dqbuf_eagain_ > 0) {
      fds[0].revents = POLLIN;
      return 1;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
  return 0;
}

void SimulatedV4l2Device::fill(uint32_t index) {
  // A lost frame still takes its number, as a driver's sequence counts it.
  frames_ += static_cast<uint64_t>(lost_frames_);
  lost_frames_ = 0;
  const uint64_t n = frames_++;
  Buffer& b = buffers_[index];
  const uint8_t y = level(n);
  size_t used = 0;
  if (pix_.pixelformat == V4L2_PIX_FMT_YUYV) {
    for (uint32_t row = 0; row < pix_.height; ++row) {
      uint8_t* p = b.bytes.data() + size_t{row} * pix_.bytesperline;
      for (uint32_t x = 0; x < pix_.width; x += 2, p += 4) {
        p[0] = y;
        p[1] = 128;
        p[2] = y;
        p[3] = 128;
      }
    }
    used = size_t{pix_.bytesperline} * pix_.height;
  } else {
    std::vector<uint8_t> jpeg;
    picksight::codecs::imencode(".jpg",
                                cv::Mat(static_cast<int>(pix_.height), static_cast<int>(pix_.width),
                                        CV_8UC3, cv::Scalar(y, y, y)),
                                jpeg);
    std::copy(jpeg.begin(), jpeg.end(), b.bytes.begin());
    used = jpeg.size();
  }
  b.done = v4l2_buffer{};
  b.done.index = index;
  b.done.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.done.memory = V4L2_MEMORY_MMAP;
  b.done.bytesused = static_cast<uint32_t>(used);
  b.done.length = static_cast<uint32_t>(b.bytes.size());
  b.done.sequence = static_cast<uint32_t>(n);
  b.done.flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_DONE;
  if (error_frames_ > 0) {
    --error_frames_;
    b.done.flags |= V4L2_BUF_FLAG_ERROR;
  }
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  b.done.timestamp.tv_sec = ts.tv_sec;
  b.done.timestamp.tv_usec = ts.tv_nsec / 1000;
  done_.push_back(index);
}

int SimulatedV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (ioctl_eintr_ > 0) {
    --ioctl_eintr_;
    return fail(EINTR);
  }
  if (fd != kFd || open_fds_ == 0) return fail(EBADF);
  if (gone_) return fail(ENODEV);
  return doIoctl(request, arg);
}

int SimulatedV4l2Device::doIoctl(unsigned long request, void* arg) {
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(arg);
      *cap = v4l2_capability{};
      std::strncpy(reinterpret_cast<char*>(cap->driver), "uvcvideo", sizeof(cap->driver));
      std::strncpy(reinterpret_cast<char*>(cap->card), "Simulated Webcam", sizeof(cap->card));
      std::strncpy(reinterpret_cast<char*>(cap->bus_info), "usb-sim-1", sizeof(cap->bus_info));
      cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
      cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto* d = static_cast<v4l2_fmtdesc*>(arg);
      if (d->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || d->index >= formats_.size())
        return fail(EINVAL);
      d->pixelformat = formats_[d->index].fourcc;
      d->flags = d->pixelformat == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
      return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* s = static_cast<v4l2_frmsizeenum*>(arg);
      const Format* f = format(s->pixel_format);
      if (!f || s->index >= f->sizes.size()) return fail(EINVAL);
      s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
      s->discrete.width = f->sizes[s->index].first;
      s->discrete.height = f->sizes[s->index].second;
      return 0;
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
      auto* iv = static_cast<v4l2_frmivalenum*>(arg);
      const Format* f = format(iv->pixel_format);
      if (!f) return fail(EINVAL);
      for (size_t i = 0; i < f->sizes.size(); ++i) {
        if (f->sizes[i].first == iv->width && f->sizes[i].second == iv->height) {
          if (iv->index >= f->rates[i].size()) return fail(EINVAL);
          iv->type = V4L2_FRMIVAL_TYPE_DISCRETE;
          iv->discrete.numerator = 1;
          iv->discrete.denominator = static_cast<uint32_t>(f->rates[i][iv->index]);
          return 0;
        }
      }
      return fail(EINVAL);
    }
    case VIDIOC_G_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      f->fmt.pix = pix_;
      return 0;
    }
    case VIDIOC_S_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (!buffers_.empty()) return fail(EBUSY);
      setFormat(f->fmt.pix);
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto* p = static_cast<v4l2_streamparm*>(arg);
      if (p->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_PARM) {
        if (streaming_) return fail(EBUSY);
        const auto& t = p->parm.capture.timeperframe;
        if (t.numerator == 0 || t.denominator == 0) return fail(EINVAL);
        const double want = double(t.denominator) / t.numerator;
        const Format* f = format(pix_.pixelformat);
        for (size_t i = 0; i < f->sizes.size(); ++i) {
          if (f->sizes[i].first != pix_.width || f->sizes[i].second != pix_.height) continue;
          const auto& rates = f->rates[i];
          fps_ = *std::min_element(rates.begin(), rates.end(), [&](double a, double b) {
            return std::abs(a - want) < std::abs(b - want);
          });
        }
      }
      p->parm.capture = v4l2_captureparm{};
      p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      p->parm.capture.timeperframe.numerator = 1000;
      p->parm.capture.timeperframe.denominator = static_cast<uint32_t>(std::lround(fps_ * 1000));
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || r->memory != V4L2_MEMORY_MMAP)
        return fail(EINVAL);
      if (streaming_ || mapped_ > 0) return fail(EBUSY);
      buffers_.clear();
      queued_.clear();
      done_.clear();
      r->count = std::min(r->count, granted_);
      for (uint32_t i = 0; i < r->count; ++i)
        buffers_.push_back(Buffer{std::vector<uint8_t>(pix_.sizeimage), {}});
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= buffers_.size()) return fail(EINVAL);
      b->length = static_cast<uint32_t>(buffers_[b->index].bytes.size());
      b->m.offset = b->index * kOffsetStride;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      const uint32_t i = b->index;
      if (i >= buffers_.size() || b->memory != V4L2_MEMORY_MMAP ||
          std::count(queued_.begin(), queued_.end(), i) ||
          std::count(done_.begin(), done_.end(), i)) {
        return fail(EINVAL);
      }
      queued_.push_back(i);
      return 0;
    }
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (!streaming_) return fail(EINVAL);
      if (dqbuf_eagain_ > 0) {
        --dqbuf_eagain_;
        return fail(EAGAIN);
      }
      if (done_.empty()) {
        if (queued_.empty() || paused_) return fail(EAGAIN);
        const uint32_t i = queued_.front();
        queued_.pop_front();
        fill(i);
      }
      const uint32_t i = done_.front();
      done_.pop_front();
      *b = buffers_[i].done;
      return 0;
    }
    case VIDIOC_STREAMON:
      if (buffers_.empty()) return fail(EINVAL);
      streaming_ = true;
      ++streamons_;
      return 0;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      queued_.clear();
      done_.clear();
      return 0;
    case VIDIOC_QUERYCTRL: {
      auto* q = static_cast<v4l2_queryctrl*>(arg);
      const bool next = (q->id & V4L2_CTRL_FLAG_NEXT_CTRL) != 0;
      const uint32_t id = q->id & ~(V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND);
      for (const auto& c : controls_) {
        if (next ? c.query.id > id : c.query.id == id) {
          *q = c.query;
          if (c.query.id == V4L2_CID_EXPOSURE_ABSOLUTE &&
              control(V4L2_CID_EXPOSURE_AUTO)->value != 1) {
            q->flags |= V4L2_CTRL_FLAG_INACTIVE;
          }
          return 0;
        }
      }
      return fail(EINVAL);
    }
    case VIDIOC_QUERYMENU: {
      auto* m = static_cast<v4l2_querymenu*>(arg);
      Control* c = control(m->id);
      if (!c) return fail(EINVAL);
      for (const auto& [index, name] : c->menu) {
        if (index == m->index) {
          std::strncpy(reinterpret_cast<char*>(m->name), name.c_str(), sizeof(m->name));
          return 0;
        }
      }
      return fail(EINVAL);
    }
    case VIDIOC_G_CTRL:
    case VIDIOC_S_CTRL: {
      auto* v = static_cast<v4l2_control*>(arg);
      Control* c = control(v->id);
      if (!c || c->query.type == V4L2_CTRL_TYPE_CTRL_CLASS ||
          (c->query.flags & V4L2_CTRL_FLAG_DISABLED)) {
        return fail(EINVAL);
      }
      if (request == VIDIOC_G_CTRL) {
        v->value = c->value;
        return 0;
      }
      if (v->value < c->query.minimum || v->value > c->query.maximum) return fail(ERANGE);
      if (v->id == V4L2_CID_EXPOSURE_ABSOLUTE && control(V4L2_CID_EXPOSURE_AUTO)->value != 1)
        return fail(EACCES);
      c->value = v->value;
      return 0;
    }
    default:
      return fail(ENOTTY);
  }
}

void SimulatedV4l2Device::setGrantedBuffers(uint32_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  granted_ = n;
}
void SimulatedV4l2Device::injectIoctlEintr(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  ioctl_eintr_ = n;
}
void SimulatedV4l2Device::injectPollEintr(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  poll_eintr_ = n;
}
void SimulatedV4l2Device::injectDqbufEagain(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  dqbuf_eagain_ = n;
}
void SimulatedV4l2Device::injectErrorFrames(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  error_frames_ = n;
}
std::string SimulatedV4l2Device::serialNumber(const std::string& path) {
  std::lock_guard<std::mutex> lock(mutex_);
  return path == kPath ? serial_ : std::string();
}
void SimulatedV4l2Device::setSerial(const std::string& serial) {
  std::lock_guard<std::mutex> lock(mutex_);
  serial_ = serial;
}
void SimulatedV4l2Device::injectLostFrames(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  lost_frames_ = n;
}
void SimulatedV4l2Device::setPaused(bool paused) {
  std::lock_guard<std::mutex> lock(mutex_);
  paused_ = paused;
}
void SimulatedV4l2Device::unplug(bool poll_fails) {
  std::lock_guard<std::mutex> lock(mutex_);
  gone_ = true;
  poll_fails_ = poll_fails;
}
void SimulatedV4l2Device::replug() {
  std::lock_guard<std::mutex> lock(mutex_);
  gone_ = false;
}
void SimulatedV4l2Device::captureNow(int n) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (int k = 0; k < n && !queued_.empty(); ++k) {
    const uint32_t i = queued_.front();
    queued_.pop_front();
    fill(i);
  }
}

SimulatedV4l2Device::State SimulatedV4l2Device::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  State s;
  s.open_fds = open_fds_;
  s.mapped = mapped_;
  s.buffers = static_cast<uint32_t>(buffers_.size());
  s.streaming = streaming_;
  s.streamons = streamons_;
  s.pixelformat = pix_.pixelformat;
  s.width = pix_.width;
  s.height = pix_.height;
  s.fps = fps_;
  s.frames = frames_;
  return s;
}

int32_t SimulatedV4l2Device::controlValue(uint32_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& c : controls_) {
    if (c.query.id == id) return c.value;
  }
  return 0;
}

}  // namespace picksight::video::testing
