// The calibration file's 3x3 matrices (transform.matrix, scale.rectify,
// lens.camera_matrix),
// read by one reader: a damaged one is refused with its key named.
#include <catch2/catch.hpp>

#include "temp_dir.hpp"

#include <fstream>
#include <string>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/calibration/calibration_store.hpp"

using namespace picksight::calibration;
using picksight::test::TempDir;

namespace {
// The load error of a calibration file holding `body` after its header.
std::string loadError(const TempDir& dir, const std::string& body) {
  const std::string path = dir.file("calibration.yaml");
  {
    std::ofstream out(path);
    out << "format_version: 2\nnext_id: 1\npoints: []\n" << body;
  }
  CalibrationStore store(path);
  const auto loaded = store.load();
  if (loaded) return "loaded";
  CHECK(loaded.error().code == CalibrationErrc::kBadFile);
  return loaded.error().message;
}
}  // namespace

TEST_CASE("a damaged calibration matrix is refused with its key named", "[calibration][store]") {
  const TempDir dir;
  const std::string homography =
      "transform: {dx: 0, dy: 0, rz_deg: 0, model: homography, rms: 0.1, ";
  const std::string scale = "scale: {mm_per_px_x: 0.2, mm_per_px_y: 0.2, ";
  const std::string lens = "lens: {image_width: 640, image_height: 480, ";
  const std::string lens_rest = ", distortion: [0, 0, 0, 0], rms_reprojection_px: 0.2}\n";
  const struct {
    std::string body;
    std::string message;
  } cases[] = {
      {homography + "}\n", "missing transform.matrix"},
      {homography + "matrix: [1, 0, 0, 0, 1, 0, 0, 0]}\n", "transform.matrix must have 9 values"},
      {homography + "matrix: [1, 0, 0, 0, 1, 0, 0, 0, .inf]}\n",
       "transform.matrix is not all finite numbers"},
      {homography + "matrix: square}\n", "transform.matrix is not a list of numbers"},
      {scale + "rectify: [1, 0, 0, 0, 1, 0, 0, 0, 1, 0]}\n", "scale.rectify must have 9 values"},
      {scale + "rectify: [.nan, 0, 0, 0, 1, 0, 0, 0, 1]}\n", "scale.rectify is not all finite"},
      {scale + "rectify: [1, 0, 0, 0, x, 0, 0, 0, 1]}\n", "scale.rectify is not a list of numbers"},
      {scale + "rectify: [1, 0, 0, 0, 0, 0, 0, 0, 1]}\n", "scale.rectify is singular"},
      {lens + "distortion: [0, 0, 0, 0]}\n", "missing lens.camera_matrix"},
      {lens + "camera_matrix: [500, 0, 320, 0, 500, 240]" + lens_rest,
       "lens.camera_matrix must have 9 values"},
      {lens + "camera_matrix: [500, 0, 320, 0, .nan, 240, 0, 0, 1]" + lens_rest,
       "lens.camera_matrix is not all finite"},
  };
  for (const auto& c : cases) {
    INFO(c.body);
    const std::string error = loadError(dir, c.body);
    INFO(error);
    CHECK(error.find(c.message) != std::string::npos);
  }
  // And sound ones are read, row by row.
  CHECK(loadError(dir, homography + "matrix: [2, 0, 1, 0, 2, 3, 0, 0, 1]}\n") == "loaded");
  CHECK(loadError(dir, scale + "rectify: [1, 0.01, 0, 0, 1, 0, 0, 0, 1]}\n") == "loaded");
  CHECK(loadError(dir, lens + "camera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]" + lens_rest) ==
        "loaded");
}
