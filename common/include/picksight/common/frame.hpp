// Frame: one camera image in process, whatever brought it (the frame codec,
// a still image, the video server's own camera thread), with where its
// pixels lie on the sensor and what is known about its acquisition. Vision
// code sees only this type, never a wire message.
//
// Ownership: a Frame is a value; share it as std::shared_ptr<const Frame>.
// Its image is a view, and `owner` keeps the bytes under it alive (a
// received ZeroMQ buffer, no copy); an image that owns its bytes (a
// refcounted cv::Mat) needs no owner. Nobody writes into a Frame's pixels.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace picksight {

// Ground truth of one part in a synthetic frame, in sensor pixels.
struct TruthPart {
  std::string type;
  double x = 0;
  double y = 0;
  double angle_deg = 0;       // [0, 360), image axes (x right, y down)
  double symmetry_deg = 360;  // period of the measurable angle; 0 = none
  double area_px = 0;
};

// Where a frame's pixels lie on the sensor: the ROI offset (sensor pixels)
// and the resize (frame pixels per sensor pixel, per axis). Pixel centres are
// at integer coordinates in both, so frame pixel (u, v) is sensor pixel
//   x = roi_x + (u + 0.5) / scale_x - 0.5,  y = roi_y + (v + 0.5) / scale_y - 0.5
// (the convention of proto/picksight.proto).
struct SensorMapping {
  double roi_x = 0;
  double roi_y = 0;
  double scale_x = 1;
  double scale_y = 1;

  cv::Point2d toSensor(cv::Point2d frame_px) const;
  cv::Point2d toFrame(cv::Point2d sensor_px) const;
  // toFrame as an affine matrix (for warps and masks in frame pixels).
  cv::Matx23d sensorToFrame() const;
  // A direction in degrees, [0, 360), image axes: a direction scales like a
  // displacement, so an anisotropic resize turns it.
  double directionToSensor(double deg) const;
  // A length along no particular axis (a perimeter): the geometric mean of
  // the two scales.
  double lengthToSensor(double length) const;
  double areaToSensor(double area) const;
  double areaToFrame(double area) const;
  // Area (m00) and central second moments (mu20, mu11, mu02) to sensor
  // pixels; the other fields are left zero.
  cv::Moments momentsToSensor(const cv::Moments& m) const;
  // A bounding box: its top-left pixel mapped, its size scaled, rounded.
  cv::Rect boxToSensor(const cv::Rect& box) const;
};

// What is known about a frame's acquisition.
struct FrameInfo {
  std::string camera;
  uint64_t sequence = 0;
  uint64_t device_timestamp_ns = 0;  // 0 when the device gives none
  uint64_t host_timestamp_ns = 0;    // CLOCK_REALTIME when acquired
  // Local CLOCK_MONOTONIC when this process got the frame: tells a frame that
  // arrived after a request from an older one, whatever the sender's clock.
  uint64_t received_ns = 0;
  uint32_t width = 0;
  uint32_t height = 0;
  bool triggered = false;  // produced for a software trigger
  // Its pixels went through lossy compression (a stream, MJPEG, a JPEG
  // file): colour at half resolution, so LEARN warns where a part is told
  // from its surface by colour alone.
  bool compressed = false;
};

struct Frame {
  cv::Mat image;                      // CV_8UC1 or CV_8UC3 (BGR)
  std::shared_ptr<const void> owner;  // keeps image's bytes alive when it is a view
  SensorMapping mapping;
  FrameInfo info;
  std::vector<TruthPart> truth;  // synthetic sources only
};

// A still image (CV_8UC1 or CV_8UC3) as a frame of `camera`: full sensor, no
// resize, triggered, stamped now. Shares the image's pixels: the caller must
// not write into them afterwards (clone first if it will).
Frame frameFromImage(const cv::Mat& image, const std::string& camera, uint64_t sequence);

// Whether the file holds a JPEG (its first bytes, whatever its name says): an
// image read from it went through lossy compression (FrameInfo::compressed).
bool isJpegFile(const std::string& path);

}  // namespace picksight
