// Parts under the light of a front-lit cell: per condition (textured belt,
// cast shadows, glints, low contrast, colour, other surfaces, JPEG frames)
// each type is taught the way a user teaches it (LEARN on a frame of the cell's
// camera with the part alone in it, anywhere in the frame and lit as the
// scenes are there, and LEARN ... AT a box around it when LEARN refuses; with
// --list-errors, where each teach frame placed the reference point), then LOCATE ALL
// runs on 1920x1080 scenes of 20 parts with mirrored and scaled distractors,
// separated and in touching pairs, through the cell's own locate function.
// Prints per condition what LEARN answered, recall, precision, confusions,
// position and angle RMS against the drawn part (never its shadow), and the
// LOCATE median and p99 beside the plain OpenCV pass, with the goals beside.
// The default types are silhouettes the other benchmarks never trained on.
// Never fails on the figures.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "opencv_baseline.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/cli/command_line.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/common/large_buffers.hpp"
#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/recognition/region_explanation.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "silhouette_types.hpp"

namespace {
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;
namespace pc = picksight::cell;
namespace pst = picksight::store;
using picksight::bench::TypeSpec;
using Clock = std::chrono::steady_clock;
using Ms = std::chrono::duration<double, std::milli>;

// A report this close to a drawn part's centroid is about that part.
constexpr double kMatchRadiusPx = 12;
// --list-errors names the parts placed further than this from their truth.
constexpr double kListOffPx = 0.2;
// The binarization window of the sharp, evenly lit image the truth is read
// on: wider than any part's length, so the window never cuts it.
constexpr int kTruthWindow = 400;

// Silhouettes none of the other benchmarks or tests trained on (Tari-1000
// classes outside silhouetteTypeSpecs, and their third drawing).
const std::vector<TypeSpec>& unseenTypeSpecs() {
  static const std::vector<TypeSpec> specs = {
      {"obj1", "shapes/tari1000/obj1_3.png", "unseen", 220},
      {"obj3", "shapes/tari1000/obj3_3.png", "unseen", 200},
      {"obj5", "shapes/tari1000/obj5_3.png", "unseen", 240},
      {"obj6", "shapes/tari1000/obj6_3.png", "unseen", 210},
      {"obj8", "shapes/tari1000/obj8_3.png", "unseen", 230},
      {"obj11", "shapes/tari1000/obj11_3.png", "unseen", 200},
      {"obj13", "shapes/tari1000/obj13_3.png", "unseen", 220},
      {"obj15", "shapes/tari1000/obj15_3.png", "unseen", 250},
      {"obj18", "shapes/tari1000/obj18_3.png", "unseen", 190},
      {"obj22", "shapes/tari1000/obj22_3.png", "unseen", 230},
      {"obj25", "shapes/tari1000/obj25_3.png", "unseen", 210},
      {"obj27", "shapes/tari1000/obj27_3.png", "unseen", 240},
      {"obj35", "shapes/tari1000/obj35_3.png", "unseen", 200},
      {"obj45", "shapes/tari1000/obj45_3.png", "unseen", 220},
  };
  return specs;
}

struct Row {
  std::string condition;
  std::string arrangement;
  int learn_ok = 0;     // taught by LEARN on the image of the part alone
  int learn_at_ok = 0;  // taught by LEARN ... AT after LEARN refused
  int untaught = 0;
  int views_refused = 0;      // --teach-views: LEARNVIEWs refused, every type
  std::string first_refusal;  // what LEARN answered first when it refused
  int truths = 0;
  int found = 0;
  int reported = 0;
  int correct = 0;
  int mirror = 0;
  int size = 0;
  int other = 0;
  int nothing = 0;
  double pos2 = 0;
  // Per type: the sum of the errors on the part (turned back with it) and
  // their count, for the scatter about each type's own offset.
  std::map<size_t, std::pair<cv::Point2d, int>> on_part;
  double ang2 = 0;
  int angles = 0;
  std::vector<double> locate_ms;
  std::vector<double> plain_ms;
  // --stages: the vision pass's first two stages alone, on the same image.
  std::vector<double> binarize_ms;
  std::vector<double> regions_ms;
  std::vector<double> uncut_ms;  // the region pass without cutting shadows
  // --teachings: each teaching's position RMS and recall, in order.
  std::vector<double> pos_by_teaching;
  std::vector<double> recall_by_teaching;
};

double positionRms(const Row& r) { return r.found ? std::sqrt(r.pos2 / r.found) : 0.0; }
double recallOf(const Row& r) { return r.truths ? static_cast<double>(r.found) / r.truths : 0.0; }

// Adds `more` (the same row under another teaching) to `into`. Each
// teaching's types keep their own offsets (`types` apart in on_part):
// the scatter is about each model's own mean error, and another teaching
// is another model.
void addTeaching(const Row& more, size_t types, size_t teaching, Row* into) {
  into->learn_ok += more.learn_ok;
  into->learn_at_ok += more.learn_at_ok;
  into->untaught += more.untaught;
  into->views_refused += more.views_refused;
  if (into->first_refusal.empty()) into->first_refusal = more.first_refusal;
  into->truths += more.truths;
  into->found += more.found;
  into->reported += more.reported;
  into->correct += more.correct;
  into->mirror += more.mirror;
  into->size += more.size;
  into->other += more.other;
  into->nothing += more.nothing;
  into->pos2 += more.pos2;
  for (const auto& [type, sum] : more.on_part) into->on_part[teaching * types + type] = sum;
  into->ang2 += more.ang2;
  into->angles += more.angles;
  for (auto [to, from] :
       {std::pair{&into->locate_ms, &more.locate_ms}, std::pair{&into->plain_ms, &more.plain_ms},
        std::pair{&into->binarize_ms, &more.binarize_ms},
        std::pair{&into->regions_ms, &more.regions_ms},
        std::pair{&into->uncut_ms, &more.uncut_ms}}) {
    to->insert(to->end(), from->begin(), from->end());
  }
  into->pos_by_teaching.push_back(positionRms(more));
  into->recall_by_teaching.push_back(recallOf(more));
}

// The frame a camera delivers: lossless, or through JPEG.
cv::Mat delivered(const cv::Mat& image, int jpeg_quality) {
  if (jpeg_quality <= 0) return image;
  std::vector<uchar> bytes;
  picksight::codecs::imencode(".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
  return picksight::codecs::imdecode(
      bytes, image.channels() == 3 ? cv::IMREAD_COLOR : cv::IMREAD_GRAYSCALE);
}

picksight::Frame frameOf(const cv::Mat& image) {
  picksight::Frame f;
  f.image = image;
  f.info.width = static_cast<uint32_t>(image.cols);
  f.info.height = static_cast<uint32_t>(image.rows);
  return f;
}

// What WHY would say of the region under `at` in `outcome`: the model it
// comes nearest to and the first test it fails ("passes" for a blob whose
// search found nothing there), or that no region lies there.
std::string whyMissed(const pc::LocateOutcome& outcome, cv::Point2d at) {
  const auto& regions = outcome.scene.regions;
  for (size_t k = 0; k < regions.size(); ++k) {
    if (cv::pointPolygonTest(regions[k].outer, at, false) < 0) continue;
    std::vector<const pv::PartModel*> models;
    if (outcome.scene.models) {
      for (const auto& m : *outcome.scene.models) models.push_back(&m);
    }
    const pv::RegionExplanation e = pv::explainRegion(regions[k], models);
    char text[256];
    std::snprintf(text, sizeof text, "region %zu (%.0f px), nearest %s, %s %.3f in %.3f..%.3f", k,
                  regions[k].area, e.nearest ? e.nearest->name.c_str() : "-",
                  pv::regionTestName(e.test), e.measured, e.low, e.high);
    return text;
  }
  return "in no region";
}

void score(const std::vector<ps::SilhouettePart>& truth, const pc::LocateOutcome& outcome,
           const std::vector<int>& type_of_model, const std::vector<cv::Point2d>& reference,
           bool list, const std::vector<TypeSpec>& specs, Row& row) {
  const std::vector<pc::LocatedPart>& parts = outcome.parts;
  std::vector<bool> claimed(truth.size(), false);
  for (const auto& t : truth) row.truths += t.kind == ps::PartKind::kTrue ? 1 : 0;
  for (const auto& p : parts) {
    if (p.type < 0) continue;  // a region no model claims: not a report
    row.reported += 1;
    const int type = type_of_model[static_cast<size_t>(p.type)];
    int best = -1;
    double best_d = kMatchRadiusPx;
    for (size_t i = 0; i < truth.size(); ++i) {
      const double d = std::hypot(p.x - truth[i].centre.x, p.y - truth[i].centre.y);
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) {
      row.nothing += 1;
      if (list)
        std::printf("    on nothing: %s at %.1f %.1f\n",
                    specs[static_cast<size_t>(type)].name.c_str(), p.x, p.y);
      continue;
    }
    const ps::SilhouettePart& t = truth[static_cast<size_t>(best)];
    if (static_cast<int>(t.type) != type) {
      row.other += 1;
      continue;
    }
    if (t.kind == ps::PartKind::kMirrored) {
      row.mirror += 1;
      continue;
    }
    if (t.kind != ps::PartKind::kTrue) {
      row.size += 1;
      continue;
    }
    if (claimed[static_cast<size_t>(best)]) continue;
    claimed[static_cast<size_t>(best)] = true;
    row.correct += 1;
    row.found += 1;
    const cv::Point2d o = reference[t.type];
    const double a = t.angle_deg * M_PI / 180.0;
    const cv::Point2d ref = t.centre + cv::Point2d(o.x * std::cos(a) - o.y * std::sin(a),
                                                   o.x * std::sin(a) + o.y * std::cos(a));
    // The error in the image and on the part (turned back with it; the same
    // there for every part of a type is the taught model's own error).
    const cv::Point2d e(p.x - ref.x, p.y - ref.y);
    const cv::Point2d on_part(e.x * std::cos(a) + e.y * std::sin(a),
                              -e.x * std::sin(a) + e.y * std::cos(a));
    const double pos = std::hypot(e.x, e.y);
    row.pos2 += pos * pos;
    auto& sum = row.on_part[t.type];
    sum.first += on_part;
    sum.second += 1;
    // Parts placed well beyond the position goal, to look at.
    if (list && pos > kListOffPx) {
      std::printf(
          "    placed %.2f px off (%+.2f %+.2f, on the part %+.2f %+.2f): %s at %.1f %.1f%s\n", pos,
          e.x, e.y, on_part.x, on_part.y, specs[t.type].name.c_str(), ref.x, ref.y,
          t.touching ? ", touching" : "");
    }
    if (p.symmetry_deg > 0) {
      const double e = picksight::angleDiffDeg(
          p.angle_deg, t.angle_deg - picksight::bench::kTrainAngleDeg, p.symmetry_deg);
      row.ang2 += e * e;
      row.angles += 1;
    }
  }
  if (!list) return;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (truth[i].kind != ps::PartKind::kTrue || claimed[i]) continue;
    std::printf("    missed: %s at %.1f %.1f%s: %s\n", specs[truth[i].type].name.c_str(),
                truth[i].centre.x, truth[i].centre.y, truth[i].touching ? ", touching" : "",
                whyMissed(outcome, truth[i].centre).c_str());
  }
}

// What the command line sets for every cell of the benchmark.
struct Settings {
  int scenes = 2;
  int rounds = 5;
  int jpeg_quality = 0;
  bool list_errors = false;
  bool stages = false;
  std::string save_frames;
  bool teach_on_plain = false;
  int teach_views = 1;
};

// One condition's light: its name, how its frames look and the vision
// app's options under it.
struct Light {
  std::string condition;
  ps::SilhouetteSceneOptions look;
  pc::VisionOptions options;
};

// The part types, as named and as drawn.
struct Types {
  const std::vector<TypeSpec>& specs;
  const std::vector<ps::SilhouetteType>& drawn;
};

// A cell taught under one light: its models and what each tells of its
// type.
struct Cell {
  std::shared_ptr<pst::ModelList> models = std::make_shared<pst::ModelList>();
  std::vector<int> type_of_model;  // a model's type -> the type's index
  std::vector<bool> chiral;        // per type: its model is not mirror-symmetric
  // Per type: where the model's reference point lies on the drawn part.
  std::vector<cv::Point2d> reference;
  Row taught;  // what LEARN, LEARN ... AT and LEARNVIEW answered
};

// Where type i lies in its teach frame for `view` (0: LEARN, then
// LEARNVIEW's) of a teaching (`again`: its seeds' offset): anywhere a user
// might lay it, its whole outline a margin inside the frame.
cv::Point2d teachSpot(const Light& light, const TypeSpec& spec, size_t i, int view,
                      uint64_t again) {
  std::mt19937_64 rng(0x7465616368ULL + 131 * i + static_cast<uint64_t>(view) + again);
  const double margin = 0.75 * spec.size_px + 20;
  std::uniform_real_distribution<double> x(margin, light.look.width - 1 - margin);
  std::uniform_real_distribution<double> y(margin, light.look.height - 1 - margin);
  const double at_x = x(rng);
  return cv::Point2d(at_x, y(rng));
}

// Where the model's reference point (the region's centroid) lies on a part
// drawn with `seed` at `spot`, turned back to the part: measured on a
// sharp, evenly back-lit image of it, so that the light of the condition
// counts in the error, not in the truth.
cv::Point2d referenceOnPart(const ps::SilhouetteType& type, const ps::SilhouetteSceneOptions& look,
                            uint64_t seed, cv::Point2d spot) {
  ps::SilhouetteSceneOptions sharp_look;
  sharp_look.noise_sigma = 0;
  sharp_look.uneven_light = false;
  sharp_look.width = look.width;
  sharp_look.height = look.height;
  cv::Point2d sharp_drawn;
  const cv::Mat sharp = ps::renderSilhouetteInFrame(type, sharp_look, seed, spot, &sharp_drawn,
                                                    picksight::bench::kTrainAngleDeg);
  pv::BinarizeOptions b;
  b.adaptive_window = kTruthWindow;
  const auto seen = pv::findRegions(pv::binarize(sharp, b), {}, sharp);
  size_t largest = 0;
  for (size_t k = 1; k < seen.size(); ++k) {
    if (seen[k].area > seen[largest].area) largest = k;
  }
  const cv::Point2d offset = seen.empty() ? cv::Point2d() : seen[largest].centroid - sharp_drawn;
  const double back = -picksight::bench::kTrainAngleDeg * M_PI / 180.0;
  return {offset.x * std::cos(back) - offset.y * std::sin(back),
          offset.x * std::sin(back) + offset.y * std::cos(back)};
}

// Writes a teach image (and what the vision pass takes for parts there,
// before any model) to --save-frames, each teaching's apart (the first's
// named as without --teachings).
void saveTeachImage(const Settings& s, const Light& light, const std::string& type, int teaching,
                    const cv::Mat& image) {
  const std::string name =
      light.condition + "-teach-" + type + (teaching > 0 ? "-" + std::to_string(teaching + 1) : "");
  picksight::codecs::imwrite(s.save_frames + "/" + name + ".png", image);
  const auto seen =
      pc::locateInFrame(frameOf(image), light.options, std::make_shared<pst::ModelList>(), -1);
  if (!seen.scene.mask.empty())
    picksight::codecs::imwrite(s.save_frames + "/" + name + "-mask.png", seen.scene.mask);
}

// More views of type i (LEARNVIEW) added to its learned model: the part
// alone again, turned and lying on another stretch of the surface, each
// read with the model so far.
void addViews(const Settings& s, const Light& light, const Types& types, size_t i,
              const ps::SilhouetteSceneOptions& teach_look, uint64_t again, const Cell& cell,
              pc::LearnOutcome* learned, Row* taught) {
  for (int v = 1; v < s.teach_views; ++v) {
    auto trial = std::make_shared<pst::ModelList>(*cell.models);
    trial->push_back(learned->model);
    cv::Point2d unused;
    const cv::Mat view =
        delivered(ps::renderSilhouetteInFrame(types.drawn[i], teach_look, 1000 * v + 7 + i + again,
                                              teachSpot(light, types.specs[i], i, v, again),
                                              &unused, picksight::bench::kTrainAngleDeg + 47.0 * v),
                  s.jpeg_quality);
    auto seen =
        pc::viewInFrame(frameOf(view), light.options, trial, learned->model.type, std::nullopt);
    if (!seen) {
      taught->views_refused += 1;
      if (s.list_errors) {
        std::printf("  %s %s: view %d refused: %s\n", light.condition.c_str(),
                    types.specs[i].name.c_str(), v, seen.error().message.c_str());
      }
      continue;
    }
    learned->model = std::move(seen->model);
  }
}

// Teaches type i into `cell` as a user would: LEARN on an image of the part
// alone under the same light (or, --teach-on-plain, on a plain surface);
// when LEARN refuses, LEARN ... AT a box around it; then its further views.
void teachType(const Settings& s, const Light& light, const Types& types, size_t i, int teaching,
               Cell* cell) {
  const uint64_t again = 100003ULL * static_cast<uint64_t>(teaching);
  const TypeSpec& spec = types.specs[i];
  ps::SilhouetteSceneOptions teach_look = light.look;
  if (s.teach_on_plain) {
    ps::FrontLight plain;
    plain.colour = light.look.front.colour;
    plain.part_bgr = light.look.front.part_bgr;
    plain.background_bgr = light.look.front.background_bgr;
    teach_look.front = plain;
  }
  const cv::Point2d spot = teachSpot(light, spec, i, 0, again);
  cv::Point2d drawn;
  const cv::Mat image =
      delivered(ps::renderSilhouetteInFrame(types.drawn[i], teach_look, 7 + i + again, spot, &drawn,
                                            picksight::bench::kTrainAngleDeg),
                s.jpeg_quality);
  if (!s.save_frames.empty()) saveTeachImage(s, light, spec.name, teaching, image);
  const picksight::Frame frame = frameOf(image);
  const cv::Mat& grey = frame.image;  // LEARN reads a colour frame in colour
  Row& taught = cell->taught;
  auto learned =
      pc::learnInImage(grey, frame.mapping, light.options, cell->models,
                       static_cast<int>(cell->models->size()) + 1, spec.name, std::nullopt);
  if (learned) {
    taught.learn_ok += 1;
  } else {
    if (taught.first_refusal.empty()) {
      taught.first_refusal = spec.name + ": " + learned.error().message;
    }
    // The box a user drags: the part with a margin of a tenth of its size.
    const double half = 0.6 * spec.size_px;
    const cv::Rect at(static_cast<int>(drawn.x - half), static_cast<int>(drawn.y - half),
                      static_cast<int>(2 * half), static_cast<int>(2 * half));
    learned = pc::learnInImage(grey, frame.mapping, light.options, cell->models,
                               static_cast<int>(cell->models->size()) + 1, spec.name, at);
    if (learned) taught.learn_at_ok += 1;
  }
  if (!learned) {
    taught.untaught += 1;
    if (s.list_errors) {
      std::printf("  %s %s: not taught: %s\n", light.condition.c_str(), spec.name.c_str(),
                  learned.error().message.c_str());
    }
    return;
  }
  cell->reference[i] = referenceOnPart(types.drawn[i], light.look, 7 + i + again, spot);
  cell->chiral[i] = !learned->model.body.mirror_symmetric;
  if (s.list_errors) {
    // The teach image's reading of the reference point, on the part.
    const double back = -picksight::bench::kTrainAngleDeg * M_PI / 180.0;
    const cv::Point2d d = learned->model.trained_centroid - drawn;
    const cv::Point2d on(d.x * std::cos(back) - d.y * std::sin(back),
                         d.x * std::sin(back) + d.y * std::cos(back));
    std::printf("  %s %s: taught %+.3f %+.3f px off on the part\n", light.condition.c_str(),
                spec.name.c_str(), on.x - cell->reference[i].x, on.y - cell->reference[i].y);
  }
  addViews(s, light, types, i, teach_look, again, *cell, &*learned, &taught);
  if (s.list_errors && s.teach_views > 1) {
    std::printf("  %s %s: %zu views, origin at %+.3f %+.3f\n", light.condition.c_str(),
                spec.name.c_str(), learned->model.views.size() + 1, learned->model.origin_shift.x,
                learned->model.origin_shift.y);
  }
  auto next = std::make_shared<pst::ModelList>(*cell->models);
  next->push_back(std::move(learned->model));
  cell->models = next;
  cell->type_of_model.resize(static_cast<size_t>(cell->models->back().type) + 1, -1);
  cell->type_of_model[static_cast<size_t>(cell->models->back().type)] = static_cast<int>(i);
}

// The cell taught under `light`, every type in turn. Teaching 0 is the
// benchmark's own; each further one lays every part down again: its
// spots, its surface and its noise from other seeds.
Cell teachCell(const Settings& s, const Light& light, const Types& types, int teaching) {
  Cell cell;
  cell.chiral.assign(types.drawn.size(), true);
  cell.reference.resize(types.drawn.size());
  for (size_t i = 0; i < types.drawn.size(); ++i) teachType(s, light, types, i, teaching, &cell);
  return cell;
}

// --stages: the vision pass's first two stages alone on `frame`, as
// locateInFrame prepares them (the vision image, a colour frame projected
// on the taught colours, and the frame's options).
void timeStages(const picksight::Frame& frame, const Light& light, const pst::ModelList& models,
                Row* row) {
  const cv::Mat grey = pc::visionImage(frame, models);
  const pc::VisionOptions o = pc::frameOptions(light.options, frame.mapping, grey.size(), models);
  cv::Mat mask;
  row->binarize_ms.push_back(
      picksight::bench::elapsedMs([&] { mask = pv::binarize(grey, o.binarize); }));
  // The regions LOCATE finds: from the speck area up when the smallest
  // region follows the models.
  const pv::RegionOptions located = pc::locateRegionOptions(o, models);
  std::vector<pv::Region> regions;
  row->regions_ms.push_back(
      picksight::bench::elapsedMs([&] { regions = pv::findRegions(mask, located, grey); }));
  pv::RegionOptions uncut = located;
  uncut.cut_shadows = false;
  row->uncut_ms.push_back(
      picksight::bench::elapsedMs([&] { regions = pv::findRegions(mask, uncut, grey); }));
}

// The row of one arrangement of `cell`'s parts under `light`: every scene
// and round located (LOCATE ALL) in turn with the plain OpenCV pass, and
// scored.
Row runArrangement(const Settings& s, const Light& light, const Types& types, const Cell& cell,
                   const std::string& name) {
  const ps::Arrangement arrangement = name == "separated"  ? ps::Arrangement::kSeparated
                                      : name == "touching" ? ps::Arrangement::kTouching
                                                           : ps::Arrangement::kOverlapping;
  Row row = cell.taught;
  row.condition = light.condition;
  row.arrangement = name;
  const std::string frames = s.save_frames + "/" + light.condition + "-" + name + "-";
  size_t turn = 0;
  for (int n = 0; n < s.scenes; ++n) {
    ps::SilhouetteSceneOptions o = light.look;
    o.arrangement = arrangement;
    o.seed = 5000 * (static_cast<uint64_t>(arrangement) + 1) + static_cast<uint64_t>(n);
    const ps::SilhouetteScene scene(types.drawn, cell.chiral, o);
    for (int r = 0; r < s.rounds; ++r) {
      const cv::Mat image = delivered(scene.render(static_cast<uint64_t>(r)), s.jpeg_quality);
      const bool save = !s.save_frames.empty() && r == 0;
      if (save) picksight::codecs::imwrite(frames + std::to_string(n) + ".png", image);
      const picksight::Frame frame = frameOf(image);
      pc::LocateOutcome outcome;
      double sink = 0;
      picksight::bench::timeInTurn<2>(turn++,
                                      {[&] {
                                         if (cell.models->empty()) return;
                                         outcome = pc::locateInFrame(frame, light.options,
                                                                     cell.models, -1);
                                       },
                                       [&] {
                                         cv::Mat grey = image;
                                         if (image.channels() == 3)
                                           cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
                                         sink += picksight::bench::competentOpenCvPass(grey);
                                       }},
                                      {&row.locate_ms, &row.plain_ms});
      if (save && !outcome.scene.mask.empty()) {
        // What the vision pass took for parts: to look at beside the frame.
        picksight::codecs::imwrite(frames + std::to_string(n) + "-mask.png", outcome.scene.mask);
      }
      if (s.stages && !cell.models->empty()) timeStages(frame, light, *cell.models, &row);
      if (s.list_errors) {
        std::printf("  %s %s scene %d round %d:\n", light.condition.c_str(), name.c_str(), n, r);
      }
      score(scene.truth(), outcome, cell.type_of_model, cell.reference, s.list_errors, types.specs,
            row);
      if (sink == 0) std::printf("!");
    }
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  // The vision pass's buffers kept, as the services keep them.
  picksight::retainLargeBuffers();
  Settings s;
  bool standard_types = false;
  bool keep_shadows = false;
  int window = 0;
  int teachings = 1;
  double blur_sigma = ps::SilhouetteSceneOptions{}.blur_sigma;
  std::string data_dir = PICKSIGHT_TEST_DATA_DIR;
  std::vector<std::string> conditions = {"clean",        "textured", "shadow", "glossy",
                                         "low-contrast", "colour",   "wood",   "metal"};
  std::vector<std::string> arrangements = {"separated", "touching"};
  picksight::cli::App app(
      "Parts under a front-lit cell's light: teaching, recall, precision, accuracy.",
      argc > 0 ? argv[0] : "picksight-bench-front-light");
  app.setHelpFlag("-h,--help", "print this help");
  std::vector<std::string> condition_names = ps::frontLightConditionNames();
  for (const auto& name : ps::photographedConditionNames()) condition_names.push_back(name);
  app.addOption("--conditions", conditions,
                "light conditions (brick, gravel: photographed surfaces, not run by default)")
      ->check(picksight::cli::isMember(condition_names));
  app.addOption("--arrangements", arrangements, "separated, touching, overlapping")
      ->check(picksight::cli::isMember({"separated", "touching", "overlapping"}));
  app.addOption("--scenes", s.scenes, "scenes per condition and arrangement")
      ->check(picksight::cli::range(1, 50))
      ->showDefault();
  app.addOption("--rounds", s.rounds, "frames (noise) per scene, each timed")
      ->check(picksight::cli::range(1, 200))
      ->showDefault();
  app.addOption("--jpeg-quality", s.jpeg_quality,
                "deliver every image through JPEG at this quality (0: lossless)")
      ->check(picksight::cli::range(0, 100))
      ->showDefault();
  app.addFlag("--standard-types", standard_types,
              "the 15 types of picksight-bench-silhouettes instead of unseen ones");
  app.addFlag("--list-errors", s.list_errors,
              "print each false report, each part missed and each placed over 0.2 px off");
  app.addFlag("--stages", s.stages,
              "also time binarization and the region pass alone (medians, ms): where the time "
              "goes");
  app.addOption("--blur", blur_sigma,
                "the lens's blur (Gaussian sigma, px) of scenes and teach images: a camera out "
                "of focus")
      ->check(picksight::cli::range(0.0, 5.0))
      ->showDefault();
  app.addOption("--window", window,
                "the adaptive threshold's window, as the vision app's --window (0: the app's "
                "own, from the image and the taught parts)")
      ->check(picksight::cli::range(0, 4000))
      ->showDefault();
  app.addFlag("--keep-shadows", keep_shadows,
              "leave cast shadows joined to the parts (to measure what cutting them gains and "
              "costs)");
  app.addFlag("--teach-on-plain", s.teach_on_plain,
              "teach each type on a plain surface, evenly lit (a sheet of card under the cell), "
              "the part's and the surface's levels and colours kept; the scenes keep the "
              "condition's light");
  app.addOption("--teachings", teachings,
                "teach the cell this many times over, each type laid again for each teaching "
                "(another spot, another stretch of the surface, another draw of the noise), and "
                "run every scene with each teaching's models: one teach image's texture and noise "
                "move every part of its type alike, and one teaching shows one draw of that")
      ->check(picksight::cli::range(1, 20));
  app.addOption("--teach-views", s.teach_views,
                "teach each type from this many images of it (LEARN, then LEARNVIEW on the part "
                "lying elsewhere, turned), each under the teach light")
      ->check(picksight::cli::range(1, 33))
      ->showDefault();
  app.addOption("--save-frames", s.save_frames,
                "write each scene's first frame, its binarization (-mask) and each teach image "
                "here (PNG), to look at");
  app.addOption("--data", data_dir, "test data directory (shapes/...)")->showDefault();
  if (auto exit_code = picksight::cli::parseMainArgs(app, argc, argv)) return *exit_code;
  if (!s.save_frames.empty() && !std::filesystem::is_directory(s.save_frames)) {
    std::fprintf(stderr, "--save-frames: %s is not a directory\n", s.save_frames.c_str());
    return 2;
  }

  const std::vector<TypeSpec>& specs =
      standard_types ? picksight::bench::silhouetteTypeSpecs() : unseenTypeSpecs();
  std::vector<ps::SilhouetteType> drawn;
  if (!picksight::bench::loadSilhouetteTypes(specs, data_dir, &drawn)) return 1;
  const Types types{specs, drawn};

  std::vector<Row> rows;
  for (const auto& condition : conditions) {
    Light light;
    light.condition = condition;
    ps::SilhouetteSceneOptions& look = light.look;
    if (!ps::frontLightCondition(condition, &look.front, &look.part_level,
                                 &look.background_level)) {
      const std::string photo = data_dir + "/surfaces/" + condition + ".png";
      if (!ps::photographedCondition(condition,
                                     picksight::codecs::imread(photo, cv::IMREAD_GRAYSCALE),
                                     &look.front, &look.part_level, &look.background_level)) {
        std::fprintf(stderr, "%s: cannot read %s\n", condition.c_str(), photo.c_str());
        return 1;
      }
    }
    look.blur_sigma = blur_sigma;
    // The vision app's defaults (the window it picks from the image and the
    // models, unless --window sets one as a user's --window would).
    light.options.binarize.adaptive_window = window;
    light.options.regions.cut_shadows = !keep_shadows;
    if (look.part_level > look.background_level) {
      light.options.binarize.polarity = pv::Polarity::kLightOnDark;
    }
    std::vector<Row> taught_rows;  // one per arrangement, over every teaching
    for (int teaching = 0; teaching < teachings; ++teaching) {
      const Cell cell = teachCell(s, light, types, teaching);
      for (size_t a = 0; a < arrangements.size(); ++a) {
        Row row = runArrangement(s, light, types, cell, arrangements[a]);
        if (teaching == 0) {
          row.pos_by_teaching.push_back(positionRms(row));
          row.recall_by_teaching.push_back(recallOf(row));
          taught_rows.push_back(row);
        } else {
          addTeaching(row, specs.size(), static_cast<size_t>(teaching), &taught_rows[a]);
        }
        std::fprintf(stderr, "%s %s done (teaching %d)\n", condition.c_str(),
                     arrangements[a].c_str(), teaching + 1);
      }
    }
    rows.insert(rows.end(), taught_rows.begin(), taught_rows.end());
  }

  std::printf(
      "\n%zu types (%s), %d scenes x %d frames per row%s, 1920x1080, 20 parts, %s\n", specs.size(),
      standard_types ? "the silhouette benchmark's" : "unseen", s.scenes, s.rounds,
      teachings > 1 ? (" x " + std::to_string(teachings) + " teachings").c_str() : "",
      s.jpeg_quality > 0 ? ("JPEG quality " + std::to_string(s.jpeg_quality)).c_str() : "lossless");
  std::printf("%-13s %-10s %5s %5s %5s %7s %9s %6s %5s %5s %8s %8s %8s %8s %8s %8s\n", "condition",
              "arrange", "LEARN", "AT", "none", "recall", "precision", "mirror", "size", "other",
              "pos RMS", "scatter", "ang RMS", "median", "p99", "plain");
  for (const auto& r : rows) {
    // The error less each type's mean on the part: what is left when every
    // type's own offset (taught with its model) is taken out.
    double held = 0;
    for (const auto& [type, sum] : r.on_part) {
      const cv::Point2d mean = sum.first / sum.second;
      held += sum.second * mean.dot(mean);
    }
    const double scatter = r.found ? std::sqrt(std::max(0.0, r.pos2 - held) / r.found) : 0.0;
    std::printf(
        "%-13s %-10s %5d %5d %5d %7.3f %9.3f %6d %5d %5d %8.4f %8.4f %8.4f %8.2f %8.2f %8.2f\n",
        r.condition.c_str(), r.arrangement.c_str(), r.learn_ok, r.learn_at_ok, r.untaught,
        recallOf(r), r.reported ? static_cast<double>(r.correct) / r.reported : 1.0, r.mirror,
        r.size, r.other, positionRms(r), scatter, r.angles ? std::sqrt(r.ang2 / r.angles) : 0.0,
        picksight::bench::nearestRank(r.locate_ms, 50),
        picksight::bench::nearestRank(r.locate_ms, 99),
        picksight::bench::nearestRank(r.plain_ms, 50));
  }
  std::printf(
      "goals: every type taught by LEARN or LEARN AT; recall >= 0.98; precision 1.0 (no mirror or "
      "size confusion); position RMS <= 0.05 px (<= 0.1 beside shadows, <= 0.03 clean); angle RMS "
      "<= 0.05 deg; LOCATE median <= 10 ms, p99 <= 20 ms (times here: the vision pass in process, "
      "ms, beside the plain OpenCV pass); scatter: the position RMS less each type's own mean "
      "error on the part (the offset a model is taught with; what is left varies part to part)\n");
  if (teachings > 1) {
    // What one teaching shows: the position RMS and recall each gave, and
    // their spread.
    std::printf("\nby teaching, each over the row's scenes: position RMS (px) / recall\n");
    for (const auto& r : rows) {
      std::printf("%-13s %-10s", r.condition.c_str(), r.arrangement.c_str());
      for (size_t t = 0; t < r.pos_by_teaching.size(); ++t) {
        std::printf(" %7.4f/%.3f", r.pos_by_teaching[t], r.recall_by_teaching[t]);
      }
      const auto [low, high] =
          std::minmax_element(r.pos_by_teaching.begin(), r.pos_by_teaching.end());
      std::printf("   position min %.4f max %.4f, recall min %.3f\n", *low, *high,
                  *std::min_element(r.recall_by_teaching.begin(), r.recall_by_teaching.end()));
    }
  }
  if (s.stages) {
    std::printf(
        "\nwhere the time goes (medians, ms): binarize, regions (shadows cut), of which "
        "cutting shadows (regions less the pass without), the rest of the vision pass "
        "(recognition, blob search)\n");
    std::printf("%-13s %-10s %8s %8s %8s %8s %8s\n", "condition", "arrange", "binarize", "regions",
                "shadows", "rest", "plain");
    for (const auto& r : rows) {
      const double b = picksight::bench::nearestRank(r.binarize_ms, 50);
      const double g = picksight::bench::nearestRank(r.regions_ms, 50);
      std::printf("%-13s %-10s %8.2f %8.2f %8.2f %8.2f %8.2f\n", r.condition.c_str(),
                  r.arrangement.c_str(), b, g, g - picksight::bench::nearestRank(r.uncut_ms, 50),
                  picksight::bench::nearestRank(r.locate_ms, 50) - b - g,
                  picksight::bench::nearestRank(r.plain_ms, 50));
    }
  }
  for (const auto& r : rows) {
    if (s.teach_views > 1 && r.arrangement == rows.front().arrangement) {
      std::printf("  %s: %d views per type, %d LEARNVIEWs refused\n", r.condition.c_str(),
                  s.teach_views, r.views_refused);
    }
    if (r.arrangement == rows.front().arrangement && !r.first_refusal.empty()) {
      std::printf("  %s: LEARN first refused with \"%s\"\n", r.condition.c_str(),
                  r.first_refusal.c_str());
    }
  }
  return 0;
}
