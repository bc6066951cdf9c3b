// Sensor mapping conversions, written once for every vision result; JPEG
// files told from the rest.
#include "picksight/common/frame.hpp"

#include "picksight/common/angles.hpp"

#include <array>
#include <cmath>
#include <fstream>

#include "picksight/common/clock.hpp"

namespace picksight {

cv::Point2d SensorMapping::toSensor(cv::Point2d p) const {
  return {roi_x + (p.x + 0.5) / scale_x - 0.5, roi_y + (p.y + 0.5) / scale_y - 0.5};
}

cv::Point2d SensorMapping::toFrame(cv::Point2d p) const {
  return {(p.x - roi_x + 0.5) * scale_x - 0.5, (p.y - roi_y + 0.5) * scale_y - 0.5};
}

cv::Matx23d SensorMapping::sensorToFrame() const {
  return {scale_x, 0, (0.5 - roi_x) * scale_x - 0.5, 0, scale_y, (0.5 - roi_y) * scale_y - 0.5};
}

double SensorMapping::directionToSensor(double deg) const {
  // A direction scales like a displacement: undo an anisotropic resize.
  const double a = deg * kRadPerDeg;
  return normalizeDeg(std::atan2(std::sin(a) / scale_y, std::cos(a) / scale_x) * kDegPerRad);
}

double SensorMapping::lengthToSensor(double length) const {
  return length / std::sqrt(scale_x * scale_y);
}

double SensorMapping::areaToSensor(double area) const { return area / (scale_x * scale_y); }

double SensorMapping::areaToFrame(double area) const { return area * scale_x * scale_y; }

cv::Moments SensorMapping::momentsToSensor(const cv::Moments& m) const {
  // An x length grows by 1/scale_x: mu_pq gains (1/sx)^(p+1) (1/sy)^(q+1).
  const double sx = scale_x, sy = scale_y;
  // A copy, not a default cv::Moments: its constructor lives in imgproc.
  cv::Moments out = m;
  out.m10 = out.m01 = out.m20 = out.m11 = out.m02 = 0;
  out.m30 = out.m21 = out.m12 = out.m03 = 0;
  out.mu30 = out.mu21 = out.mu12 = out.mu03 = 0;
  out.nu20 = out.nu11 = out.nu02 = out.nu30 = out.nu21 = out.nu12 = out.nu03 = 0;
  out.m00 = m.m00 / (sx * sy);
  out.mu20 = m.mu20 / (sx * sx * sx * sy);
  out.mu02 = m.mu02 / (sx * sy * sy * sy);
  out.mu11 = m.mu11 / (sx * sx * sy * sy);
  return out;
}

cv::Rect SensorMapping::boxToSensor(const cv::Rect& box) const {
  const cv::Point2d tl = toSensor(cv::Point2d(box.x, box.y));
  return {static_cast<int>(std::lround(tl.x)), static_cast<int>(std::lround(tl.y)),
          static_cast<int>(std::lround(box.width / scale_x)),
          static_cast<int>(std::lround(box.height / scale_y))};
}

Frame frameFromImage(const cv::Mat& image, const std::string& camera, uint64_t sequence) {
  Frame frame;
  frame.image = image;
  frame.info.camera = camera;
  frame.info.sequence = sequence;
  frame.info.host_timestamp_ns = realtimeNs();
  frame.info.received_ns = monotonicNs();
  frame.info.width = static_cast<uint32_t>(image.cols);
  frame.info.height = static_cast<uint32_t>(image.rows);
  frame.info.triggered = true;
  return frame;
}

bool isJpegFile(const std::string& path) {
  // Every JPEG stream starts with a start-of-image marker followed by
  // another marker (JFIF, Exif, a table).
  std::array<char, 3> head{};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(head.data(), head.size())) return false;
  return static_cast<unsigned char>(head[0]) == 0xFF &&
         static_cast<unsigned char>(head[1]) == 0xD8 && static_cast<unsigned char>(head[2]) == 0xFF;
}

}  // namespace picksight
