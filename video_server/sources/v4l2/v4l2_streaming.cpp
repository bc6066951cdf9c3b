// V4L2 mmap streaming: buffers requested, mapped and queued, frames copied
// out of them, and the software trigger's frame selection.
#include "v4l2_source.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <chrono>

#include "picksight/common/clock.hpp"
#include "v4l2_formats.hpp"

namespace picksight::video {

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
  last_device_sequence_.reset();  // the driver numbers from 0 again
  skip_left_ = options_.skip;
  return {};
}

void V4l2Source::stopStreaming() {
  if (!streaming_) return;
  // STREAMOFF also takes every queued buffer back from the driver.
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  xioctl(VIDIOC_STREAMOFF, &type);
  streaming_ = false;
}

void V4l2Source::countSequence(uint32_t sequence) {
  // The driver numbers every frame it captured, delivered or not: a jump is
  // frames it lost (no free buffer, a USB hiccup). Wraps at 2^32.
  if (last_device_sequence_) {
    const uint32_t step = sequence - *last_device_sequence_;
    if (step > 1 && step < (1u << 31)) counters_.sequence_gaps += step - 1;
  }
  last_device_sequence_ = sequence;
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

uint64_t V4l2Source::frameIntervalNs() const {
  // The rate set on the device; a webcam that never told runs at 30 fps or less.
  const double fps = applied_fps_ > 0 ? applied_fps_ : 30.0;
  return static_cast<uint64_t>(1e9 / fps);
}

Result<void> V4l2Source::softwareTrigger() {
  if (!fd_) return notOpen();
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
  if (!fd_ || !streaming_) return notOpen();
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
    countSequence(buf.sequence);
    const V4l2Mapping& mapping = buffers_[buf.index];
    timestamps_monotonic_ =
        (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    const uint64_t device_ns = timestamps_monotonic_
                                   ? static_cast<uint64_t>(buf.timestamp.tv_sec) * 1000000000ull +
                                         static_cast<uint64_t>(buf.timestamp.tv_usec) * 1000ull
                                   : 0;
    const size_t used = std::min<size_t>(buf.bytesused, mapping.length());
    const V4l2PixelFormat* info = findPixelFormat(format_.pixelformat);
    cv::Mat image;
    // The timestamp marks the frame's first USB packet, after its exposure:
    // a frame stamped less than one frame interval after the trigger may
    // have been exposed partly before it.
    const bool before_trigger =
        trigger_pending_ && device_ns != 0 && device_ns < trigger_ns_ + frameIntervalNs();
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
      if (!before_trigger) {
        ++dropped_;
        ++counters_.incomplete_buffers;
      }
      continue;
    }
    if (skip_left_ > 0) {
      // Taken before the camera's automatic exposure settled.
      --skip_left_;
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

}  // namespace picksight::video
