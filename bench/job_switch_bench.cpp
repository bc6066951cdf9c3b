// JOB LOAD with 16 trained types, each with its teach image (a noisy
// 1920x1080 frame shrunk to 1024 px, as LEARN keeps it): the time from the
// request line to the reply in one cell (VisionCell over a still camera),
// alternating two jobs, on the disk the data directory is on (fsyncs
// included: on tmpfs they cost nothing, so the file system is printed).
// The first load of each job reads and checks its file; later ones find
// it parsed (JobSwitch keeps the last few), so both are printed.
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "picksight/app/vision_cell.hpp"
#include "picksight/cli/command_line.hpp"

namespace {
using namespace picksight;
using Clock = std::chrono::steady_clock;

constexpr int kTypes = 16;

// Sixteen dark parts of different shapes (width, height and hole vary) on
// a light surface with sensor-like noise, in a 4 x 4 grid of cells.
cv::Mat scene() {
  cv::Mat image(1080, 1920, CV_8UC1, cv::Scalar(200));
  for (int k = 0; k < kTypes; ++k) {
    const cv::Point centre(240 + 480 * (k % 4), 135 + 270 * (k / 4));
    const cv::Size half(60 + 12 * k, 30 + 4 * (k % 5));
    cv::rectangle(image, centre - cv::Point(half), centre + cv::Point(half), cv::Scalar(45),
                  cv::FILLED);
    if (k % 2 == 1) cv::circle(image, centre + cv::Point(half.width / 2, 0), 8 + k / 2, 200, -1);
  }
  cv::Mat noise(image.size(), CV_8UC1);
  cv::randn(noise, 0, 4);
  cv::add(image, noise, image);
  return image;
}

std::string fileSystem(const std::string& path) {
  struct statfs s {};
  if (::statfs(path.c_str(), &s) != 0) return "?";
  switch (static_cast<unsigned long>(s.f_type)) {
    case 0x01021994:
      return "tmpfs";
    case 0xEF53:
      return "ext4";
    case 0x794c7630:
      return "overlayfs";
    case 0x58465342:
      return "xfs";
    case 0x9123683E:
      return "btrfs";
    default:
      return "type 0x" + std::to_string(s.f_type);
  }
}

bool ok(const std::string& reply, const std::string& request) {
  if (reply.rfind("OK", 0) == 0) return true;
  std::fprintf(stderr, "%s: %s\n", request.c_str(), reply.c_str());
  return false;
}
}  // namespace

int main(int argc, char** argv) {
  // Where the data directory goes: the working directory by default (a
  // real disk, unlike /tmp on many machines).
  std::string parent = ".";
  int rounds = 40;
  picksight::cli::App app("JOB LOAD of two jobs of 16 trained types, alternately, in one cell.",
                          "picksight-bench-job-switch");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--dir", parent,
                "where the benchmark's data directory is made (and removed): the disk measured")
      ->typeName("DIR")
      ->check(picksight::cli::existingDirectory())
      ->showDefault();
  app.addOption("--loads", rounds, "timed loads after the first of each job")
      ->typeName("N")
      ->check(picksight::cli::range(1, 100000))
      ->showDefault();
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  const std::string dir = parent + "/picksight-job-bench-" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  int status = 0;
  {
    app::VisionCell cell(dir, std::make_unique<link::StillCamera>(scene()), cell::VisionOptions{});
    for (const auto& problem : cell.load()) std::fprintf(stderr, "%s\n", problem.c_str());
    for (int k = 0; k < kTypes; ++k) {
      const int x = 480 * (k % 4), y = 270 * (k / 4);
      const std::string learn = "LEARN " + std::to_string(k + 1) + " part" + std::to_string(k + 1) +
                                " AT " + std::to_string(x) + " " + std::to_string(y) + " 480 270";
      if (!ok(cell.handle(learn), learn)) return 1;
    }
    if (!ok(cell.handle("JOB SAVE a"), "JOB SAVE a")) return 1;
    if (!ok(cell.handle("TOLERANCE 1 area_tolerance 0.2"), "TOLERANCE")) return 1;
    if (!ok(cell.handle("VISION min_area 500"), "VISION")) return 1;
    if (!ok(cell.handle("JOB SAVE b"), "JOB SAVE b")) return 1;
    const auto bytes = std::filesystem::file_size(dir + "/jobs/a.job");
    std::vector<double> first, ms;
    for (int r = 0; r < rounds + 2; ++r) {
      const std::string request = r % 2 == 0 ? "JOB LOAD a" : "JOB LOAD b";
      const auto start = Clock::now();
      const std::string reply = cell.handle(request);
      (r < 2 ? first : ms)
          .push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
      if (!ok(reply, request)) status = 1;
    }
    std::sort(ms.begin(), ms.end());
    std::printf("JOB LOAD, %d types with teach images, job file %.1f MB, %s (%s)\n", kTypes,
                bytes / 1e6, dir.c_str(), fileSystem(dir).c_str());
    std::printf("  first load of each job (file read and checked): %.1f ms, %.1f ms\n", first[0],
                first[1]);
    std::printf(
        "  %d switches after: median %.1f ms, p90 %.1f ms, max %.1f ms "
        "(goal: median < 100 ms)\n",
        rounds, ms[ms.size() / 2], ms[ms.size() * 9 / 10], ms.back());
  }
  std::filesystem::remove_all(dir);
  return status;
}
