// Aravis's fake GigE Vision camera as a child process on 127.0.0.1, for the
// Aravis source tests: started fresh per test (its settings persist only as
// long as its process), killed and restarted to simulate an unplugged camera.
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "picksight/tool_support/subprocess.hpp"

namespace picksight::test {

class FakeGvCamera {
 public:
  // The id Aravis gives the fake camera: "<vendor>-<model>-<serial>".
  static constexpr const char* kDeviceId = "Aravis-Fake-GV01";

  // Starts the camera and waits until Aravis can open it; REQUIREs success.
  FakeGvCamera();
  ~FakeGvCamera();
  FakeGvCamera(const FakeGvCamera&) = delete;
  FakeGvCamera& operator=(const FakeGvCamera&) = delete;

  void start();
  // SIGKILL: the camera vanishes as if unplugged, no goodbye on the wire.
  void kill();
  bool running() const { return process_ != nullptr; }

 private:
  std::unique_ptr<tool_support::Subprocess> process_;
};

// The fake camera draws a diagonal ramp, (x + y + frame id) mod 255, scaled by
// gain and exposure (1 at their defaults): every pixel is its left and upper
// neighbour plus one, modulo 255, also in any crop of the frame.
bool isDiagonalRamp(const cv::Mat& image);

}  // namespace picksight::test
