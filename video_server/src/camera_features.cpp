// The camera's requests that run on its acquisition thread, between grabs:
// features by name, the feature list in slices, the simulated robot.
#include "picksight/video_server/camera.hpp"

#include <algorithm>
#include <future>

namespace picksight::video {
namespace {
constexpr std::chrono::milliseconds kCommandTimeout{5000};
// The longest a feature listing holds the acquisition thread at a time.
constexpr std::chrono::milliseconds kMinFeatureSlice{10};
constexpr std::chrono::milliseconds kMaxFeatureSlice{100};
}  // namespace

template <typename T>
Result<T> Camera::onAcquisitionThread(std::function<Result<T>(Source&, bool open)> fn) {
  auto promise = std::make_shared<std::promise<Result<T>>>();
  auto future = promise->get_future();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // open_ is read on the acquisition thread when the command runs.
    commands_.push_back([this, fn, promise] { promise->set_value(fn(*source_, open_)); });
    if (!thread_.joinable()) {
      // No acquisition thread: nobody else touches the source.
      Command command = std::move(commands_.back());
      commands_.pop_back();
      command();
      return future.get();
    }
  }
  wake_.notify_all();
  if (future.wait_for(kCommandTimeout) != std::future_status::ready) {
    return makeError(SourceErrc::kTimeout,
                     "camera " + config_.name + " is busy: no answer within 5 s");
  }
  return future.get();
}

Result<std::vector<Feature>> Camera::features() {
  // Names first, then the features a slice at a time: a camera with
  // hundreds of them (each read a register round trip over GigE) grabs
  // between slices and keeps its frame rate, where one pass would hold its
  // acquisition thread for seconds.
  auto names = onAcquisitionThread<std::vector<std::string>>(
      [](Source& s, bool open) -> Result<std::vector<std::string>> {
        if (!open) return makeError(SourceErrc::kUnavailable, "camera is not connected");
        return s.featureNames();
      });
  if (!names) return names.error();
  const auto shared = std::make_shared<const std::vector<std::string>>(std::move(*names));
  const std::chrono::milliseconds slice = featureSlice();
  // Shared: a slice that outlived its caller's patience still has somewhere to write.
  auto out = std::make_shared<std::vector<Feature>>();
  size_t next = 0;
  while (next < shared->size()) {
    auto read = onAcquisitionThread<size_t>(
        [out, shared, next, slice](Source& s, bool open) -> Result<size_t> {
          if (!open) return makeError(SourceErrc::kUnavailable, "camera is not connected");
          const auto until = std::chrono::steady_clock::now() + slice;
          size_t i = next;
          do {
            if (auto f = s.listedFeature((*shared)[i])) out->push_back(std::move(*f));
            ++i;
          } while (i < shared->size() && std::chrono::steady_clock::now() < until);
          return i;
        });
    if (!read) return read.error();
    next = *read;
  }
  return std::move(*out);
}

std::chrono::milliseconds Camera::featureSlice() const {
  std::lock_guard<std::mutex> lock(mutex_);
  // Half a frame period, so that the frame due next still comes on time;
  // between bounds that keep a slow camera's listing from taking minutes
  // and a fast one's from crawling.
  const auto half_period =
      std::chrono::milliseconds(static_cast<long long>(500.0 / std::max(fps_, 1e-3)));
  if (mode_ != AcquisitionMode::kFreeRun) return kMaxFeatureSlice;
  return std::clamp(half_period, kMinFeatureSlice, kMaxFeatureSlice);
}

Result<Feature> Camera::feature(const std::string& name) {
  return onAcquisitionThread<Feature>([name](Source& s, bool open) -> Result<Feature> {
    if (!open) return makeError(SourceErrc::kUnavailable, "camera is not connected");
    return s.feature(name);
  });
}

Result<Feature> Camera::setFeature(const std::string& name, const std::string& value) {
  return onAcquisitionThread<Feature>([name, value](Source& s, bool open) -> Result<Feature> {
    if (!open) return makeError(SourceErrc::kUnavailable, "camera is not connected");
    if (auto ok = s.setFeature(name, value); !ok) return ok.error();
    return s.feature(name);
  });
}

Result<SimulatedRobot> Camera::moveTarget(std::optional<cv::Point2d> at_mm) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!robot_) return makeError(SourceErrc::kNotSupported, "this camera has no simulated robot");
  }
  // A closed synthetic source keeps the position for when it opens again.
  auto robot = onAcquisitionThread<SimulatedRobot>(
      [at_mm](Source& s, bool /*open*/) { return s.moveTarget(at_mm); });
  if (robot) {
    std::lock_guard<std::mutex> lock(mutex_);
    robot_ = *robot;
  }
  return robot;
}

Result<SimulatedRobot> Camera::simulatedRobot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!robot_) return makeError(SourceErrc::kNotSupported, "this camera has no simulated robot");
  return *robot_;
}

}  // namespace picksight::video
