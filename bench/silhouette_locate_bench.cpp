// LOCATE ALL and LOCATE <type> over the robot protocol on everyday-object
// silhouette scenes: the recognition goal's figure (a robot's request to its reply, fresh frame
// included) taken through the real processes, where picksight-bench-silhouettes
// times the vision pass in process. The scenes (1920x1080, 15 trained types, 20
// parts with mirrored and scaled distractors) are rendered to lossless PGM files
// and served by the video server's directory camera, one per trigger; the types
// are trained in process and stored as the vision app's model files. Printed
// beside the plain OpenCV pass on the same frames, timed in this process between
// the requests. Never fails on the figures.
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench_cell.hpp"
#include "opencv_baseline.hpp"
#include "picksight/common/command_line.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/training/part_training.hpp"
#include "silhouette_types.hpp"

namespace {
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// The binarization window for parts up to 350 px (the vision app's --window).
constexpr int kWindow = 400;

// Parts in a LOCATE ALL reply ("OK <n> type x y rz ..."); -1 when not OK.
int partsIn(const std::string& reply) {
  std::istringstream in(reply);
  std::string ok;
  int n = -1;
  if (!(in >> ok >> n) || ok != "OK") return -1;
  return n;
}
}  // namespace

int main(int argc, char** argv) {
  int scenes = 3;
  int requests = 150;
  std::string data_dir = PICKSIGHT_TEST_DATA_DIR;
  std::vector<std::string> which = {"separated", "touching", "overlapping"};
  CLI::App app("LOCATE ALL over the robot protocol on silhouette scenes, beside plain OpenCV.",
               argc > 0 ? argv[0] : "picksight-bench-silhouette-locate");
  app.set_help_flag("-h,--help", "print this help");
  app.add_option("--scenes", scenes, "scenes per arrangement (frames the camera cycles through)")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  app.add_option("--requests", requests, "LOCATE ALL requests timed per arrangement")
      ->check(CLI::Range(10, 100000))
      ->capture_default_str();
  app.add_option("--data", data_dir, "test data directory (shapes/...)")->capture_default_str();
  app.add_option("--arrangements", which, "separated, touching, overlapping")
      ->check(CLI::IsMember({"separated", "touching", "overlapping"}));
  if (auto exit_code = picksight::parseMainArgs(app, argc, argv)) return *exit_code;

  const auto& specs = picksight::bench::silhouetteTypeSpecs();
  std::vector<ps::SilhouetteType> types;
  if (!picksight::bench::loadSilhouetteTypes(specs, data_dir, &types)) return 1;
  const std::string cell_dir = picksight::bench::makeDataDir();
  if (cell_dir.empty()) return 1;

  // One model per type (types 1..15), trained on the part alone, as the
  // recognition benchmark trains them, and stored where the vision app
  // loads its models from.
  const ps::SilhouetteSceneOptions look;
  pv::TrainOptions train;
  train.binarize.adaptive_window = kWindow;
  picksight::store::ModelLibrary library(cell_dir + "/models");
  std::vector<bool> chiral;
  for (size_t i = 0; i < types.size(); ++i) {
    const int side = static_cast<int>(specs[i].size_px * 1.5) + 300;
    const cv::Mat image = ps::renderSilhouetteAlone(types[i], side, look, 7 + i, nullptr,
                                                    picksight::bench::kTrainAngleDeg);
    auto model = pv::trainModel(image, static_cast<int>(i) + 1, specs[i].name, train);
    if (!model.ok()) {
      std::fprintf(stderr, "training %s failed: %s\n", specs[i].name.c_str(),
                   model.error().message.c_str());
      return 1;
    }
    chiral.push_back(!model.value().body.mirror_symmetric);
    if (auto stored = library.store(model.value()); !stored.ok()) {
      std::fprintf(stderr, "storing %s: %s\n", specs[i].name.c_str(),
                   stored.error().message.c_str());
      return 1;
    }
  }
  std::printf("trained %zu types into %s/models\n", types.size(), cell_dir.c_str());
  std::printf("\n  %-12s %-9s %8s %8s %8s %8s   %-14s %s\n", "scenes", "LOCATE", "median", "p99",
              "min", "OpenCV", "ratio medians", "parts per reply (truth)");

  for (const auto& name : which) {
    const ps::Arrangement arrangement = name == "separated"  ? ps::Arrangement::kSeparated
                                        : name == "touching" ? ps::Arrangement::kTouching
                                                             : ps::Arrangement::kOverlapping;
    // The frames, lossless, named in the order the camera serves them.
    const std::string frames_dir = cell_dir + "/frames_" + name;
    if (::mkdir(frames_dir.c_str(), 0755) != 0) {
      std::perror(frames_dir.c_str());
      return 1;
    }
    std::vector<cv::Mat> frames;
    size_t true_parts = 0;
    for (int n = 0; n < scenes; ++n) {
      ps::SilhouetteSceneOptions o = look;
      o.arrangement = arrangement;
      o.seed = 1000 * (static_cast<uint64_t>(arrangement) + 1) + static_cast<uint64_t>(n);
      const ps::SilhouetteScene scene(types, chiral, o);
      for (const auto& t : scene.truth()) true_parts += t.kind == ps::PartKind::kTrue;
      frames.push_back(scene.render(0));
      char file[64];
      std::snprintf(file, sizeof file, "/%04d.pgm", n);
      if (!cv::imwrite(frames_dir + file, frames.back())) {
        std::fprintf(stderr, "cannot write %s%s\n", frames_dir.c_str(), file);
        return 1;
      }
    }

    auto server = picksight::bench::startVideoServer("cam0=dir:" + frames_dir);
    if (!server) {
      std::fprintf(stderr, "the video server did not start\n");
      return 1;
    }
    auto vision =
        picksight::bench::startVision(*server, cell_dir, {"--window", std::to_string(kWindow)});
    if (!vision) {
      std::fprintf(stderr, "the vision app did not start\n");
      return 1;
    }
    // Warm-up: every frame once, caches, connections.
    for (int i = 0; i < 2 * scenes; ++i) (void)vision->robot.request("LOCATE ALL", 10s);
    // LOCATE ALL (every type, one pass) and LOCATE <type> (how a robot
    // asks for the part it picks next: types 1..15 in turn), alternated.
    struct Timed {
      std::vector<double> ms;
      double parts = 0;
      int failures = 0;
    };
    Timed all;
    Timed one;
    std::vector<double> plain;
    double sink = 0;
    const auto timeRequest = [&](const std::string& request, Timed* timed) {
      const auto t0 = Clock::now();
      const auto reply = vision->robot.request(request, 10s);
      timed->ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      const int n = reply ? partsIn(*reply) : -1;
      if (n < 0) {
        if (++timed->failures == 1)
          std::cerr << request << " -> " << (reply ? *reply : "no reply") << "\n";
        return;
      }
      timed->parts += n;
    };
    for (int i = 0; i < requests; ++i) {
      // Alternated with the requests: the same machine's state for both.
      const cv::Mat& frame = frames[static_cast<size_t>(i % scenes)];
      const auto p0 = Clock::now();
      sink += picksight::bench::competentOpenCvPass(frame);
      plain.push_back(std::chrono::duration<double, std::milli>(Clock::now() - p0).count());
      timeRequest("LOCATE ALL", &all);
      timeRequest("LOCATE " + std::to_string(1 + i % static_cast<int>(types.size())), &one);
    }
    const double plain_median = picksight::bench::nearestRank(plain, 50);
    const auto row = [&](const std::string& label, const char* kind, const Timed& t, double truth) {
      const double median = picksight::bench::nearestRank(t.ms, 50);
      const int answered = requests - t.failures;
      std::printf("  %-12s %-9s %8.2f %8.2f %8.2f %8.2f   %6.2fx         %.1f (%.1f)%s\n",
                  label.c_str(), kind, median, picksight::bench::nearestRank(t.ms, 99),
                  picksight::bench::nearestRank(t.ms, 0), plain_median,
                  plain_median > 0 ? median / plain_median : 0.0,
                  answered > 0 ? t.parts / answered : 0.0, truth,
                  t.failures ? (" " + std::to_string(t.failures) + " failed").c_str() : "");
    };
    row(name, "ALL", all, static_cast<double>(true_parts) / scenes);
    row("", "<type>", one,
        static_cast<double>(true_parts) / scenes / static_cast<double>(types.size()));
    if (sink == 0) std::printf("!");
  }
  std::printf(
      "\n  ms; LOCATE round trip over TCP, fresh frame (a trigger, the next file read and\n"
      "  published, the vision pass, the reply): ALL with every model in one pass, <type>\n"
      "  with one type's model (types in turn; truth: the mean per type), the two alternated;\n"
      "  OpenCV: Otsu + findContours + moments on the same frames in this process.\n"
      "  Goal: median <= 10 ms, p99 <= 20 ms.\n");
  std::error_code ec;
  std::filesystem::remove_all(cell_dir, ec);
  return 0;
}
