// The synthetic camera: renders scenes with known ground truth so the whole
// product runs, and is tested, on a machine with no camera.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "picksight/sources/source.hpp"
#include "picksight/synthetic/scene.hpp"

namespace picksight::video {

struct SyntheticSourceOptions {
  synthetic::SceneOptions scene;
  // A new layout (seed + n) every this many frames; 0 = the same parts always.
  uint64_t scene_every = 0;
};

// Parses the part after "synthetic:", comma-separated key=value pairs:
// width, height, parts, seed, noise, size (part size px), light (uneven|flat),
// types (names joined by '+'), scene_every. The error names the key.
Result<SyntheticSourceOptions> parseSyntheticOptions(const std::string& text);

class SyntheticSource : public Source {
 public:
  explicit SyntheticSource(SyntheticSourceOptions options);

  Result<void> open() override;
  void close() override {}
  SourceInfo info() const override;
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;

 private:
  // A pooled image buffer nobody else holds any more, or a fresh one when
  // all are still in use.
  cv::Mat& freeBuffer();

  SyntheticSourceOptions options_;
  std::unique_ptr<synthetic::SceneRenderer> renderer_;
  uint64_t frame_index_ = 0;
  uint64_t layout_ = 0;  // which layout renderer_ holds
  // Rendered frames live in these buffers while published (the camera's last
  // frame, ZeroMQ until sent): reusing them spares the page faults of a fresh
  // 2 MB allocation per frame.
  std::vector<cv::Mat> pool_;
  cv::Mat spare_;  // when every pooled buffer is in use
};

}  // namespace picksight::video
