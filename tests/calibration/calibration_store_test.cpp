// Calibration persistence: survives a reload, ids never reused, damaged
// files refused with the file named, and a failed write changes nothing.
#include <catch2/catch.hpp>

#include "temp_dir.hpp"

#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "picksight/calibration/calibration_store.hpp"
#include "picksight/calibration/vision_frame.hpp"

using namespace picksight::calibration;
namespace fs = std::filesystem;

namespace {
using picksight::test::TempDir;
}  // namespace

TEST_CASE("calibration points, transform, scale and lens survive a reload",
          "[calibration][store]") {
  TempDir dir;
  const std::string file = dir.file("calibration.yaml");
  {
    CalibrationStore store(file);
    REQUIRE(store.load());
    CHECK(*store.addPoint({{1.5, -2.25}, {300.125, 40}}) == 1);
    CHECK(*store.addPoint({{10, 20}, {310, 60}}) == 2);
    CHECK(*store.addPoint({{30, 5}, {330, 45}}, cv::Point2d(120.25, -20.5)) == 3);
    REQUIRE(store.deletePoint(2));
    CalibrationResult r;
    r.transform = PlaneTransform::rigid({300.1234567891, 41.5, -12.25, false});
    r.rms = 0.0123;
    r.inliers = 2;
    REQUIRE(store.setTransform(r));
    REQUIRE(store.setScale({0.2512345678, 0.25, 0.1}));
    LensModel lens;
    lens.image_size = cv::Size(640, 480);
    lens.camera_matrix = cv::Matx33d(536, 0, 342, 0, 536, 235, 0, 0, 1);
    lens.distortion = {-0.26, -0.04, 0.0018, -0.0003, 0.24};
    lens.rms_reprojection_px = 0.41;
    REQUIRE(store.setLens(lens));
  }
  CalibrationStore again(file);
  REQUIRE(again.load());
  REQUIRE(again.points().size() == 2);
  CHECK(again.points().at(1).robot.x == 300.125);
  CHECK(again.points().at(3).vision.y == 5);
  // The sensor pixel a point was measured at, when given.
  REQUIRE(again.pixels().count(3));
  CHECK(again.pixels().at(3) == cv::Point2d(120.25, -20.5));
  CHECK_FALSE(again.pixels().count(1));
  CHECK_FALSE(again.points().count(2));
  REQUIRE(again.transform());
  CHECK(again.transform()->transform.dx == 300.1234567891);
  CHECK(again.transform()->transform.rz_deg == -12.25);
  REQUIRE(again.scale());
  CHECK(again.scale()->mm_per_px_x == 0.2512345678);
  REQUIRE(again.lens());
  CHECK(again.lens()->distortion[4] == 0.24);
  // Ids are never reused, even after a delete and a restart.
  CHECK(*again.addPoint({{0, 0}, {0, 0}}) == 4);
  CHECK_FALSE(again.deletePoint(2));
  CHECK(again.deletePoint(2).error().message.find("2") != std::string::npos);
}

TEST_CASE("a damaged calibration file is refused, named, and left alone", "[calibration][store]") {
  TempDir dir;
  const std::string file = dir.file("calibration.yaml");
  std::ofstream(file) << "format_version: 1\npoints:\n  - {id: 1, vision_x: 1}\n";
  CalibrationStore store(file);
  auto r = store.load();
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find(file) != std::string::npos);
  CHECK(store.points().empty());
  std::ofstream(file) << "format_version: 7\n";
  CHECK_FALSE(store.load());
  std::ofstream(file) << "{{{{ not yaml";
  CHECK_FALSE(store.load());
}

TEST_CASE("a failed write keeps memory and disk as they were", "[calibration][store]") {
  TempDir dir;
  const std::string sub = dir.file("data");
  fs::create_directory(sub);
  CalibrationStore store(sub + "/calibration.yaml");
  REQUIRE(store.addPoint({{1, 1}, {2, 2}}));
  // The directory vanishes (a disk unmounted): the write fails cleanly.
  fs::remove_all(sub);
  CHECK_FALSE(store.addPoint({{3, 3}, {4, 4}}));
  CHECK(store.points().size() == 1);
  CHECK_FALSE(store.deletePoint(1));
  CHECK(store.points().size() == 1);
}

TEST_CASE("the vision frame flips y so that a camera looking down is right-handed",
          "[calibration][frame]") {
  VisionFrame frame(PixelScale{0.5, 0.25, 0});
  const cv::Point2d mm = frame.toMm({100, 40});
  CHECK(mm.x == 50);
  CHECK(mm.y == -10);
  CHECK(frame.toPixels(mm).x == Approx(100));
  CHECK(frame.toPixels(mm).y == Approx(40));
  // 30 degrees clockwise on screen is 30 degrees clockwise seen from above:
  // -30, that is 330, counter-clockwise.
  CHECK(VisionFrame::angleToVision(30) == Approx(330));
  CHECK(VisionFrame::angleToImage(VisionFrame::angleToVision(123)) == Approx(123));
}

TEST_CASE("similarity, tilt and homography transforms survive a reload", "[calibration][store]") {
  TempDir dir;
  const std::string file = dir.file("calibration.yaml");
  const cv::Matx33d h(0.998, -0.061, 328.4, 0.0605, 0.9975, -614.4, 1.2e-6, -3.4e-6, 1);
  {
    CalibrationStore store(file);
    CalibrationResult r;
    r.transform = PlaneTransform::similarity({10, 20, 179.5, true}, 0.997);
    r.method = Method::kSimilarity;
    REQUIRE(store.setTransform(r));
  }
  CalibrationStore again(file);
  REQUIRE(again.load());
  REQUIRE(again.transform());
  CHECK(again.transform()->method == Method::kSimilarity);
  CHECK(again.transform()->transform.model == TransformModel::kSimilarity);
  CHECK(again.transform()->transform.scale == 0.997);
  CHECK(again.transform()->transform.mirrored);
  CHECK(again.transform()->transform.apply({100, 50}).x ==
        Approx(PlaneTransform::similarity({10, 20, 179.5, true}, 0.997).apply({100, 50}).x));
  CalibrationResult r;
  r.transform = *PlaneTransform::homography(h);
  r.method = Method::kHomography;
  REQUIRE(again.setTransform(r));
  CalibrationStore third(file);
  REQUIRE(third.load());
  REQUIRE(third.transform());
  CHECK(third.transform()->transform.model == TransformModel::kHomography);
  CHECK(third.transform()->transform.matrix == r.transform.matrix);
  r.transform.model = TransformModel::kTilt;
  r.method = Method::kTilt;
  REQUIRE(third.setTransform(r));
  CalibrationStore fourth(file);
  REQUIRE(fourth.load());
  REQUIRE(fourth.transform());
  CHECK(fourth.transform()->method == Method::kTilt);
  CHECK(fourth.transform()->transform.model == TransformModel::kTilt);
  CHECK(fourth.transform()->transform.matrix == r.transform.matrix);
}

TEST_CASE("a version 1 calibration file is still read", "[calibration][store]") {
  TempDir dir;
  const std::string file = dir.file("calibration.yaml");
  std::ofstream(file) << "format_version: 1\nnext_id: 3\npoints:\n"
                         "  - {id: 2, vision_x: 1.5, vision_y: 2, robot_x: 300, robot_y: 40}\n"
                         "transform:\n  dx: 328.4\n  dy: -614.4\n  rz_deg: 181\n"
                         "  mirrored: false\n  method: geometric\n  rms: 0.1\n  inliers: 17\n";
  CalibrationStore store(file);
  REQUIRE(store.load());
  REQUIRE(store.transform());
  CHECK(store.transform()->method == Method::kGeometric);
  CHECK(store.transform()->transform.model == TransformModel::kRigid);
  CHECK(store.transform()->transform.apply({0, 0}).x == Approx(328.4));
  CHECK(store.points().at(2).robot.x == 300);
}

TEST_CASE("non-finite numbers in a calibration file are refused with the key named",
          "[calibration][store]") {
  TempDir dir;
  const std::string file = dir.file("calibration.yaml");
  const std::string good_point = "  - {id: 1, vision_x: 1, vision_y: 2, robot_x: 3, robot_y: 4}\n";
  struct Case {
    std::string text;
    std::string key;
  };
  for (const Case& c : {
           Case{"format_version: 2\ntransform: {dx: .nan, dy: 0, rz_deg: 0, rms: 0}\n",
                "transform.dx"},
           Case{"format_version: 2\ntransform: {dx: 0, dy: 0, rz_deg: .inf, rms: 0}\n",
                "transform.rz_deg"},
           Case{"format_version: 2\ntransform: {dx: 0, dy: 0, rz_deg: 0, rms: 0, model: "
                "similarity, scale: -.inf}\n",
                "transform.scale"},
           Case{"format_version: 2\ntransform: {dx: 0, dy: 0, rz_deg: 0, rms: 0, model: "
                "homography, matrix: [1, 0, 0, 0, 1, .nan, 0, 0, 1]}\n",
                "transform.matrix"},
           Case{"format_version: 2\npoints:\n" + good_point +
                    "  - {id: 2, vision_x: .nan, vision_y: 2, robot_x: 3, robot_y: 4}\n",
                "point 2 vision_x"},
           Case{"format_version: 2\nscale: {mm_per_px_x: .nan, mm_per_px_y: 0.25}\n",
                "scale.mm_per_px_x"},
       }) {
    INFO(c.text);
    std::ofstream(file) << c.text;
    CalibrationStore store(file);
    auto r = store.load();
    REQUIRE_FALSE(r);
    CHECK(r.error().code == CalibrationErrc::kBadFile);
    CHECK(r.error().message.find(c.key) != std::string::npos);
    CHECK_FALSE(store.transform());
  }
}
