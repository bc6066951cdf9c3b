// Recognition benchmark: trains part models on synthetic parts (and on public
// silhouettes), recognizes them in scenes with exact ground truth, and prints
// precision and recall per type, position RMS (px) and angle RMS (deg), for
// separated and touching parts; then the time of the whole recognition of a
// 1920x1080 frame with 20 parts and 9 trained types beside a plain OpenCV
// pass on the same frames. Prints figures; never fails on them.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include "picksight/cli/command_line.hpp"
#include "picksight/codecs/codecs.hpp"

#include "opencv_baseline.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/common/text.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

namespace {
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;
using Clock = std::chrono::steady_clock;

constexpr double kMatchRadiusPx = 10;

// A ground-truth part of a benchmark scene.
struct Truth {
  std::string type;
  cv::Point2d centre;
  double angle_deg = 0;  // of the part, image axes
  bool touching = false;
};

struct Trained {
  pv::PartModel model;
  double truth_angle_deg = 0;  // of the training part: rotation 0
};

struct TypeStats {
  int truths = 0;
  int found = 0;     // truths matched by a result of their type
  int reported = 0;  // results of this type
  int correct = 0;   // results of this type on a truth of this type
  double pos2 = 0;
  double ang2 = 0;
  int angles = 0;
  double worst_pos = 0;
  double worst_ang = 0;
};

struct Tally {
  std::map<std::string, TypeStats> per_type;
  int mirror_confusions = 0;
};

std::vector<pv::Region> regionsOf(const cv::Mat& grey) {
  return pv::findRegions(pv::binarize(grey, {}), {}, grey);
}

// Scores one scene's results against its truth.
void score(const std::vector<Truth>& truth, const std::vector<pv::Match>& matches,
           const std::map<std::string, Trained>& trained, Tally& tally) {
  std::vector<bool> used(matches.size(), false);
  for (const auto& m : matches) tally.per_type[m.model->name].reported += 1;
  for (const auto& t : truth) {
    TypeStats& s = tally.per_type[t.type];
    s.truths += 1;
    int best = -1;
    double best_d = kMatchRadiusPx;
    for (size_t i = 0; i < matches.size(); ++i) {
      const double d = cv::norm(matches[i].centroid - t.centre);
      if (!used[i] && d < best_d) {
        best_d = d;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) continue;
    const pv::Match& m = matches[static_cast<size_t>(best)];
    used[static_cast<size_t>(best)] = true;
    if (m.model->name != t.type) {
      const bool mirror =
          (m.model->name + "_mirror" == t.type) || (t.type + "_mirror" == m.model->name);
      if (mirror) tally.mirror_confusions += 1;
      continue;
    }
    s.found += 1;
    s.correct += 1;
    s.pos2 += best_d * best_d;
    s.worst_pos = std::max(s.worst_pos, best_d);
    const double period = m.symmetry_deg;
    if (period > 0 && !std::isnan(t.angle_deg)) {
      const double expected = t.angle_deg - trained.at(t.type).truth_angle_deg;
      const double e = picksight::angleDiffDeg(m.angle_deg, expected, period);
      s.ang2 += e * e;
      s.angles += 1;
      s.worst_ang = std::max(s.worst_ang, e);
    }
  }
}

void print(const char* title, const Tally& tally) {
  std::printf("%s\n", title);
  std::printf("  %-18s %6s %6s %9s %7s %9s %9s %9s %9s\n", "type", "truth", "found", "precision",
              "recall", "pos RMS", "pos max", "ang RMS", "ang max");
  TypeStats all;
  for (const auto& [type, s] : tally.per_type) {
    const double precision = s.reported > 0 ? static_cast<double>(s.correct) / s.reported : 1.0;
    const double recall = s.truths > 0 ? static_cast<double>(s.found) / s.truths : 1.0;
    std::printf("  %-18s %6d %6d %9.3f %7.3f %9.4f %9.4f %9.4f %9.4f\n", type.c_str(), s.truths,
                s.found, precision, recall, s.found ? std::sqrt(s.pos2 / s.found) : 0.0,
                s.worst_pos, s.angles ? std::sqrt(s.ang2 / s.angles) : 0.0, s.worst_ang);
    all.truths += s.truths;
    all.found += s.found;
    all.reported += s.reported;
    all.correct += s.correct;
    all.pos2 += s.pos2;
    all.ang2 += s.ang2;
    all.angles += s.angles;
    all.worst_pos = std::max(all.worst_pos, s.worst_pos);
    all.worst_ang = std::max(all.worst_ang, s.worst_ang);
  }
  std::printf(
      "  %-18s %6d %6d %9.3f %7.3f %9.4f %9.4f %9.4f %9.4f   mirror confusions %d\n", "ALL",
      all.truths, all.found, all.reported ? static_cast<double>(all.correct) / all.reported : 1.0,
      all.truths ? static_cast<double>(all.found) / all.truths : 1.0,
      all.found ? std::sqrt(all.pos2 / all.found) : 0.0, all.worst_pos,
      all.angles ? std::sqrt(all.ang2 / all.angles) : 0.0, all.worst_ang, tally.mirror_confusions);
}

ps::SceneOptions sceneOptions(int width, int height, int parts, uint64_t seed,
                              std::vector<std::string> types) {
  ps::SceneOptions o = ps::sceneOptions(width, height, parts, seed, std::move(types));
  o.part_size = 120;
  o.noise_sigma = 3;
  o.uneven_light = true;
  o.blur_sigma = 0.7;
  return o;
}

std::map<std::string, Trained> trainSynthetic(const std::vector<std::string>& types) {
  std::map<std::string, Trained> trained;
  int id = 1;
  for (const auto& type : types) {
    const ps::SceneRenderer scene(
        sceneOptions(400, 400, 1, 1000 + static_cast<uint64_t>(id), {type}));
    auto outcome = pv::trainModel(scene.render(0), id, type);
    if (!outcome.ok()) {
      std::printf("  training %s failed: %s\n", type.c_str(), outcome.error().message.c_str());
      continue;
    }
    std::printf(
        "  trained %-15s area %8.1f holes %d order %2d symmetry %5.1f mirror-symmetric %d "
        "primitives %zu corners %zu hu-tol %.2f\n",
        type.c_str(), outcome.value().body.area, outcome.value().body.holes,
        outcome.value().orientation_order, outcome.value().symmetryDeg(),
        outcome.value().body.mirror_symmetric ? 1 : 0, outcome.value().loops[0].primitives.size(),
        outcome.value().corners.size(), outcome.value().body.hu_tolerance);
    trained[type] = Trained{outcome.value(), scene.truth()[0].angle_deg};
    ++id;
  }
  return trained;
}

std::vector<const pv::PartModel*> modelList(const std::map<std::string, Trained>& trained) {
  std::vector<const pv::PartModel*> models;
  for (const auto& [type, t] : trained) models.push_back(&t.model);
  return models;
}

void syntheticAccuracy(const std::map<std::string, Trained>& trained,
                       const std::vector<std::string>& types, int scenes, bool touching) {
  Tally tally;
  const auto models = modelList(trained);
  for (int i = 0; i < scenes; ++i) {
    auto o = sceneOptions(1280, 960, 12, 500 + static_cast<uint64_t>(i), types);
    o.touching = touching;
    const ps::SceneRenderer scene(o);
    std::vector<Truth> truth;
    for (const auto& t : scene.truth()) {
      if (touching && !t.touching) continue;
      truth.push_back({t.type, {t.x, t.y}, t.angle_deg, t.touching});
    }
    const cv::Mat grey = scene.render(static_cast<uint64_t>(i));
    const auto regions = regionsOf(grey);
    auto matches = pv::recognize(regions, models);
    if (touching) {
      // Only parts in contact count in this set: drop results on free parts.
      std::vector<pv::Match> kept;
      for (const auto& m : matches) {
        bool near_free = false;
        for (const auto& t : scene.truth()) {
          near_free = near_free || (!t.touching && std::hypot(m.centroid.x - t.x,
                                                              m.centroid.y - t.y) < kMatchRadiusPx);
        }
        if (!near_free) kept.push_back(m);
      }
      matches = kept;
    }
    score(truth, matches, trained, tally);
  }
  print(touching ? "synthetic, touching parts (pairs in contact, one merged blob each; only parts "
                   "in contact counted; located from their grey-level edges)"
                 : "synthetic, separated parts",
        tally);
}
// Public silhouettes (white on black, 128x128) made into dark parts on a lit,
// noisy background: drawn 4x larger, turned, mirrored or scaled there, and
// averaged down so edge pixels are partly covered. The truth centroid is the
// centroid of the 4x drawing.
constexpr int kSuper = 4;
// The drawings are 128 px with parts of 40 to 100 px: drawn at twice that,
// the size of the synthetic parts.
constexpr double kSilhouetteScale = 2.0;

struct Silhouette {
  std::string name;
  cv::Mat big;  // CV_8UC1 0/255 at kSuper x, smoothed edges
};

Silhouette loadSilhouette(const std::string& path, const std::string& name) {
  const cv::Mat img = picksight::codecs::imread(path, cv::IMREAD_GRAYSCALE);
  Silhouette s;
  s.name = name;
  if (img.empty()) return s;
  cv::Mat up;
  cv::resize(img, up, img.size() * kSuper, 0, 0, cv::INTER_LINEAR);
  cv::threshold(up, s.big, 127, 255, cv::THRESH_BINARY);
  return s;
}

// The silhouette turned by `deg` (image axes), mirrored and scaled, on a
// square patch whose centre is the patch's centre; returns it with the
// centroid of the drawing within the patch.
cv::Mat posedSilhouette(const Silhouette& s, double deg, bool mirrored, double scale,
                        cv::Point2d* centroid) {
  cv::Mat src = s.big;
  if (mirrored) {
    cv::Mat flipped;  // never in place: src shares the silhouette's pixels
    cv::flip(s.big, flipped, 1);
    src = flipped;
  }
  const int side = static_cast<int>(std::ceil(std::hypot(src.cols, src.rows) * scale)) + 8;
  cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(0.5f * src.cols, 0.5f * src.rows), -deg, scale);
  m.at<double>(0, 2) += 0.5 * side - 0.5 * src.cols;
  m.at<double>(1, 2) += 0.5 * side - 0.5 * src.rows;
  cv::Mat patch;
  cv::warpAffine(src, patch, m, cv::Size(side, side), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(0));
  cv::threshold(patch, patch, 127, 255, cv::THRESH_BINARY);
  const cv::Moments mm = cv::moments(patch, true);
  *centroid = mm.m00 > 0 ? cv::Point2d(mm.m10 / mm.m00, mm.m01 / mm.m00)
                         : cv::Point2d(0.5 * side, 0.5 * side);
  return patch;
}

// Dark parts where `canvas` (kSuper x) is set, on a lit background with a
// light gradient and sensor noise.
cv::Mat renderCanvas(const cv::Mat& canvas, uint64_t seed) {
  cv::Mat coverage;
  cv::resize(canvas, coverage, canvas.size() / kSuper, 0, 0, cv::INTER_AREA);
  coverage.convertTo(coverage, CV_32F, 1.0 / 255);
  cv::Mat grey(coverage.size(), CV_32F);
  for (int y = 0; y < grey.rows; ++y) {
    for (int x = 0; x < grey.cols; ++x) {
      const double light =
          1.0 + 0.15 * (x - 0.5 * grey.cols) / grey.cols - 0.1 * (y - 0.5 * grey.rows) / grey.rows;
      grey.at<float>(y, x) = static_cast<float>(light * (200 - 155 * coverage.at<float>(y, x)));
    }
  }
  cv::Mat noise(grey.size(), CV_32F);
  cv::RNG rng(seed | 1);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::Mat out;
  cv::Mat(grey + noise).convertTo(out, CV_8U);
  return out;
}

void silhouetteAccuracy(const std::string& data_dir, int scenes) {
  // Trained: the first drawing of six Kimia-99 classes. Among the others:
  // every other Kimia-99 drawing, the trained ones mirrored (a different
  // part unless the model finds itself mirror-symmetric) and scaled by 0.8.
  const std::string dir = data_dir + "/shapes/kimia99/";
  std::vector<Silhouette> trained_shapes;
  std::vector<Silhouette> others;
  for (int c = 1; c <= 9; ++c) {
    for (int i = 1; i <= 11; ++i) {
      const std::string name = "kimia" + std::to_string(c) + "_" + std::to_string(i);
      Silhouette s = loadSilhouette(
          dir + "trainimage" + std::to_string(c) + "_" + std::to_string(i) + ".png", name);
      if (s.big.empty()) {
        std::printf("silhouettes: cannot read %s (set --data DIR)\n", (dir + name).c_str());
        return;
      }
      (i == 1 && c <= 6 ? trained_shapes : others).push_back(std::move(s));
    }
  }
  std::map<std::string, Trained> trained;
  int id = 100;
  for (const auto& s : trained_shapes) {
    cv::Point2d c;
    const cv::Mat patch = posedSilhouette(s, 0, false, kSilhouetteScale, &c);
    cv::Mat canvas(400 * kSuper, 400 * kSuper, CV_8UC1, cv::Scalar(0));
    const cv::Point at(200 * kSuper - patch.cols / 2, 200 * kSuper - patch.rows / 2);
    patch.copyTo(canvas(cv::Rect(at, patch.size())));
    auto outcome = pv::trainModel(renderCanvas(canvas, static_cast<uint64_t>(id)), id, s.name);
    ++id;
    if (!outcome.ok()) {
      std::printf("  training %s failed: %s\n", s.name.c_str(), outcome.error().message.c_str());
      continue;
    }
    std::printf(
        "  trained %-10s area %8.1f holes %d order %2d symmetry %5.1f mirror-symmetric %d\n",
        s.name.c_str(), outcome.value().body.area, outcome.value().body.holes,
        outcome.value().orientation_order, outcome.value().symmetryDeg(),
        outcome.value().body.mirror_symmetric ? 1 : 0);
    trained[s.name] = Trained{outcome.value(), 0.0};
  }
  const auto models = modelList(trained);
  Tally tally;
  std::mt19937_64 rng(99);
  const auto uniform = [&](double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
  };
  for (int n = 0; n < scenes; ++n) {
    const cv::Size size(1920, 1080);
    cv::Mat canvas(size * kSuper, CV_8UC1, cv::Scalar(0));
    std::vector<Truth> truth;
    std::vector<std::pair<cv::Point2d, double>> placed;  // centre, radius (px)
    for (int k = 0; k < 10; ++k) {
      const int pick = static_cast<int>(rng() % 4);
      const Silhouette* s = nullptr;
      bool mirrored = false;
      double scale = 1.0;
      std::string type;
      if (pick <= 1) {
        s = &trained_shapes[rng() % trained_shapes.size()];
        mirrored = pick == 1;
        const bool same = !mirrored || trained.at(s->name).model.body.mirror_symmetric;
        type = same ? s->name : s->name + "_mirror";
      } else if (pick == 2) {
        s = &others[rng() % others.size()];
        type = "other";
      } else {
        s = &trained_shapes[rng() % trained_shapes.size()];
        scale = 0.8;
        type = s->name + "_scaled";
      }
      const double deg = uniform(0, 360);
      cv::Point2d c;
      const cv::Mat patch = posedSilhouette(*s, deg, mirrored, scale * kSilhouetteScale, &c);
      double radius = 0;  // of the drawing about the patch centre, pixels
      {
        std::vector<cv::Point> ink;
        cv::findNonZero(patch, ink);
        for (const auto& p : ink)
          radius = std::max(radius, std::hypot(p.x - 0.5 * patch.cols, p.y - 0.5 * patch.rows));
        radius = radius / kSuper + 2;
      }
      for (int attempt = 0; attempt < 200; ++attempt) {
        const cv::Point2d centre(uniform(radius + 4, size.width - radius - 4),
                                 uniform(radius + 4, size.height - radius - 4));
        const bool free = std::all_of(placed.begin(), placed.end(), [&](const auto& p) {
          return cv::norm(p.first - centre) > p.second + radius + 6;
        });
        if (!free) continue;
        placed.push_back({centre, radius});
        const cv::Point at(static_cast<int>(std::lround(centre.x * kSuper)) - patch.cols / 2,
                           static_cast<int>(std::lround(centre.y * kSuper)) - patch.rows / 2);
        // The patch may reach past the canvas where it holds no ink.
        const cv::Rect box = cv::Rect(at, patch.size()) & cv::Rect(cv::Point(0, 0), canvas.size());
        cv::Mat dst = canvas(box);
        cv::max(dst, patch(box - at), dst);
        const cv::Point2d hi(at.x + c.x, at.y + c.y);
        Truth t{type, {(hi.x + 0.5) / kSuper - 0.5, (hi.y + 0.5) / kSuper - 0.5}, deg, false};
        // A mirror-symmetric part seen mirrored has a rotation that depends
        // on where its mirror axis lies: only its position is scored.
        if (mirrored) t.angle_deg = std::nan("");
        truth.push_back(t);
        break;
      }
    }
    const cv::Mat grey = renderCanvas(canvas, 1000 + static_cast<uint64_t>(n));
    score(truth, pv::recognize(regionsOf(grey), models), trained, tally);
  }
  // Distractors are not types: only what was reported on them counts (as
  // precision lost by the model reported).
  for (auto it = tally.per_type.begin(); it != tally.per_type.end();) {
    it = trained.count(it->first) ? std::next(it) : tally.per_type.erase(it);
  }
  print(
      "silhouettes (Kimia-99: 6 trained among 93 others, mirrored and 0.8x copies; rotated, noisy, "
      "uneven light)",
      tally);
}

// The plain OpenCV passes the recognition is measured against (see
// opencv_baseline.hpp). Functions of their own so that a profiler can tell
// their cost apart.
__attribute__((noinline)) double plainPass(const cv::Mat& grey) {
  return picksight::bench::competentOpenCvPass(grey);
}
__attribute__((noinline)) double labellingPass(const cv::Mat& grey) {
  return picksight::bench::labellingOpenCvPass(grey);
}

// Whole recognition (binarize + regions + recognize with 9 models) beside
// the plain OpenCV pass, on the same 1920x1080 frames, 20 parts each.
__attribute__((noinline)) void speed(const std::map<std::string, Trained>& all, int rounds) {
  std::map<std::string, Trained> nine;
  for (const auto& [type, t] : all) {
    if (nine.size() < 9) nine[type] = t;
  }
  std::vector<std::string> types;
  for (const auto& [type, t] : nine) types.push_back(type);
  const auto models = modelList(nine);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 8; ++i) {
    frames.push_back(
        ps::SceneRenderer(sceneOptions(1920, 1080, 20, 900 + static_cast<uint64_t>(i), types))
            .render(0));
  }
  const auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  std::vector<double> plain, labelling, binarize, regions, recognize, whole;
  size_t found = 0;
  double sink = 0;
  // At least 200 frames of each pass, for a p99 by nearest rank; the pass
  // that runs first turns from frame to frame.
  const int enough = std::max(
      rounds, (200 + static_cast<int>(frames.size()) - 1) / static_cast<int>(frames.size()));
  size_t turn = 0;
  for (int r = 0; r < enough; ++r) {
    for (const auto& grey : frames) {
      const auto ours = [&] {
        const auto t0 = Clock::now();
        const cv::Mat mask = pv::binarize(grey, {});
        const auto t1 = Clock::now();
        const auto regs = pv::findRegions(mask, {}, grey);
        const auto t2 = Clock::now();
        const auto matches = pv::recognize(regs, models);
        const auto t3 = Clock::now();
        found += matches.size();
        binarize.push_back(ms(t0, t1));
        regions.push_back(ms(t1, t2));
        recognize.push_back(ms(t2, t3));
      };
      picksight::bench::timeInTurn<3>(
          turn++, {[&] { sink += plainPass(grey); }, [&] { sink += labellingPass(grey); }, ours},
          {&plain, &labelling, &whole});
    }
  }
  const auto median = [](const std::vector<double>& v) {
    return picksight::bench::nearestRank(v, 50);
  };
  const auto p99 = [](const std::vector<double>& v) {
    return picksight::bench::nearestRank(v, 99);
  };
  const double base = median(plain);
  std::printf(
      "speed: 1920x1080, 20 parts, %zu trained types, %zu frames x %d rounds, passes in turns "
      "(ms: median, p99 by nearest rank; ratio of medians to the plain pass)\n",
      nine.size(), frames.size(), enough);
  std::printf("  %-52s %7.2f %7.2f   1.00x\n", "plain OpenCV pass (Otsu+findContours+moments)",
              base, p99(plain));
  std::printf("  %-52s %7.2f %7.2f   %.2fx\n", "PickSight whole recognition", median(whole),
              p99(whole), median(whole) / base);
  std::printf("  %-52s %7.2f\n", "  binarize (adaptive)", median(binarize));
  std::printf("  %-52s %7.2f\n", "  regions (contours, grey-level moments)", median(regions));
  std::printf("  %-52s %7.2f\n", "  recognize (gates, rotations, verification)", median(recognize));
  std::printf("  %-52s %7.2f   %.2fx\n", "PickSight whole recognition, best of all rounds",
              *std::min_element(whole.begin(), whole.end()),
              *std::min_element(whole.begin(), whole.end()) /
                  *std::min_element(plain.begin(), plain.end()));
  std::printf("  %-52s %7.2f %7.2f   %.2fx\n", "old pass, with CC labels (Otsu+CC+findContours)",
              median(labelling), p99(labelling), median(labelling) / base);
  std::printf("  (%.1f parts recognized per frame%s)\n",
              static_cast<double>(found) / static_cast<double>(whole.size()), sink > 0 ? "" : "!");
}
}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  int scenes = 10;
  int rounds = 10;
  bool accuracy = true;  // --accuracy 0: the speed figures alone (profiling)
  std::string data_dir = PICKSIGHT_TEST_DATA_DIR;
  int threads = -1;
  picksight::cli::App app(
      "Recognition on synthetic parts and silhouettes: precision, recall, "
      "accuracy and speed.",
      "picksight-bench-recognition");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--scenes", scenes, "scenes per accuracy figure")
      ->check(picksight::cli::range(1, 1000))
      ->showDefault();
  app.addOption("--rounds", rounds, "timed passes per speed figure")
      ->check(picksight::cli::range(1, 1000))
      ->showDefault();
  app.addOption("--accuracy", accuracy, "0: the speed figures alone (profiling)")->showDefault();
  app.addOption("--data", data_dir, "test data directory (shapes/...)")->showDefault();
  // 1: every instruction on the calling thread, where a profiler charges it
  // to the step that asked for it.
  app.addOption("--threads", threads, "OpenCV's threads (default: every core)")
      ->check(picksight::cli::range(1, 256));
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  if (threads > 0) cv::setNumThreads(threads);
  const auto& types = ps::allPartTypes();
  std::printf(
      "training on one synthetic part of each of %zu types (120 px, noise 3, blur 0.7, uneven "
      "light)\n",
      types.size());
  const auto trained = trainSynthetic(types);
  if (accuracy) {
    syntheticAccuracy(trained, types, scenes, false);
    syntheticAccuracy(trained, types, scenes, true);
    silhouetteAccuracy(data_dir, scenes);
  }
  speed(trained, rounds);
  return 0;
}
