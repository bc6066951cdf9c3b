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
  // The simulated robot: its hidden transform and the target it holds
  // (hidden until moveTarget()).
  synthetic::RobotCamera robot;
  synthetic::CalibrationTarget target;
};

// Parses the part after "synthetic:", comma-separated key=value pairs:
// width, height, parts, seed, noise, size (part size px), light (uneven, flat,
// or a front light: textured, shadow, glossy, low-contrast, wood, metal),
// types (names joined by '+'), touching, blur, scene_every; the simulated
// robot: mm_per_px, rz, dx, dy (mm), tilt_x, tilt_y (degrees); its target:
// target (disc|grid), target_radius (mm), grid (COLSxROWS), grid_pitch (mm).
// The error names the key.
Result<SyntheticSourceOptions> parseSyntheticOptions(const std::string& text);

class SyntheticSource : public Source {
 public:
  explicit SyntheticSource(SyntheticSourceOptions options);

  Result<void> open() override;
  void close() override {}
  SourceInfo info() const override;
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;
  // One feature, "Parts": how many parts lie in the scene (0 = an empty
  // table, as for a calibration), the layout drawn again from the seed.
  std::vector<Feature> features() override;
  Result<Feature> feature(const std::string& name) override;
  Result<void> setFeature(const std::string& name, const std::string& value) override;
  Result<SimulatedRobot> moveTarget(std::optional<cv::Point2d> at_mm) override;
  Result<SimulatedRobot> simulatedRobot() const override;

 private:
  // Lays out the scene (with `seed_offset` added to the seed) and shows the
  // target where the robot holds it.
  void makeRenderer(uint64_t seed_offset);
  // A pooled image buffer nobody else holds any more, or a fresh one when
  // all are still in use.
  cv::Mat& freeBuffer();

  SyntheticSourceOptions options_;
  std::unique_ptr<synthetic::SceneRenderer> renderer_;
  uint64_t frame_index_ = 0;
  uint64_t layout_ = 0;                      // which layout renderer_ holds
  std::optional<cv::Point2d> target_at_mm_;  // where the robot holds the target
  // Rendered frames live in these buffers while published (the camera's last
  // frame, ZeroMQ until sent): reusing them spares the page faults of a fresh
  // 2 MB allocation per frame.
  std::vector<cv::Mat> pool_;
  cv::Mat spare_;  // when every pooled buffer is in use
};

}  // namespace picksight::video
