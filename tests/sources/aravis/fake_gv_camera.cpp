// Fake GigE camera process for the Aravis tests (see fake_gv_camera.hpp).
#include "fake_gv_camera.hpp"

#include <csignal>
#include <thread>

#include <catch2/catch.hpp>

#include "picksight/sources/source.hpp"

namespace picksight::test {

using tool_support::Subprocess;

using namespace std::chrono_literals;

FakeGvCamera::FakeGvCamera() { start(); }

FakeGvCamera::~FakeGvCamera() { kill(); }

void FakeGvCamera::start() {
  REQUIRE_FALSE(running());
  process_ =
      std::make_unique<Subprocess>(std::vector<std::string>{ARV_FAKE_GV_CAMERA, "-i", "127.0.0.1"});
  // Ready when discovery finds it and its control channel answers: open it
  // the way the driver does. Generous: a loaded machine is slow to start it.
  auto source = video::makeSource(std::string("aravis:") + kDeviceId);
  REQUIRE(source);
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  bool opened = false;
  while (!opened && std::chrono::steady_clock::now() < deadline) {
    opened = static_cast<bool>((*source)->open());
    if (!opened) std::this_thread::sleep_for(100ms);
  }
  (*source)->close();
  REQUIRE(opened);
}

void FakeGvCamera::kill() {
  if (!process_) return;
  process_->kill(SIGKILL);
  process_->wait(5s);
  process_.reset();
}

bool isDiagonalRamp(const cv::Mat& image) {
  if (image.type() != CV_8UC1 || image.empty()) return false;
  const int origin = image.at<uint8_t>(0, 0);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (image.at<uint8_t>(y, x) != (origin + x + y) % 255) return false;
    }
  }
  return true;
}

}  // namespace picksight::test
