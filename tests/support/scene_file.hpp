// Drawn scenes for end-to-end tests: the image file of a file camera,
// replaced atomically (the file source re-reads it when its inode changes),
// and the fixed-point placement of shapes drawn supersampled then averaged
// down (exact edge coverage, unlike LINE_AA).
#pragma once

#include <catch2/catch.hpp>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace picksight::e2e {

// A point of the final image (pixel centres at integer coordinates) on a
// canvas `super` times larger, in fixed point with `shift` fractional bits.
inline cv::Point supersampledPoint(cv::Point2d p, int super, int shift) {
  const double s = super * (1 << shift);
  return {static_cast<int>(std::lround((p.x + 0.5) * s - 0.5 * (1 << shift))),
          static_cast<int>(std::lround((p.y + 0.5) * s - 0.5 * (1 << shift)))};
}

// A temporary directory holding scene.png, removed at the end.
struct SceneFile {
  std::string dir;
  std::string path;
  explicit SceneFile(const cv::Mat& first) {
    char d[] = "/tmp/picksight-scene-XXXXXX";
    REQUIRE(::mkdtemp(d) != nullptr);
    dir = d;
    path = dir + "/scene.png";
    show(first);
  }
  ~SceneFile() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  SceneFile(const SceneFile&) = delete;
  SceneFile& operator=(const SceneFile&) = delete;
  void show(const cv::Mat& img) const {
    const std::string next = dir + "/next.png";
    REQUIRE(picksight::codecs::imwrite(next, img));
    REQUIRE(std::rename(next.c_str(), path.c_str()) == 0);
  }
};

}  // namespace picksight::e2e
