// Recognition benchmark on everyday-object silhouettes (Tari-1000, Kimia-99)
// and a few of the repository's own shapes: 15 trained types rendered as a
// camera sees them at 1920x1080, 20 parts per scene with mirrored and scaled
// distractors, separated, in touching pairs and in overlapping pairs. Prints
// per shape family the LOCATE-equivalent time (binarize, regions, recognize
// with every model) beside a plain OpenCV pass on the same frames,
// precision, recall and the position and angle errors. Never fails on them.
// --types trains any other drawings instead (shapes never tuned on);
// --from-edges locates every part the way touching parts are; --models
// trains fewer types, or more (drawings never put in a scene), for what
// LOCATE ALL costs against the number of types a cell has taught.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"

#include "opencv_baseline.hpp"
#include "picksight/cli/command_line.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"
#include "silhouette_types.hpp"

namespace {
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;
using picksight::bench::TypeSpec;
using Clock = std::chrono::steady_clock;
using Ms = std::chrono::duration<double, std::milli>;

// CPU time of the whole process (every thread), ms: the work a stage does,
// which a busy machine does not inflate the way it does the wall time.
double cpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// A result this close to a drawn part's centroid is about that part.
constexpr double kMatchRadiusPx = 12;

struct Stats {
  int truths = 0;
  int found = 0;
  int reported = 0;
  int correct = 0;
  double pos2 = 0;
  double mask_pos2 = 0;  // against the drawn mask's centroid
  double ang2 = 0;
  int angles = 0;
  double worst_pos = 0;
  double worst_ang = 0;
  void add(const Stats& o) {
    truths += o.truths;
    found += o.found;
    reported += o.reported;
    correct += o.correct;
    pos2 += o.pos2;
    mask_pos2 += o.mask_pos2;
    ang2 += o.ang2;
    angles += o.angles;
    worst_pos = std::max(worst_pos, o.worst_pos);
    worst_ang = std::max(worst_ang, o.worst_ang);
  }
};

struct Confusions {
  int mirror = 0;     // a model reported on its own mirror image
  int size = 0;       // on a 0.8x or 1.25x copy of itself
  int other = 0;      // on another type, or a distractor of another type
  int nothing = 0;    // where no part is
  int duplicate = 0;  // twice on one part
};

struct Tally {
  std::vector<Stats> per_type;
  Confusions confusions;
  std::vector<double> ours_ms;
  std::vector<double> plain_ms;
  // The vision pass's stages, per frame: where its time goes.
  std::vector<double> binarize_ms;
  std::vector<double> regions_ms;
  std::vector<double> recognize_ms;
  std::vector<double> binarize_cpu_ms;  // the same, CPU time of all threads
  std::vector<double> regions_cpu_ms;
  std::vector<double> recognize_cpu_ms;
  int parts = 0;
  int distractors = 0;
  int frames = 0;
  // --scaling: recognition's time on N cores, simulated (kWorkers), per frame.
  std::vector<std::vector<double>> simulated_ms;
  std::vector<double> costliest_share;  // the costliest region's share of the work
};

// The core counts --scaling simulates.
constexpr int kWorkers[] = {1, 2, 4, 8, 16};

// The time `workers` cores take for regions costing `ms` each, dealt in
// their order to the first core free (as a work queue deals them; no cost
// of dealing counted): what recognition on that many cores can reach.
double makespanMs(const std::vector<double>& ms, int workers) {
  std::vector<double> free_at(static_cast<size_t>(workers), 0.0);
  for (const double m : ms) {
    auto first = std::min_element(free_at.begin(), free_at.end());
    *first += m;
  }
  return *std::max_element(free_at.begin(), free_at.end());
}

// Where a part's model reference point truly lies: the drawn mask's centroid
// plus, turned with the part, the offset from it to the reference point the
// model was trained with (`reference`, per type). The two differ where the
// drawing has detail finer than the camera resolves (a tail tip a pixel
// wide): the image, and so the model, lacks it, and the robot is taught
// its grasp on the model.
cv::Point2d referenceOf(const ps::SilhouettePart& t, const std::vector<cv::Point2d>& reference) {
  const cv::Point2d o = reference[t.type];
  const double a = t.angle_deg * M_PI / 180.0;
  return t.centre +
         cv::Point2d(o.x * std::cos(a) - o.y * std::sin(a), o.x * std::sin(a) + o.y * std::cos(a));
}

// Prints a false report: what was reported, and what is drawn there.
void listFalse(const char* what, const pv::Match& m, const ps::SilhouettePart* t,
               const std::vector<TypeSpec>& specs) {
  std::printf("    false report (%s): %s at %.1f, %.1f turned %.2f%s", what, m.model->name.c_str(),
              m.centroid.x, m.centroid.y, m.angle_deg,
              m.from_edges ? " in a blob" : " whole region");
  if (t) {
    std::printf("; drawn: %s kind %d turned %.2f, %.0f%% of its outline hidden",
                specs[t->type].name.c_str(), static_cast<int>(t->kind), t->angle_deg,
                100 * t->hidden);
  }
  std::printf("\n");
}

void score(const std::vector<ps::SilhouettePart>& truth, const std::vector<pv::Match>& matches,
           const std::vector<cv::Point2d>& reference, const std::vector<TypeSpec>* list_errors,
           Tally& tally) {
  std::vector<bool> claimed(truth.size(), false);
  for (const auto& t : truth) {
    if (t.kind == ps::PartKind::kTrue) tally.per_type[t.type].truths += 1;
  }
  for (const auto& m : matches) {
    const auto type = static_cast<size_t>(m.model->type);
    Stats& s = tally.per_type[type];
    s.reported += 1;
    int best = -1;
    double best_d = kMatchRadiusPx;
    for (size_t i = 0; i < truth.size(); ++i) {
      const double d = cv::norm(m.centroid - truth[i].centre);
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) {
      tally.confusions.nothing += 1;
      if (list_errors) listFalse("on nothing", m, nullptr, *list_errors);
      continue;
    }
    const ps::SilhouettePart& t = truth[static_cast<size_t>(best)];
    const char* wrong = t.type != type                       ? "other type"
                        : t.kind == ps::PartKind::kMirrored  ? "mirror"
                        : t.kind != ps::PartKind::kTrue      ? "size"
                        : claimed[static_cast<size_t>(best)] ? "duplicate"
                                                             : nullptr;
    if (wrong && list_errors) listFalse(wrong, m, &t, *list_errors);
    if (t.type != type) {
      tally.confusions.other += 1;
      continue;
    }
    if (t.kind == ps::PartKind::kMirrored) {
      tally.confusions.mirror += 1;
      continue;
    }
    if (t.kind != ps::PartKind::kTrue) {
      tally.confusions.size += 1;
      continue;
    }
    if (claimed[static_cast<size_t>(best)]) {
      tally.confusions.duplicate += 1;
      continue;
    }
    claimed[static_cast<size_t>(best)] = true;
    s.correct += 1;
    s.found += 1;
    const double pos = cv::norm(m.centroid - referenceOf(t, reference));
    s.pos2 += pos * pos;
    s.mask_pos2 += best_d * best_d;
    s.worst_pos = std::max(s.worst_pos, pos);
    if (m.symmetry_deg > 0) {
      // The model's frame is the part as trained: turned by kTrainAngleDeg.
      const double e = picksight::angleDiffDeg(
          m.angle_deg, t.angle_deg - picksight::bench::kTrainAngleDeg, m.symmetry_deg);
      s.ang2 += e * e;
      s.angles += 1;
      s.worst_ang = std::max(s.worst_ang, e);
    }
  }
  if (!list_errors) return;
  for (size_t i = 0; i < truth.size(); ++i) {
    const ps::SilhouettePart& t = truth[i];
    if (t.kind != ps::PartKind::kTrue || claimed[i]) continue;
    std::printf("    missed: %s at %.1f, %.1f turned %.2f, %.0f%% of its outline hidden%s\n",
                (*list_errors)[t.type].name.c_str(), t.centre.x, t.centre.y, t.angle_deg,
                100 * t.hidden, t.touching ? ", touching" : "");
  }
}

void printRow(const std::string& name, const Stats& s) {
  std::printf("  %-16s %6d %6d %7.3f %9.3f %8.4f %8.4f %8.4f %8.4f\n", name.c_str(), s.truths,
              s.found, s.truths ? static_cast<double>(s.found) / s.truths : 1.0,
              s.reported ? static_cast<double>(s.correct) / s.reported : 1.0,
              s.found ? std::sqrt(s.pos2 / s.found) : 0.0, s.worst_pos,
              s.angles ? std::sqrt(s.ang2 / s.angles) : 0.0, s.worst_ang);
}

void print(ps::Arrangement arrangement, const Tally& t, bool per_type,
           const std::vector<TypeSpec>& specs, size_t models) {
  std::printf("\n%s: %d frames, %.1f parts per frame, %.1f of them distractors\n",
              ps::arrangementName(arrangement), t.frames,
              t.frames ? static_cast<double>(t.parts) / t.frames : 0.0,
              t.frames ? static_cast<double>(t.distractors) / t.frames : 0.0);
  std::printf("  %-16s %6s %6s %7s %9s %8s %8s %8s %8s\n", "family/type", "truth", "found",
              "recall", "precision", "pos RMS", "pos max", "ang RMS", "ang max");
  std::map<std::string, Stats> families;
  Stats all;
  for (size_t i = 0; i < specs.size(); ++i) {
    families[specs[i].family].add(t.per_type[i]);
    all.add(t.per_type[i]);
  }
  for (const auto& [family, s] : families) {
    printRow(family, s);
    if (!per_type) continue;
    for (size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].family == family) printRow("  " + specs[i].name, t.per_type[i]);
    }
  }
  printRow("ALL", all);
  std::printf(
      "  position RMS against the drawn masks' centroids instead of the trained reference points "
      "%.4f px\n",
      all.found ? std::sqrt(all.mask_pos2 / all.found) : 0.0);
  std::printf("  false reports: mirror %d, size %d, other type %d, on nothing %d, duplicate %d\n",
              t.confusions.mirror, t.confusions.size, t.confusions.other, t.confusions.nothing,
              t.confusions.duplicate);
  const double ours = picksight::bench::nearestRank(t.ours_ms, 50);
  const double plain = picksight::bench::nearestRank(t.plain_ms, 50);
  std::printf(
      "  LOCATE-equivalent (binarize+regions+recognize, %zu models) median %.2f ms p99 %.2f ms "
      "max %.2f ms\n",
      models, ours, picksight::bench::nearestRank(t.ours_ms, 99),
      picksight::bench::nearestRank(t.ours_ms, 100));
  std::printf("  of which binarize %.2f ms, regions %.2f ms, recognize %.2f ms (medians)\n",
              picksight::bench::nearestRank(t.binarize_ms, 50),
              picksight::bench::nearestRank(t.regions_ms, 50),
              picksight::bench::nearestRank(t.recognize_ms, 50));
  std::printf(
      "  CPU time, all threads: binarize %.2f ms, regions %.2f ms, recognize %.2f ms "
      "(medians)\n",
      picksight::bench::nearestRank(t.binarize_cpu_ms, 50),
      picksight::bench::nearestRank(t.regions_cpu_ms, 50),
      picksight::bench::nearestRank(t.recognize_cpu_ms, 50));
  std::printf("  plain OpenCV pass (Otsu+findContours+moments) median %.2f ms p99 %.2f ms\n", plain,
              picksight::bench::nearestRank(t.plain_ms, 99));
  std::printf("  ratio of medians (vision / plain OpenCV) %.2fx\n", plain > 0 ? ours / plain : 0);
  if (!t.simulated_ms.empty()) {
    std::printf(
        "  recognition on N cores, simulated from each region's time alone on one thread "
        "(dealt whole, in order, to the first free core; a blob's models are spread over idle "
        "cores as well, which this leaves out; %zu frames, medians):\n   ",
        t.simulated_ms.front().size());
    const double one = picksight::bench::nearestRank(t.simulated_ms.front(), 50);
    for (size_t k = 0; k < t.simulated_ms.size(); ++k) {
      const double m = picksight::bench::nearestRank(t.simulated_ms[k], 50);
      std::printf(" %d: %.2f ms (x%.2f)", kWorkers[k], m, m > 0 ? one / m : 0.0);
    }
    std::printf(
        "\n  the costliest region's share of a frame's recognition: median %.2f, max %.2f\n",
        picksight::bench::nearestRank(t.costliest_share, 50),
        picksight::bench::nearestRank(t.costliest_share, 100));
  }
}
}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  int scenes = 6;
  int rounds = 20;
  int threads = -1;
  bool per_type = true;
  std::string data_dir = PICKSIGHT_TEST_DATA_DIR;
  std::vector<std::string> which = {"separated", "touching", "overlapping"};
  picksight::cli::App app(
      "Recognition on everyday-object silhouettes: speed, precision, recall, accuracy.",
      argc > 0 ? argv[0] : "picksight-bench-silhouettes");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--scenes", scenes, "scenes per arrangement")
      ->check(picksight::cli::positiveNumber())
      ->showDefault();
  app.addOption("--rounds", rounds, "frames (noise) per scene, each timed")
      ->check(picksight::cli::positiveNumber())
      ->showDefault();
  app.addOption("--threads", threads, "OpenCV worker threads (-1: OpenCV's default)")
      ->showDefault();
  app.addOption("--data", data_dir, "test data directory (shapes/...)")->showDefault();
  app.addOption("--arrangements", which, "separated, touching, overlapping")
      ->check(picksight::cli::isMember({"separated", "touching", "overlapping"}));
  app.addFlag("!--no-per-type", per_type, "families only");
  // The camera's look, for conditions the defaults do not show: a defocused
  // lens, a noisier sensor, less contrast, light parts on a dark table.
  ps::SilhouetteSceneOptions look;
  picksight::bench::addSceneSizeOptions(app, look);
  app.addOption("--blur", look.blur_sigma, "edge blur, sigma in pixels")
      ->check(picksight::cli::range(0.0, 5.0))
      ->showDefault();
  app.addOption("--noise", look.noise_sigma, "sensor noise, sigma in grey levels")
      ->check(picksight::cli::range(0.0, 40.0))
      ->showDefault();
  app.addOption("--part-level", look.part_level, "grey level of the parts")
      ->check(picksight::cli::range(0.0, 255.0))
      ->showDefault();
  app.addOption("--background-level", look.background_level, "grey level of the background")
      ->check(picksight::cli::range(0.0, 255.0))
      ->showDefault();
  int jpeg_quality = 0;
  app.addOption("--jpeg-quality", jpeg_quality,
                "deliver every image (training and scenes) through JPEG at this quality, as an "
                "IP camera or a phone's stream does (0: lossless)")
      ->check(picksight::cli::range(0, 100))
      ->showDefault();
  bool from_edges = false;
  app.addFlag("--from-edges", from_edges,
              "locate every blob's parts the way touching parts are (hypotheses and the edge "
              "fit), to measure that path on separated parts");
  bool scaling = false;
  app.addFlag("--scaling", scaling,
              "also time each region's recognition alone (first frame of each scene) and "
              "print the time on 1 to 16 cores it gives, simulated");
  bool list_false = false;
  app.addFlag("--list-errors", list_false,
              "print each false report (the type reported, where, and what is drawn there) and "
              "each part missed");
  std::vector<std::string> custom;
  app.addOption("--types", custom,
                "train these drawings instead of the default 15 (family \"other\"): "
                "FILE[:SIZE_PX] under the data directory, e.g. "
                "shapes/tari1000/obj3_1.png:220 (size default 220)");
  int model_count = 0;
  app.addOption("--models", model_count,
                "train this many types (0: the scene's): fewer, the first of the scene's; more, "
                "the scene's and drawings never put in a scene (false reports if found)")
      ->check(picksight::cli::range(0, 100))
      ->showDefault();
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  // What the camera delivers of a rendered image.
  const auto delivered = [jpeg_quality](const cv::Mat& image) {
    if (jpeg_quality <= 0) return image;
    std::vector<uchar> bytes;
    picksight::codecs::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
    return picksight::codecs::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  };
  if (threads >= 0) cv::setNumThreads(threads);

  // Adaptive binarization needs a window wider than the widest part: the
  // setting a user picks for parts up to 350 px.
  pv::BinarizeOptions binarize;
  binarize.adaptive_window = 400;
  if (look.part_level > look.background_level) binarize.polarity = pv::Polarity::kLightOnDark;
  pv::TrainOptions train;
  train.binarize = binarize;

  std::vector<TypeSpec> specs = picksight::bench::silhouetteTypeSpecs();
  if (!custom.empty()) {
    specs.clear();
    for (const auto& item : custom) {
      const auto colon = item.rfind(':');
      const std::string file = colon == std::string::npos ? item : item.substr(0, colon);
      double size = 220;
      if (colon != std::string::npos) {
        try {
          size = std::stod(item.substr(colon + 1));
        } catch (const std::exception&) {
          size = 0;
        }
      }
      if (!(size >= 20 && size <= 600)) {
        std::fprintf(stderr, "--types %s: size must be 20..600 px\n", item.c_str());
        return 1;
      }
      const auto slash = file.rfind('/');
      std::string name = slash == std::string::npos ? file : file.substr(slash + 1);
      name = name.substr(0, name.rfind('.'));
      specs.push_back({name, file, "other", size});
    }
  }
  // The scene's types (every one drawn) come first; the models trained are
  // the first `trained` of them, then the extra drawings.
  const size_t scene_types = specs.size();
  const size_t trained = model_count > 0 ? static_cast<size_t>(model_count) : scene_types;
  if (trained > scene_types) {
    const auto extra = picksight::bench::untaughtTypeSpecs(specs, trained - scene_types);
    specs.insert(specs.end(), extra.begin(), extra.end());
  }
  std::vector<ps::SilhouetteType> types;
  if (!picksight::bench::loadSilhouetteTypes(specs, data_dir, &types)) return 1;

  // One model per type, trained on the part alone turned by kTrainAngleDeg.
  std::vector<pv::PartModel> models;
  std::vector<bool> chiral;
  std::vector<cv::Point2d> reference;  // per type: trained centroid - drawn centroid
  std::printf("training %zu types (adaptive window %d px), %zu of them LOCATE's models:\n",
              types.size(), binarize.adaptive_window, std::min(trained, types.size()));
  for (size_t i = 0; i < types.size(); ++i) {
    const int side = static_cast<int>(specs[i].size_px * 1.5) + 300;
    const cv::Mat image = delivered(ps::renderSilhouetteAlone(types[i], side, look, 7 + i, nullptr,
                                                              picksight::bench::kTrainAngleDeg));
    // The reference point's offset from the drawn centroid is what the
    // camera's blur takes from the drawing: measured without noise and
    // under even light, so that one image's noise is not counted in every
    // part's error.
    ps::SilhouetteSceneOptions clean = look;
    clean.noise_sigma = 0;
    clean.uneven_light = false;
    cv::Point2d drawn;
    const cv::Mat sharp = ps::renderSilhouetteAlone(types[i], side, clean, 7 + i, &drawn,
                                                    picksight::bench::kTrainAngleDeg);
    const auto seen = pv::findRegions(pv::binarize(sharp, binarize), {}, sharp);
    // Measured on the part as trained, turned back to the drawing's frame
    // (referenceOf turns it with each scene part).
    const cv::Point2d offset = seen.empty() ? cv::Point2d() : seen.front().centroid - drawn;
    const double back = -picksight::bench::kTrainAngleDeg * M_PI / 180.0;
    reference.push_back({offset.x * std::cos(back) - offset.y * std::sin(back),
                         offset.x * std::sin(back) + offset.y * std::cos(back)});
    auto outcome = pv::trainModel(image, static_cast<int>(i), specs[i].name, train);
    if (!outcome.ok()) {
      std::fprintf(stderr, "training %s failed: %s\n", specs[i].name.c_str(),
                   outcome.error().message.c_str());
      return 1;
    }
    const pv::PartModel& m = outcome.value();
    size_t primitives = 0;
    for (const auto& loop : m.loops) primitives += loop.primitives.size();
    std::printf(
        "  %-8s %-15s %4.0f px area %7.0f holes %d primitives %4zu corners %3zu order %2d "
        "symmetry %5.1f mirror-symmetric %d\n",
        specs[i].name.c_str(), specs[i].family.c_str(), specs[i].size_px, m.body.area, m.body.holes,
        primitives, m.corners.size(), m.orientation_order, m.symmetryDeg(),
        m.body.mirror_symmetric ? 1 : 0);
    chiral.push_back(!m.body.mirror_symmetric);
    models.push_back(outcome.value());
  }
  std::vector<const pv::PartModel*> list;
  for (size_t i = 0; i < models.size() && i < trained; ++i) list.push_back(&models[i]);
  // Only the scene's types are drawn (the extra drawings' models are
  // trained above; scored as other types wherever they are reported).
  types.resize(scene_types);
  chiral.resize(scene_types);

  for (const auto& name : which) {
    const ps::Arrangement arrangement = name == "separated"  ? ps::Arrangement::kSeparated
                                        : name == "touching" ? ps::Arrangement::kTouching
                                                             : ps::Arrangement::kOverlapping;
    Tally tally;
    tally.per_type.resize(specs.size());
    size_t turn = 0;
    for (int n = 0; n < scenes; ++n) {
      ps::SilhouetteSceneOptions o = look;
      o.arrangement = arrangement;
      o.seed = 1000 * (static_cast<uint64_t>(arrangement) + 1) + static_cast<uint64_t>(n);
      const ps::SilhouetteScene scene(types, chiral, o);
      for (int r = 0; r < rounds; ++r) {
        const cv::Mat grey = delivered(scene.render(static_cast<uint64_t>(r)));
        std::vector<pv::Match> matches;
        double sink = 0;
        picksight::bench::timeInTurn<2>(
            turn++,
            {[&] {
               const double c0 = cpuMs();
               const auto t0 = Clock::now();
               const cv::Mat mask = pv::binarize(grey, binarize);
               const auto t1 = Clock::now();
               const double c1 = cpuMs();
               const auto regions = pv::findRegions(mask, {}, grey);
               const auto t2 = Clock::now();
               const double c2 = cpuMs();
               if (from_edges) {
                 matches.clear();
                 for (size_t i = 0; i < regions.size(); ++i) {
                   const auto in_blob = pv::locateInBlob(regions, i, list);
                   matches.insert(matches.end(), in_blob.begin(), in_blob.end());
                 }
               } else {
                 matches = pv::recognize(regions, list);
               }
               const auto t3 = Clock::now();
               const double c3 = cpuMs();
               tally.binarize_ms.push_back(Ms(t1 - t0).count());
               tally.regions_ms.push_back(Ms(t2 - t1).count());
               tally.recognize_ms.push_back(Ms(t3 - t2).count());
               tally.binarize_cpu_ms.push_back(c1 - c0);
               tally.regions_cpu_ms.push_back(c2 - c1);
               tally.recognize_cpu_ms.push_back(c3 - c2);
             },
             [&] { sink += picksight::bench::competentOpenCvPass(grey); }},
            {&tally.ours_ms, &tally.plain_ms});
        if (scaling && r == 0 && !from_edges) {
          // Each region alone, as recognize() does it on a worker thread.
          const auto regions = pv::findRegions(pv::binarize(grey, binarize), {}, grey);
          std::vector<double> each;
          for (const auto& region : regions) {
            const std::vector<pv::Region> alone{region};
            const auto t0 = Clock::now();
            const auto found = pv::recognize(alone, list);
            each.push_back(Ms(Clock::now() - t0).count());
            if (found.size() > 1000) std::printf("!");
          }
          if (tally.simulated_ms.empty()) tally.simulated_ms.resize(std::size(kWorkers));
          for (size_t k = 0; k < std::size(kWorkers); ++k)
            tally.simulated_ms[k].push_back(makespanMs(each, kWorkers[k]));
          double total = 0;
          for (const double m : each) total += m;
          if (total > 0)
            tally.costliest_share.push_back(*std::max_element(each.begin(), each.end()) / total);
        }
        score(scene.truth(), matches, reference, list_false ? &specs : nullptr, tally);
        tally.parts += static_cast<int>(scene.truth().size());
        for (const auto& t : scene.truth()) tally.distractors += t.kind != ps::PartKind::kTrue;
        tally.frames += 1;
        if (sink == 0) std::printf("!");
      }
    }
    print(arrangement, tally, per_type, specs, list.size());
    std::fflush(stdout);
  }
  return 0;
}
