// Colour axes: projection of a colour frame on the axis between a part's
// colour and its surface's, and the axis of a part taught in a rectangle.
#include "picksight/vision/segmentation/colour_axis.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace picksight::vision {
namespace {
// Two colours closer than this (BGR distance) are one, whatever the noise.
constexpr double kMinColourDistance = 20;
// ... or closer than this many times the rim's own spread (its texture and
// noise).
constexpr double kMinDistanceOverSpread = 3;
// Colour axes whose ends are this close (BGR distance) project alike.
constexpr double kSameAxis = 6;
// A rectangle narrower than this holds no part with a rim around it.
constexpr int kMinSide = 8;

double luma(const cv::Vec3d& bgr) { return 0.114 * bgr[0] + 0.587 * bgr[1] + 0.299 * bgr[2]; }

// The per-channel median of `pixels` (BGR).
cv::Vec3d medianColour(std::vector<cv::Vec3b>& pixels) {
  cv::Vec3d m;
  for (int c = 0; c < 3; ++c) {
    std::vector<uint8_t> channel(pixels.size());
    for (size_t i = 0; i < pixels.size(); ++i) channel[i] = pixels[i][c];
    const auto mid = channel.begin() + static_cast<std::ptrdiff_t>(channel.size() / 2);
    std::nth_element(channel.begin(), mid, channel.end());
    m[c] = *mid;
  }
  return m;
}
}  // namespace

cv::Mat projectOnColourAxes(const cv::Mat& bgr, const std::vector<ColourAxis>& axes) {
  CV_Assert(bgr.type() == CV_8UC3);
  // Each projection costs a pass over the frame's three channels (2-4 ms at
  // 1920x1080), and a cell teaches many types of one colour on one surface:
  // fifteen such axes cost 50 ms a frame. Axes whose two ends lie within
  // kSameAxis of an axis already projected give the same levels to within
  // a few grey levels, and are not projected again.
  std::vector<const ColourAxis*> distinct;
  for (const auto& axis : axes) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](const ColourAxis* a) {
      return cv::norm(a->part - axis.part) <= kSameAxis &&
             cv::norm(a->background - axis.background) <= kSameAxis;
    });
    if (!seen) distinct.push_back(&axis);
  }
  // level = part + (background - part) * t, t = (p - part) . d / |d|^2: a
  // linear map of the three channels, done by cv::transform.
  std::vector<cv::Matx14d> maps;
  for (const ColourAxis* each : distinct) {
    const ColourAxis& axis = *each;
    const cv::Vec3d d = axis.background - axis.part;
    const double d2 = d.dot(d);
    if (d2 <= 0) continue;
    const double gain = (kColourBackgroundLevel - kColourPartLevel) / d2;
    maps.emplace_back(gain * d[0], gain * d[1], gain * d[2],
                      kColourPartLevel - gain * axis.part.dot(d));
  }
  cv::Mat out;
  if (maps.empty()) {
    cv::cvtColor(bgr, out, cv::COLOR_BGR2GRAY);
    return out;
  }
  // cv::transform runs on one core: bands of rows on every core instead,
  // each pixel mapped as before (a 1920x1080 frame's projection took 2.3 ms
  // on one core, 1.2 ms in bands on two, the same levels; LOCATE on the
  // front-light benchmark's colour frames, 14 types taught, median 16.2 ->
  // 11.6 ms separated, 26.3 -> 22.1 touching).
  out.create(bgr.size(), CV_8UC1);
  cv::parallel_for_(cv::Range(0, bgr.rows), [&](const cv::Range& rows) {
    const cv::Mat in = bgr.rowRange(rows.start, rows.end);
    cv::Mat band = out.rowRange(rows.start, rows.end);
    cv::transform(in, band, maps.front());
    cv::Mat one;
    for (size_t k = 1; k < maps.size(); ++k) {
      cv::transform(in, one, maps[k]);
      cv::min(band, one, band);
    }
  });
  return out;
}

namespace {
// How far each pixel of `box` lies from `background` (saturated to 8 bits):
// its whole colour difference, or (`hue_only`) only the part of it across
// the background's own colour, which a change of light along the surface
// (the lamp's fall-off, a vignette, a blotch of the belt's grey) does not
// move, since it scales a colour along itself.
double distanceOf(const cv::Vec3d& c, const cv::Vec3d& background, bool hue_only) {
  const double b2 = background.dot(background);
  const cv::Vec3d v =
      hue_only && b2 > 0 ? c - background * (c.dot(background) / b2) : c - background;
  return std::sqrt(v.dot(v));
}

cv::Mat distanceFrom(const cv::Mat& box, const cv::Vec3d& background, bool hue_only) {
  cv::Mat distance(box.size(), CV_8UC1);
  for (int y = 0; y < box.rows; ++y) {
    const cv::Vec3b* p = box.ptr<cv::Vec3b>(y);
    uint8_t* d = distance.ptr<uint8_t>(y);
    for (int x = 0; x < box.cols; ++x) {
      d[x] = cv::saturate_cast<uint8_t>(
          distanceOf(cv::Vec3d(p[x][0], p[x][1], p[x][2]), background, hue_only));
    }
  }
  return distance;
}

// The part's colour in `box`: the median of the pixels Otsu's split of
// `distance` sets apart; none when it sets none apart.
std::optional<cv::Vec3d> farColour(const cv::Mat& box, const cv::Mat& distance) {
  cv::Mat far;
  cv::threshold(distance, far, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  std::vector<cv::Vec3b> part;
  for (int y = 0; y < box.rows; ++y) {
    const cv::Vec3b* p = box.ptr<cv::Vec3b>(y);
    const uint8_t* f = far.ptr<uint8_t>(y);
    for (int x = 0; x < box.cols; ++x) {
      if (f[x]) part.push_back(p[x]);
    }
  }
  if (part.empty()) return std::nullopt;
  return medianColour(part);
}
}  // namespace

std::optional<ColourAxis> colourAxisIn(const cv::Mat& bgr, const cv::Rect& rect) {
  CV_Assert(bgr.type() == CV_8UC3);
  const cv::Rect r = rect & cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (r.width < kMinSide || r.height < kMinSide) return std::nullopt;
  const cv::Mat box = bgr(r);
  std::vector<cv::Vec3b> rim;
  for (int x = 0; x < box.cols; ++x) {
    rim.push_back(box.at<cv::Vec3b>(0, x));
    rim.push_back(box.at<cv::Vec3b>(box.rows - 1, x));
  }
  for (int y = 1; y + 1 < box.rows; ++y) {
    rim.push_back(box.at<cv::Vec3b>(y, 0));
    rim.push_back(box.at<cv::Vec3b>(y, box.cols - 1));
  }
  ColourAxis axis;
  axis.background = medianColour(rim);
  // Split on the whole colour difference first; where that sets apart the
  // surface's own light (a whole frame's rim, darkened by the vignette, set
  // its lit middle apart, and the part was a few percent of it), on the
  // difference across the surface's colour alone. Each against the rim's
  // own spread in that difference: a vignette spreads the rim's
  // brightness, not its hue.
  for (const bool hue_only : {false, true}) {
    double squares = 0;
    for (const auto& p : rim) {
      squares += std::pow(distanceOf(cv::Vec3d(p[0], p[1], p[2]), axis.background, hue_only), 2);
    }
    const double spread = std::sqrt(squares / static_cast<double>(rim.size()));
    const auto part = farColour(box, distanceFrom(box, axis.background, hue_only));
    if (!part) continue;
    axis.part = *part;
    if (distanceOf(axis.part, axis.background, hue_only) >=
        std::max(kMinColourDistance, kMinDistanceOverSpread * spread)) {
      return axis;
    }
  }
  return std::nullopt;
}

bool colourSeparatesBetter(const ColourAxis& axis, double factor) {
  return cv::norm(axis.part - axis.background) >
         factor * std::abs(luma(axis.part) - luma(axis.background));
}

}  // namespace picksight::vision
