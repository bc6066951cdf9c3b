// V4L2 format negotiation: the pixel format and frame size to stream, from
// what the device offers, what the source string asks and the rate wanted.
#include "v4l2_source.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <tuple>

#include "picksight/common/log.hpp"
#include "v4l2_formats.hpp"

namespace picksight::video {

namespace {
// One pixel format the device offers, at the size it would stream.
struct Candidate {
  uint32_t fourcc;
  bool emulated;  // converted by libv4l2 in software
  uint32_t width, height;
  bool exact;
  double max_fps;  // 0 = unknown
};

using Ioctl = std::function<int(unsigned long, void*)>;

// The size of `c.fourcc` the device offers nearest the wanted one (by
// area, then shape), and whether it is the wanted one.
void sizeNearest(const Ioctl& ioctl, uint32_t want_w, uint32_t want_h, Candidate& c) {
  double best = std::numeric_limits<double>::max();
  bool enumerated = false;
  for (uint32_t k = 0;; ++k) {
    v4l2_frmsizeenum size{};
    size.index = k;
    size.pixel_format = c.fourcc;
    if (ioctl(VIDIOC_ENUM_FRAMESIZES, &size) < 0) break;
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
}

// The fastest rate of `c` at its size (0: unknown), to prefer MJPEG when
// YUYV cannot keep up.
double fastestRate(const Ioctl& ioctl, const Candidate& c) {
  double max_fps = 0;
  v4l2_frmivalenum ival{};
  ival.pixel_format = c.fourcc;
  ival.width = c.width;
  ival.height = c.height;
  for (ival.index = 0; ioctl(VIDIOC_ENUM_FRAMEINTERVALS, &ival) == 0; ++ival.index) {
    const auto& f = ival.type == V4L2_FRMIVAL_TYPE_DISCRETE ? ival.discrete : ival.stepwise.min;
    if (f.numerator > 0) max_fps = std::max(max_fps, double(f.denominator) / f.numerator);
    if (ival.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;
  }
  return max_fps;
}
}  // namespace

Result<void> V4l2Source::chooseFormat() {
  v4l2_format current{};
  current.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_FMT, &current) < 0) return deviceError("VIDIOC_G_FMT");
  const bool size_given = options_.width > 0;
  const uint32_t want_w =
      size_given ? static_cast<uint32_t>(options_.width) : current.fmt.pix.width;
  const uint32_t want_h =
      size_given ? static_cast<uint32_t>(options_.height) : current.fmt.pix.height;

  const Ioctl ioctl = [this](unsigned long request, void* arg) { return xioctl(request, arg); };
  std::vector<Candidate> candidates;
  formats_.clear();
  for (uint32_t i = 0;; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &desc) < 0) break;  // EINVAL ends the list
    formats_.push_back(fourccName(desc.pixelformat));
    if (!findPixelFormat(desc.pixelformat)) continue;
    if (options_.fourcc != 0 && desc.pixelformat != options_.fourcc) continue;

    Candidate c{
        desc.pixelformat, (desc.flags & V4L2_FMT_FLAG_EMULATED) != 0, want_w, want_h, false, 0};
    sizeNearest(ioctl, want_w, want_h, c);
    c.max_fps = fastestRate(ioctl, c);
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
    return std::make_tuple(!c.exact, !fast_enough, c.emulated, pixelFormatRank(c.fourcc));
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
  const V4l2PixelFormat* info = findPixelFormat(fmt.fmt.pix.pixelformat);
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

}  // namespace picksight::video
