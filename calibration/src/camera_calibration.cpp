// Camera scale and lens calibration.
#include "picksight/calibration/camera_calibration.hpp"

#include "picksight/calibration/calibration_errors.hpp"

#include <opencv2/calib3d.hpp>

#include <cmath>

#include "picksight/common/angles.hpp"

namespace picksight::calibration {

Result<PixelScale> scaleFromCircle(const cv::Moments& m, double radius_mm) {
  if (!(radius_mm > 0))
    return makeError(CalibrationErrc::kBadInput, "target radius must be positive");
  if (m.m00 <= 0 || m.mu20 <= 0 || m.mu02 <= 0)
    return makeError(CalibrationErrc::kBadTarget, "target has no area");
  PixelScale s;
  s.mm_per_px_x = radius_mm / (2.0 * std::sqrt(m.mu20 / m.m00));
  s.mm_per_px_y = radius_mm / (2.0 * std::sqrt(m.mu02 / m.m00));
  // Axis of the imaged ellipse; meaningless for a circle (isotropic), so it
  // only counts once the ellipse is measurably elongated.
  const double spread = std::hypot(m.mu20 - m.mu02, 2 * m.mu11) / (m.mu20 + m.mu02);
  if (spread > 1e-3) {
    const double axis = 0.5 * std::atan2(2 * m.mu11, m.mu20 - m.mu02) * 180.0 / M_PI;
    // How far the axis leans from the nearest image axis.
    s.skew_deg = picksight::angleDiffDeg(axis, 0.0, 90.0);
  }
  return s;
}

std::vector<cv::Point2d> LensModel::undistort(const std::vector<cv::Point2d>& pixels) const {
  if (pixels.empty()) return {};
  std::vector<cv::Point2d> out;
  cv::undistortPoints(pixels, out, cv::Mat(camera_matrix), distortion, cv::noArray(),
                      cv::Mat(camera_matrix));
  return out;
}

Result<LensModel> calibrateChessboard(const std::vector<cv::Mat>& views,
                                      const ChessboardOptions& options, std::vector<int>* skipped) {
  std::vector<cv::Point3f> board;
  for (int y = 0; y < options.inner_corners.height; ++y) {
    for (int x = 0; x < options.inner_corners.width; ++x) {
      board.emplace_back(static_cast<float>(x * options.square_mm),
                         static_cast<float>(y * options.square_mm), 0.f);
    }
  }
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  cv::Size size;
  for (size_t i = 0; i < views.size(); ++i) {
    cv::Mat grey = views[i];
    if (grey.channels() == 3) cv::cvtColor(views[i], grey, cv::COLOR_BGR2GRAY);
    if (grey.empty() || (!size.empty() && grey.size() != size)) {
      if (skipped) skipped->push_back(static_cast<int>(i));
      continue;
    }
    std::vector<cv::Point2f> corners;
    const bool found =
        cv::findChessboardCorners(grey, options.inner_corners, corners,
                                  cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found) {
      if (skipped) skipped->push_back(static_cast<int>(i));
      continue;
    }
    cv::cornerSubPix(grey, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.01));
    size = grey.size();
    image_points.push_back(corners);
    object_points.push_back(board);
  }
  if (image_points.size() < 3) {
    return makeError(CalibrationErrc::kBadInput, "the chessboard was found in " +
                                                     std::to_string(image_points.size()) +
                                                     " views; at least 3 are needed");
  }
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F);
  cv::Mat dist;
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = options.fix_aspect_ratio ? cv::CALIB_FIX_ASPECT_RATIO : 0;
  LensModel model;
  model.rms_reprojection_px =
      cv::calibrateCamera(object_points, image_points, size, k, dist, rvecs, tvecs, flags);
  model.image_size = size;
  model.camera_matrix = cv::Matx33d(k);
  dist.reshape(1, 1).copyTo(model.distortion);
  model.views = static_cast<int>(image_points.size());
  return model;
}

std::string lensModelToYaml(const LensModel& model) {
  cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "format_version" << 1;
  fs << "image_width" << model.image_size.width << "image_height" << model.image_size.height;
  fs << "camera_matrix" << cv::Mat(model.camera_matrix);
  fs << "distortion_coefficients" << cv::Mat(model.distortion, true);
  fs << "rms_reprojection_px" << model.rms_reprojection_px << "views" << model.views;
  return fs.releaseAndGetString();
}

Result<LensModel> lensModelFromYaml(const std::string& text) {
  try {
    cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    if (!fs.isOpened()) return makeError(CalibrationErrc::kBadFile, "not a YAML document");
    if (static_cast<int>(fs["format_version"]) != 1)
      return makeError(CalibrationErrc::kBadFile, "format_version must be 1");
    LensModel m;
    m.image_size =
        cv::Size(static_cast<int>(fs["image_width"]), static_cast<int>(fs["image_height"]));
    cv::Mat k;
    cv::Mat d;
    fs["camera_matrix"] >> k;
    fs["distortion_coefficients"] >> d;
    if (k.rows != 3 || k.cols != 3 || k.type() != CV_64F)
      return makeError(CalibrationErrc::kBadFile, "camera_matrix must be 3x3");
    if (d.total() < 4 || d.total() > 14)
      return makeError(CalibrationErrc::kBadFile,
                       "distortion_coefficients must have 4 to 14 values");
    m.camera_matrix = cv::Matx33d(k);
    d.reshape(1, 1).convertTo(d, CV_64F);
    d.copyTo(m.distortion);
    m.rms_reprojection_px = static_cast<double>(fs["rms_reprojection_px"]);
    m.views = static_cast<int>(fs["views"]);
    if (m.image_size.width <= 0 || m.image_size.height <= 0)
      return makeError(CalibrationErrc::kBadFile, "image size missing");
    return m;
  } catch (const cv::Exception& e) {
    return makeError(CalibrationErrc::kBadFile, std::string("unreadable lens model: ") + e.what());
  }
}

}  // namespace picksight::calibration
