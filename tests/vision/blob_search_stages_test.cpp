// The blob search's stages one at a time (vision/blob_search/src/blob_search.hpp)
// on one blob of two drawn parts that touch, an L and a bar: which models
// may lie in it, the screened poses, the edge fit and placement, the choice
// of parts, whether they explain the blob, the anchors near what is left,
// and the hand test.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "blob_search.hpp"
#include "drawn_parts.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"
#include "touching_parts_internal.hpp"

using namespace picksight::vision;
using picksight::angleDiffDeg;
using picksight::vision::touching::BlobSearch;
using picksight::vision::touching::Candidate;
namespace pt = picksight::test;
namespace ps = picksight::synthetic;

namespace {
// An L with arms of different lengths (it differs from its mirror image),
// and a bar as wide as the L's long arm.
ps::Shape lDrawing() {
  return ps::Shape{{{{0, 0}, {100, 0}, {100, 30}, {30, 30}, {30, 70}, {0, 70}}}};
}
ps::Shape lShape() { return pt::centred(lDrawing()); }
ps::Shape bar() { return pt::centred(ps::Shape{{pt::rectLoop(90, 30)}}); }

PartModel trainAlone(const ps::Shape& shape, int type, const std::string& name) {
  const cv::Mat image = pt::drawParts(400, 300, {{shape, 200, 150, 0}}, 5);
  auto model = trainModel(image, type, name);
  INFO((model.ok() ? std::string() : model.error().message));
  REQUIRE(model.ok());
  return model.value();
}

struct Models {
  PartModel l = trainAlone(lShape(), 1, "ell");
  PartModel b = trainAlone(bar(), 2, "bar");
  // Larger than the blob: never searched.
  PartModel big = trainAlone(ps::Shape{{pt::rectLoop(260, 200)}}, 3, "big");
};

const Models& models() {
  static const Models m;
  return m;
}

// The L at (260, 220) turned by 25 degrees (mirrored when asked), and the
// bar against the end of its long arm, overlapping it by 2 px so that the
// two make one blob.
struct Scene {
  cv::Mat grey;
  std::vector<Region> regions;
  ImagePose l_pose;
  ImagePose bar_pose;
};

// The L at `l_centre` turned 25 degrees (mirrored or not) and `other`
// beside it, turned with it, its centre at `at` in the L's drawing (y
// flipped with the L); the other's pose in `bar_pose`.
Scene lAndOther(bool mirrored_l, cv::Point2d l_centre, const ps::Shape& other, cv::Point2d at) {
  const ps::ShapeMoments lm = ps::shapeMoments(lDrawing());
  const double turn = 25;
  const double c = std::cos(turn * M_PI / 180);
  const double s = std::sin(turn * M_PI / 180);
  const double flip = mirrored_l ? -1.0 : 1.0;
  const cv::Point2d offset(at.x - lm.cx, flip * (at.y - lm.cy));
  Scene scene;
  scene.l_pose = {l_centre, turn, mirrored_l};
  scene.bar_pose = {
      scene.l_pose.centre + cv::Point2d(c * offset.x - s * offset.y, s * offset.x + c * offset.y),
      turn, false};
  scene.grey =
      pt::drawParts(640, 480,
                    {{lShape(), scene.l_pose.centre.x, scene.l_pose.centre.y, turn, mirrored_l},
                     {other, scene.bar_pose.centre.x, scene.bar_pose.centre.y, turn}},
                    11);
  scene.regions = findRegions(binarize(scene.grey, {}), {}, scene.grey);
  return scene;
}

// The bar past the L's long arm's end, on its axis, 2 px over it.
Scene touchingPair(bool mirrored_l) {
  return lAndOther(mirrored_l, {260, 220}, bar(), {100 + 45 - 2, 15});
}

// A block wider than the L's arms (none of it fits in the L, nor the L's
// arm in it: the bar, as wide as the long arm, screens as one there).
ps::Shape block() { return pt::centred(ps::Shape{{pt::rectLoop(50, 40)}}); }

// The block beyond the end of the L's long arm (x = 100), half its width
// past it, its top 10 above the arm's lower side (y = 30): its side
// against the arm's end along 10 px (a contact, no overlap).
Scene blockAtArm(bool mirrored_l) {
  return lAndOther(mirrored_l, {240, 200}, block(), {100 + 25, 30 - 10 + 20});
}

std::vector<const PartModel*> all() { return {&models().l, &models().b, &models().big}; }

// Takes one part alone: the best of its model's screened poses, refined,
// within half a pixel of `truth`.
void takeAlone(BlobSearch& search, const PartModel& model, const ImagePose& truth) {
  auto screened = search.screen(model, touching::Anchors::kAll);
  REQUIRE(!screened.empty());
  screened.resize(1);
  search.refine(screened);
  search.choose();
  REQUIRE(search.taken().size() == 1);
  const Candidate& taken = *search.placed()[search.taken().front()].candidate;
  REQUIRE(std::hypot(taken.pose.centre.x - truth.centre.x, taken.pose.centre.y - truth.centre.y) <
          0.5);
}

bool isCopy(const LoneReading& reading) { return reading.kind == LoneReading::Kind::kCopy; }

// The lone-region reading of `list` (see readLoneRegion), as recognize()
// hands it to the blob search.
LoneRegionTest loneReadingOf(const std::vector<const PartModel*>& list) {
  double tolerance = 0;
  for (const PartModel* m : list) tolerance = std::max(tolerance, m->edge_tolerance);
  return [list, tolerance](const Region& r) { return readLoneRegion(r, list, tolerance); };
}

bool near(const ImagePose& a, const ImagePose& b, const PartModel& m, double px, double deg) {
  return std::hypot(a.centre.x - b.centre.x, a.centre.y - b.centre.y) <= px &&
         angleDiffDeg(a.angle_deg, b.angle_deg, m.symmetryDeg()) <= deg;
}

const Candidate* closest(const std::deque<Candidate>& refined, const PartModel& m,
                         const ImagePose& truth) {
  const Candidate* best = nullptr;
  for (const auto& c : refined) {
    if (c.model != &m) continue;
    const double d = std::hypot(c.pose.centre.x - truth.centre.x, c.pose.centre.y - truth.centre.y);
    if (!best || d < std::hypot(best->pose.centre.x - truth.centre.x,
                                best->pose.centre.y - truth.centre.y)) {
      best = &c;
    }
  }
  return best;
}
}  // namespace

TEST_CASE("blob search: only the models no larger than the blob are searched",
          "[vision][blob_search]") {
  const Scene scene = touchingPair(false);
  REQUIRE(scene.regions.size() == 1);
  const auto models_list = all();
  const BlobSearch search(scene.regions, 0, models_list, nullptr);
  const auto& fitting = search.fitting();
  REQUIRE(fitting.size() == 2);
  CHECK(fitting[0] == &models().l);
  CHECK(fitting[1] == &models().b);
  // The blob's anchors: the L's corners and the bar's, less those the
  // contact hides.
  CHECK(search.corners().corners.size() >= 6);
}

TEST_CASE("blob search: screening proposes the part's pose, best first, no two alike",
          "[vision][blob_search]") {
  const Scene scene = touchingPair(false);
  REQUIRE(scene.regions.size() == 1);
  const auto models_list = all();
  const BlobSearch search(scene.regions, 0, models_list, nullptr);
  const PartModel& l = models().l;
  for (const bool quick : {true, false}) {
    INFO("quick " << quick);
    const auto screened =
        search.screen(l, quick ? touching::Anchors::kQuick : touching::Anchors::kAll);
    REQUIRE(!screened.empty());
    CHECK(screened.size() <= 8);
    for (size_t i = 1; i < screened.size(); ++i) {
      CHECK(screened[i - 1].score >= screened[i].score);
      for (size_t j = 0; j < i; ++j) CHECK_FALSE(near(screened[i].pose, screened[j].pose, l, 2, 3));
    }
    // A corner's pose is a few degrees and pixels off before the edge fit.
    CHECK(near(screened.front().pose, scene.l_pose, l, 4, 4));
  }
}

TEST_CASE("blob search: the edge fit puts a screened pose on the part, placed in the blob",
          "[vision][blob_search]") {
  const Scene scene = touchingPair(false);
  REQUIRE(scene.regions.size() == 1);
  const auto models_list = all();
  BlobSearch search(scene.regions, 0, models_list, nullptr);
  const PartModel& l = models().l;
  search.refine(search.screen(l, touching::Anchors::kAll));
  const Candidate* fitted = closest(search.refined(), l, scene.l_pose);
  REQUIRE(fitted);
  CHECK(near(fitted->pose, scene.l_pose, l, 0.3, 0.5));
  CHECK(fitted->score * 100 >= l.verify_percent);
  const auto& placed = search.placed();
  CHECK(std::any_of(placed.begin(), placed.end(),
                    [&](const auto& p) { return p.candidate == fitted; }));
  // The same part 40 px off lies on the background: not placed.
  const Candidate off{&l, {fitted->pose.centre + cv::Point2d(0, 40), 25, false}, 0.95, 0.1, 0};
  CHECK_FALSE(search.place(off));
}

TEST_CASE("blob search: the parts are chosen and explain the blob whole", "[vision][blob_search]") {
  const Scene scene = touchingPair(false);
  REQUIRE(scene.regions.size() == 1);
  const auto models_list = all();
  BlobSearch search(scene.regions, 0, models_list, nullptr);
  // The L alone leaves the bar's pixels unexplained.
  search.refine(search.screen(models().l, touching::Anchors::kAll));
  search.choose();
  REQUIRE(search.taken().size() == 1);
  CHECK_FALSE(search.explainsWhole());
  // The anchors the full search goes on from lie by the bar, and the rest
  // is about the bar's area.
  const size_t corners_before = search.corners().corners.size();
  const double rest = search.narrowToRest();
  CHECK(rest == Approx(models().b.body.area).epsilon(0.2));
  CHECK(search.corners().corners.size() < corners_before);
  for (const auto& c : search.corners().corners) {
    INFO("corner at " << c.at.x << ", " << c.at.y);
    CHECK(std::hypot(c.at.x - scene.bar_pose.centre.x, c.at.y - scene.bar_pose.centre.y) < 70);
  }
  // With the bar, the two parts are the blob.
  search.refine(search.screen(models().b, touching::Anchors::kAll));
  search.choose();
  const auto matches = search.matches();
  REQUIRE(matches.size() == 2);
  CHECK(search.explainsWhole());
  for (const auto& m : matches) {
    const ImagePose& truth = m.model == &models().l ? scene.l_pose : scene.bar_pose;
    CHECK(std::hypot(m.centroid.x - truth.centre.x, m.centroid.y - truth.centre.y) < 0.3);
    CHECK(angleDiffDeg(m.angle_deg, truth.angle_deg, m.symmetry_deg) < 0.5);
    CHECK(m.touching);
  }
  // run() is the stages in order: the same parts as locateInBlob.
  BlobSearch whole(scene.regions, 0, models_list, nullptr);
  const auto run = whole.run();
  const auto located = locateInBlob(scene.regions, 0, models_list);
  REQUIRE(run.size() == located.size());
  for (size_t i = 0; i < run.size(); ++i) {
    CHECK(run[i].model == located[i].model);
    CHECK(run[i].centroid == located[i].centroid);
    CHECK(run[i].angle_deg == located[i].angle_deg);
  }
}

TEST_CASE("blob search: a part drawn as the mirror image of its model is not reported",
          "[vision][blob_search]") {
  const PartModel& l = models().l;
  REQUIRE_FALSE(l.body.mirror_symmetric);
  const auto models_list = all();
  {
    // The L as trained: its own hand, not the mirror image.
    const Scene scene = touchingPair(false);
    REQUIRE(scene.regions.size() == 1);
    BlobSearch search(scene.regions, 0, models_list, nullptr);
    search.refine(search.screen(l, touching::Anchors::kAll));
    const Candidate* fitted = closest(search.refined(), l, scene.l_pose);
    REQUIRE(fitted);
    CHECK_FALSE(search.showsMirror(*fitted));
  }
  // The L mirrored: the bar is found, the L's model reports nothing there.
  const Scene scene = touchingPair(true);
  REQUIRE(scene.regions.size() == 1);
  BlobSearch search(scene.regions, 0, models_list, nullptr);
  const auto found = search.run();
  bool bar_found = false;
  for (const auto& m : found) {
    INFO(m.model->name << " at " << m.centroid.x << ", " << m.centroid.y);
    CHECK(m.model != &l);
    bar_found = bar_found || (m.model == &models().b &&
                              std::hypot(m.centroid.x - scene.bar_pose.centre.x,
                                         m.centroid.y - scene.bar_pose.centre.y) < 0.5);
  }
  CHECK(bar_found);
}

TEST_CASE("blob search: what the parts leave is not searched when it is a whole untaught copy",
          "[vision][blob_search]") {
  // A block against the end of the L drawn mirrored: once the block is
  // taken, what is left is the L's mirror image whole, which the region
  // tests call a copy (no part): the search ends there.
  const Scene scene = blockAtArm(true);
  REQUIRE(scene.regions.size() == 1);
  static const PartModel block_model = trainAlone(block(), 5, "block");
  const auto takeBlock = [&](BlobSearch& search) {
    takeAlone(search, block_model, scene.bar_pose);
  };
  const auto isAt = [&](const Match& m, const PartModel& model, const ImagePose& pose) {
    return m.model == &model &&
           std::hypot(m.centroid.x - pose.centre.x, m.centroid.y - pose.centre.y) < 0.5;
  };
  const std::vector<const PartModel*> taught{&models().l, &block_model};
  const LoneRegionTest copy_test = loneReadingOf(taught);
  {
    BlobSearch search(scene.regions, 0, taught, nullptr, &copy_test);
    CHECK_FALSE(isCopy(search.readRest()));  // nothing taken yet: the blob is no copy
    takeBlock(search);
    CHECK(isCopy(search.readRest()));
    CHECK(isCopy(search.readRest()));  // the same parts taken: the same answer
    // Without the test, nothing is taken for a copy.
    BlobSearch plain(scene.regions, 0, taught, nullptr);
    takeBlock(plain);
    CHECK_FALSE(isCopy(plain.readRest()));
  }
  const auto found = locateInBlob(scene.regions, 0, taught, nullptr, &copy_test);
  REQUIRE(found.size() == 1);
  CHECK(isAt(found.front(), block_model, scene.bar_pose));
  // The mirror image taught as a type of its own (a left and a right
  // bracket): what the block leaves is that type's part, not a copy, and it
  // is found.
  PartModel mirror_l;
  {
    const cv::Mat image = pt::drawParts(400, 300, {{lShape(), 200, 150, 0, true}}, 5);
    auto trained = trainModel(image, 4, "ell-mirrored");
    REQUIRE(trained.ok());
    mirror_l = trained.value();
  }
  const std::vector<const PartModel*> both_hands{&models().l, &block_model, &mirror_l};
  const LoneRegionTest hands_test = loneReadingOf(both_hands);
  BlobSearch search(scene.regions, 0, both_hands, nullptr, &hands_test);
  takeBlock(search);
  CHECK_FALSE(isCopy(search.readRest()));
  const auto both = locateInBlob(scene.regions, 0, both_hands, nullptr, &hands_test);
  CHECK(both.size() == 2);
  CHECK(std::any_of(both.begin(), both.end(),
                    [&](const Match& m) { return isAt(m, mirror_l, scene.l_pose); }));
  CHECK(std::any_of(both.begin(), both.end(),
                    [&](const Match& m) { return isAt(m, block_model, scene.bar_pose); }));
}

TEST_CASE("blob search: what the parts leave is placed from its reading when it is one part",
          "[vision][blob_search]") {
  // The L and the block against the end of its long arm: once the block is
  // taken, what is left is the L whole, which its model passes as a lone
  // region: it is placed from that reading's pose, with no model screened.
  const Scene scene = blockAtArm(false);
  REQUIRE(scene.regions.size() == 1);
  static const PartModel block_model = trainAlone(block(), 5, "block");
  const PartModel& l = models().l;
  const std::vector<const PartModel*> taught{&l, &block_model};
  const LoneRegionTest reading = loneReadingOf(taught);
  BlobSearch search(scene.regions, 0, taught, nullptr, &reading);
  takeAlone(search, block_model, scene.bar_pose);
  const LoneReading rest = search.readRest();
  CHECK(rest.kind == LoneReading::Kind::kPart);
  CHECK(rest.model == &l);
  const size_t refined = search.refined().size();
  CHECK(search.settleRest());
  CHECK(search.refined().size() == refined + 1);  // one edge fit, no screening
  REQUIRE(search.taken().size() == 2);
  const auto l_at = std::find_if(search.taken().begin(), search.taken().end(), [&](size_t i) {
    return search.placed()[i].candidate->model == &l;
  });
  REQUIRE(l_at != search.taken().end());
  CHECK(near(search.placed()[*l_at].candidate->pose, scene.l_pose, l, 0.3, 0.3));
  // Without the reading the rest is neither: the search goes on.
  BlobSearch plain(scene.regions, 0, taught, nullptr);
  takeAlone(plain, block_model, scene.bar_pose);
  CHECK(plain.readRest().kind == LoneReading::Kind::kNeither);
  CHECK_FALSE(plain.settleRest());
  CHECK(plain.taken().size() == 1);
}

TEST_CASE("blob search: a rest is a copy when mirrored or larger, never when smaller than a part",
          "[vision][blob_search]") {
  // A rest smaller than a part may be that part less what its neighbours'
  // drawn outlines took off it (a part 90 px long between two others read
  // at 0.93 of its model's scale): it is searched. The mirror image and a
  // larger copy cannot be a part of the type.
  const PartModel& l = models().l;
  const auto alone = [](const ps::Shape& shape, bool mirrored) {
    const cv::Mat image = pt::drawParts(400, 300, {{shape, 200, 150, 30, mirrored}}, 5);
    auto regions = findRegions(binarize(image, {}), {}, image);
    REQUIRE(regions.size() == 1);
    return regions.front();
  };
  const std::vector<const PartModel*> taught{&l};
  CHECK(isWholeCopy(alone(lShape(), true), taught, l.edge_tolerance));
  CHECK(isWholeCopy(alone(pt::scaled(lShape(), 1.25), false), taught, l.edge_tolerance));
  CHECK_FALSE(isWholeCopy(alone(pt::scaled(lShape(), 0.8), false), taught, l.edge_tolerance));
  CHECK_FALSE(isWholeCopy(alone(lShape(), false), taught, l.edge_tolerance));
  // Two sizes of one shape taught as two types (washers of two sizes): an
  // L between them is smaller than the large one's part, and may be that
  // part less what its neighbours took, though the small one finds it a
  // larger copy of its own; larger than both, it is a copy.
  static const PartModel small_l = trainAlone(pt::scaled(lShape(), 0.8), 6, "small ell");
  const std::vector<const PartModel*> sizes{&l, &small_l};
  CHECK(isWholeCopy(alone(pt::scaled(lShape(), 0.9), false), {&small_l}, l.edge_tolerance));
  CHECK_FALSE(isWholeCopy(alone(pt::scaled(lShape(), 0.9), false), sizes, l.edge_tolerance));
  CHECK(isWholeCopy(alone(pt::scaled(lShape(), 1.25), false), sizes, l.edge_tolerance));
}

TEST_CASE("blob search: a part touches only what shares its blob", "[vision][blob_search]") {
  // The L alone: found by the search (from its edges), it explains its
  // region whole and touches nothing.
  const cv::Mat alone = pt::drawParts(640, 480, {{lShape(), 260, 220, 25}}, 11);
  const auto regions = findRegions(binarize(alone, {}), {}, alone);
  REQUIRE(regions.size() == 1);
  const auto lone = locateInBlob(regions, 0, {&models().l});
  REQUIRE(lone.size() == 1);
  CHECK(lone.front().from_edges);
  CHECK_FALSE(lone.front().touching);
  // An L 7 % larger than the one taught, alone: the model fits it loosely
  // (the search goes on looking for more), but it leaves only a rim of its
  // blob and touches nothing.
  const cv::Mat loose = pt::drawParts(640, 480, {{pt::scaled(lShape(), 1.07), 260, 220, 25}}, 11);
  const auto loose_regions = findRegions(binarize(loose, {}), {}, loose);
  REQUIRE(loose_regions.size() == 1);
  BlobSearch search(loose_regions, 0, {&models().l}, nullptr);
  const auto found = search.run();
  REQUIRE(found.size() == 1);
  CHECK_FALSE(search.explainsWhole());
  CHECK_FALSE(found.front().touching);
  // The L against the bar, searched with the L's model alone: one part
  // found, the bar's pixels left over: it touches them.
  const Scene pair = touchingPair(false);
  REQUIRE(pair.regions.size() == 1);
  const auto beside = locateInBlob(pair.regions, 0, {&models().l});
  REQUIRE(beside.size() == 1);
  CHECK(beside.front().touching);
}

namespace {
// The touching pair with the end of the L's short arm, from `from_y` (in
// the L's drawing) to past its end, cut out of the mask, as a threshold
// loses a thin limb whose light is uneven at low contrast; the grey levels
// where they still show the arm faint (darker than the surface by
// `faint_share` of the contrast), and where the arm is truly missing (the surface's
// level there).
struct ArmCut {
  Scene pair;
  cv::Mat mask;
  cv::Mat faint;
  cv::Mat missing;
  // The one blob of the mask, read with `grey`'s levels.
  std::vector<Region> regions(const cv::Mat& grey) const {
    auto found = findRegions(mask, {}, grey);
    REQUIRE(found.size() == 1);
    return found;
  }
};

ArmCut armCut(double from_y, double faint_share) {
  ArmCut cut{touchingPair(false), {}, {}, {}};
  const Scene& pair = cut.pair;
  const ps::ShapeMoments lm = ps::shapeMoments(lDrawing());
  const double c = std::cos(25 * M_PI / 180);
  const double s = std::sin(25 * M_PI / 180);
  std::vector<cv::Point> tip;
  for (const cv::Point2d d : {cv::Point2d(-3, from_y), cv::Point2d(33, from_y), cv::Point2d(33, 74),
                              cv::Point2d(-3, 74)}) {
    const cv::Point2d q(d.x - lm.cx, d.y - lm.cy);
    tip.emplace_back(static_cast<int>(std::lround(pair.l_pose.centre.x + c * q.x - s * q.y)),
                     static_cast<int>(std::lround(pair.l_pose.centre.y + s * q.x + c * q.y)));
  }
  cut.mask = binarize(pair.grey, {});
  cv::fillPoly(cut.mask, std::vector<std::vector<cv::Point>>{tip}, cv::Scalar(0));
  cv::Mat in_tip(cut.mask.size(), CV_8UC1, cv::Scalar(0));
  cv::fillPoly(in_tip, std::vector<std::vector<cv::Point>>{tip}, cv::Scalar(255));
  cut.faint = pair.grey.clone();
  cut.faint.setTo(cv::Scalar(200 - faint_share * 155), in_tip & (pair.grey < 190));
  cut.missing = pair.grey.clone();
  cv::fillPoly(cut.missing, std::vector<std::vector<cv::Point>>{tip}, cv::Scalar(200));
  return cut;
}
}  // namespace

TEST_CASE("blob search: a stretch of a part the mask lost is read from the grey levels",
          "[vision][blob_search]") {
  // The arm's last 5 px, faint at 0.6 of the contrast: the L's boundary
  // there is on a part, not the background; truly missing, the L's model
  // crosses the background there, as a look-alike would.
  const ArmCut cut = armCut(65, 0.6);
  const auto lFound = [&](const cv::Mat& grey) {
    for (const auto& m : locateInBlob(cut.regions(grey), 0, {&models().l, &models().b})) {
      if (m.model == &models().l && std::hypot(m.centroid.x - cut.pair.l_pose.centre.x,
                                               m.centroid.y - cut.pair.l_pose.centre.y) < 2)
        return true;
    }
    return false;
  };
  CHECK(lFound(cut.faint));
  CHECK_FALSE(lFound(cut.missing));
}

TEST_CASE("blob search: a part lying off its blob where the grey levels show it is placed",
          "[vision][blob_search]") {
  // The arm's last 9.5 px lost: 6.8 % of the L lies off its blob, more
  // than a placed part may (kMaxOutside, 6 %). Where the grey levels show
  // that stretch (at 0.9 of the contrast) it is the part's, not off it: the
  // L verified at its pose is placed. Truly missing, it is not.
  const ArmCut cut = armCut(60.5, 0.45);
  const auto placed = [&](const cv::Mat& grey) {
    const auto regions = cut.regions(grey);
    const std::vector<const PartModel*> list{&models().l, &models().b};
    BlobSearch search(regions, 0, list, nullptr);
    const Candidate verified{&models().l, cut.pair.l_pose, 0.9, 0.1, 0};
    return search.place(verified);
  };
  CHECK(placed(cut.faint));
  CHECK_FALSE(placed(cut.missing));
}

namespace {
// A disc 30 px across, taught alone; `centres` drawn as one blob.
const PartModel& discModel() {
  static const PartModel m = trainAlone(ps::Shape{{pt::circleLoop(15, {0, 0})}}, 4, "disc");
  return m;
}

// The discs found in the one blob of `centres` drawn, each matched to the
// nearest centre (farther than 0.3 px: not matched).
std::pair<size_t, size_t> discsFound(const std::vector<cv::Point2d>& centres) {
  std::vector<pt::DrawnPart> parts;
  for (const auto& c : centres)
    parts.push_back({ps::Shape{{pt::circleLoop(15, {0, 0})}}, c.x, c.y, 0});
  const cv::Mat grey = pt::drawParts(400, 300, parts, 21);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const auto found = locateInBlob(regions, 0, {&discModel()});
  size_t matched = 0;
  for (const auto& f : found) {
    for (const auto& c : centres) {
      if (std::hypot(f.centroid.x - c.x, f.centroid.y - c.y) < 0.3) {
        ++matched;
        break;
      }
    }
  }
  return {found.size(), matched};
}
}  // namespace

TEST_CASE("blob search: every disc of a pile larger than one screening is found",
          "[vision][blob_search]") {
  // A disc's turn is unseen by its edges: the edge fit must still settle.
  // Twelve discs 29 px apart in two rows of six (each overlapping its
  // neighbours by a pixel: one blob), more than one screening keeps.
  std::vector<cv::Point2d> grid;
  for (int row = 0; row < 2; ++row) {
    for (int col = 0; col < 6; ++col) grid.emplace_back(110 + 29 * col, 130 + 29 * row);
  }
  const auto [found, matched] = discsFound(grid);
  CHECK(found == 12);
  CHECK(matched == 12);
}

TEST_CASE("blob search: a disc overlapped on both sides still shows enough of its rim",
          "[vision][blob_search]") {
  // Three discs 23 px apart in a row: 0.63 of the middle one's rim lies
  // on edges (0.57 at 21 px, 0.72 at 25).
  const auto [found, matched] = discsFound({{150, 150}, {173, 150}, {196, 150}});
  CHECK(found == 3);
  CHECK(matched == 3);
}

TEST_CASE("blob search: a part placed on the relief inside a larger part is refused",
          "[vision][blob_search]") {
  // A large disc whose face shows eight specks of 3 x 3 px (the relief of a
  // coin under a lamp: small holes in the mask, past the pinholes that are
  // not counted) on a circle as wide as the small disc taught: a pose of the
  // small disc there has its rim by those specks' edges, and nowhere on the
  // large disc's outline.
  const cv::Point2d centre(200, 150);
  ps::Shape face{{pt::circleLoop(40, {0, 0})}};
  for (int k = 0; k < 8; ++k) {
    const double a = k * M_PI / 4;
    face.loops.push_back(pt::rectLoop(3, 3, {15 * std::cos(a), 15 * std::sin(a)}));
  }
  const cv::Mat grey = pt::drawParts(400, 300, {{face, centre.x, centre.y, 0}}, 5);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  REQUIRE(regions[0].holes >= 6);
  BlobSearch search(regions, 0, {&discModel()}, nullptr);
  Candidate inside{&discModel(), {centre, 0, false}, 0.9};
  CHECK_FALSE(search.place(inside));
  // A small disc drawn against the large one's rim: most of its boundary
  // on the blob's outline, placed.
  const cv::Point2d beside = centre + cv::Point2d(54, 0);
  const cv::Mat pair =
      pt::drawParts(400, 300,
                    {{face, centre.x, centre.y, 0},
                     {ps::Shape{{pt::circleLoop(15, {0, 0})}}, beside.x, beside.y, 0}},
                    5);
  const auto pair_regions = findRegions(binarize(pair, {}), {}, pair);
  REQUIRE(pair_regions.size() == 1);
  BlobSearch pair_search(pair_regions, 0, {&discModel()}, nullptr);
  Candidate touching{&discModel(), {beside, 0, false}, 0.9};
  CHECK(pair_search.place(touching));
}

TEST_CASE("blob search: a patch of the surface's light is not searched, a faint pair of parts is",
          "[vision][blob_search][front]") {
  const auto models_list = all();
  {
    // A vignetted corner or a blotch of a belt: the surface 10 levels darker
    // at the patch's middle, fading over 60 px, with the sensor's noise.
    // The threshold takes it in as one blob as large as the L and the bar.
    cv::Mat grey(480, 640, CV_32F);
    for (int y = 0; y < grey.rows; ++y) {
      for (int x = 0; x < grey.cols; ++x) {
        const double r2 = (x - 320.0) * (x - 320.0) + (y - 240.0) * (y - 240.0);
        grey.at<float>(y, x) = static_cast<float>(200 - 10 * std::exp(-r2 / (2 * 60.0 * 60.0)));
      }
    }
    cv::Mat noise(grey.size(), CV_32F);
    cv::RNG(5).fill(noise, cv::RNG::NORMAL, 0, 3);
    grey += noise;
    grey.convertTo(grey, CV_8U);
    cv::Mat mask;
    cv::compare(grey, 195, mask, cv::CMP_LT);
    cv::medianBlur(mask, mask, 5);
    const auto regions = findRegions(mask, {}, grey);
    REQUIRE(!regions.empty());
    CAPTURE(regions[0].area);
    REQUIRE(regions[0].area > models().l.body.area * 1.5);
    const BlobSearch search(regions, 0, models_list, nullptr);
    CHECK(search.fitting().empty());
    CHECK(locateInBlob(regions, 0, models_list).empty());
  }
  {
    // The L and the bar touching, 13 grey levels darker than their surface
    // (the faintest parts of the front-light benchmark's low contrast),
    // with noise of 3 levels: their outline steps, and they are searched.
    const Scene scene = touchingPair(false);
    cv::Mat faint;
    scene.grey.convertTo(faint, CV_32F, 13.0 / 155.0, 200.0 * (1 - 13.0 / 155.0));
    cv::Mat noise(faint.size(), CV_32F);
    cv::RNG(7).fill(noise, cv::RNG::NORMAL, 0, 3);
    faint += noise;
    faint.convertTo(faint, CV_8U);
    const auto regions = findRegions(binarize(faint, {}), {}, faint);
    REQUIRE(!regions.empty());
    CAPTURE(regions[0].area);
    const BlobSearch search(regions, 0, models_list, nullptr);
    CHECK(search.fitting().size() == 2);
  }
}

namespace {
// proposeAbout (the search of what the parts found leave) over the whole
// turn: `shape` alone, drawn sharp at each turn, searched about middles 4
// and 12 px from its reference point; how many of the searches proposed
// its pose, within 4.5 px and 4 degrees.
std::pair<int, int> aboutEveryTurn(const PartModel& model, const ps::Shape& shape) {
  const auto search = touching::searchOf(model);
  const double loose = touching::kLooseScreenFactor * model.edge_tolerance;
  int found = 0;
  int tried = 0;
  for (double turn = 3.7; turn < 360; turn += 5.3) {
    const cv::Point2d at(260.3, 220.6);
    const cv::Mat grey = pt::drawParts(520, 440, {{shape, at.x, at.y, turn}}, 3);
    const auto regions = findRegions(binarize(grey, {}), {}, grey);
    REQUIRE(regions.size() == 1);
    const std::vector<std::vector<cv::Point>> contours{regions[0].outer};
    const cv::Rect box = regions[0].bbox + cv::Size(40, 40) - cv::Point(20, 20);
    const EdgeDistance edges(contours, box, loose);
    const EdgeDistance wide(contours, box, loose + touching::kAboutWidePx);
    for (const cv::Point2d off : {cv::Point2d(4, 4), cv::Point2d(-4, 4), cv::Point2d(4, -4),
                                  cv::Point2d(-4, -4), cv::Point2d(12, -4), cv::Point2d(-4, 12)}) {
      std::vector<Candidate> proposed;
      touching::proposeAbout(model, *search, at - off, edges, wide, &proposed);
      ++tried;
      INFO("turn " << turn << ", middle " << off.x << " " << off.y << " px off");
      if (proposed.size() != 1) continue;
      const ImagePose& got = proposed[0].pose;
      INFO("proposed " << got.centre.x - at.x << " " << got.centre.y - at.y << " px off, turned "
                       << got.angle_deg);
      if (near(got, {at, turn, false}, model, 4.5, 4.0)) ++found;
    }
  }
  return {found, tried};
}
}  // namespace

TEST_CASE("blob search: searched about a middle a part between the first look's poses is found",
          "[vision][blob_search]") {
  // The rest search's first look reads reference points 8 px apart and
  // turns 12 px apart at the rim, more loosely than the second: a part
  // whose reference point lies between four of those points and whose turn
  // lies between two of those turns must still be found, in every turn;
  // also with the model's edge tolerance set tighter than taught
  // (TOLERANCE ... edge_tolerance_px 1), where the first look's wider
  // reading is what finds it.
  for (const double tolerance : {0.0, 1.0}) {
    PartModel model = models().l;
    if (tolerance > 0) model.edge_tolerance = tolerance;
    INFO("edge tolerance " << model.edge_tolerance << " px");
    const auto [found, tried] = aboutEveryTurn(model, lShape());
    CHECK(found == tried);
  }
}

namespace {
// A plate 90 x 30 px with a stick `wide` px across and 16 px long out of
// the middle of one long side, in the frame of the whole part's centroid;
// and the plate alone in the same frame (the stick not in the frame at
// all, as a thin stretch of a part at 30 grey levels of contrast is not).
struct Stick {
  ps::Shape whole;
  ps::Shape plate;
};

Stick stickShapes(double wide) {
  const double half = wide / 2;
  const ps::Shape whole{{{{0, 0},
                          {90, 0},
                          {90, 30},
                          {45 + half, 30},
                          {45 + half, 46},
                          {45 - half, 46},
                          {45 - half, 30},
                          {0, 30}}}};
  const ps::ShapeMoments m = ps::shapeMoments(whole);
  Stick s{whole, ps::Shape{{pt::rectLoop(90, 30, {45, 15})}}};
  for (ps::Shape* shape : {&s.whole, &s.plate}) {
    for (auto& loop : shape->loops) {
      for (auto& p : loop) p -= cv::Point2d(m.cx, m.cy);
    }
  }
  return s;
}

// Whether the part, taught whole, is placed where it lies without its
// stick against the bar (one blob), at its true pose and verified.
bool placedWithoutStick(double wide) {
  const Stick s = stickShapes(wide);
  const PartModel model = trainAlone(s.whole, 5, "stick");
  const ImagePose pose{{300, 200}, 20, false};
  // The bar along the plate's long side away from the stick, 2 px into it.
  const double c = std::cos(20 * M_PI / 180);
  const double sn = std::sin(20 * M_PI / 180);
  const ps::ShapeMoments m = ps::shapeMoments(s.whole);
  const cv::Point2d bar_at(45 - m.cx, -15 + 2 - m.cy);
  const cv::Mat grey = pt::drawParts(640, 480,
                                     {{s.plate, pose.centre.x, pose.centre.y, 20},
                                      {bar(), pose.centre.x + c * bar_at.x - sn * bar_at.y,
                                       pose.centre.y + sn * bar_at.x + c * bar_at.y, 20}},
                                     13);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const std::vector<const PartModel*> list{&model, &models().b};
  BlobSearch search(regions, 0, list, nullptr);
  const Candidate verified{&model, pose, 0.9, 0.1, 0};
  return search.place(verified);
}
}  // namespace

TEST_CASE("blob search: a part whose thin stick does not show is placed, a wide one is missed",
          "[vision][blob_search]") {
  // A stick 3 px across missing: its outline (13 % of the part's) crosses
  // the background, but a stretch that thin may not show at all under a
  // poor light (kThinHalfWidthPx). One 12 px across missing is a part that
  // is not there: refused, the blob holding more than the part.
  CHECK(placedWithoutStick(3));
  CHECK_FALSE(placedWithoutStick(12));
}

TEST_CASE("blob search: two touching parts no anchor led to are found about their own middles",
          "[vision][blob_search]") {
  // A disc and a square whose corner meets its rim: one blob with a neck
  // where they touch. Nothing taken (as when the noisy corners of a faint
  // pair lead nowhere), the search about the blob's middle alone lies
  // between the two, where neither is; the pieces the blob parts into at
  // the neck each hold one part.
  const ps::Shape disc{{pt::circleLoop(55)}};
  const ps::Shape square{{pt::rectLoop(90, 90)}};
  const PartModel disc_model = trainAlone(disc, 1, "disc");
  const PartModel square_model = trainAlone(square, 2, "square");
  const double towards = 20;
  const cv::Point2d disc_at(220, 240);
  // The square's corner 2 px inside the rim, on the line at `towards`.
  const cv::Point2d along(std::cos(towards * M_PI / 180), std::sin(towards * M_PI / 180));
  const cv::Point2d square_at = disc_at + (55 - 2 + 45 * std::sqrt(2.0)) * along;
  const double square_turn = towards + 45;
  const cv::Mat grey = pt::drawParts(
      640, 480, {{disc, disc_at.x, disc_at.y, 0}, {square, square_at.x, square_at.y, square_turn}},
      13);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const std::vector<const PartModel*> models_list{&disc_model, &square_model};
  BlobSearch search(regions, 0, models_list, nullptr);
  REQUIRE(search.fitting().size() == 2);
  search.searchRestMiddle();
  search.choose();
  REQUIRE(search.taken().size() == 2);
  bool disc_found = false;
  bool square_found = false;
  for (const size_t i : search.taken()) {
    const Candidate& c = *search.placed()[i].candidate;
    if (c.model == &disc_model) {
      disc_found = std::hypot(c.pose.centre.x - disc_at.x, c.pose.centre.y - disc_at.y) < 0.5;
    } else {
      square_found = near(c.pose, {square_at, square_turn, false}, square_model, 0.5, 0.5);
    }
  }
  CHECK(disc_found);
  CHECK(square_found);
}

namespace {
// The one part the search of what a blob leaves (searchRestMiddle, nothing
// found in it before) takes in region 0, `model` the only one searched.
Candidate onlyPartFromRest(const std::vector<Region>& regions, const PartModel& model) {
  const std::vector<const PartModel*> models_list{&model};
  BlobSearch search(regions, 0, models_list, nullptr);
  REQUIRE(search.fitting().size() == 1);
  search.searchRestMiddle();
  search.choose();
  REQUIRE(search.taken().size() == 1);
  return *search.placed()[search.taken().front()].candidate;
}
}  // namespace

TEST_CASE("blob search: a part touching an untaught shape at a point is found about its own middle",
          "[vision][blob_search]") {
  // A disc and a larger square no model knows, its corner just meeting the
  // disc's rim: the rest parts in two under the seam, and the larger piece,
  // searched first, is the square. Nothing taken there, the disc's piece is
  // searched about its own middle.
  const ps::Shape disc{{pt::circleLoop(45)}};
  const ps::Shape square{{pt::rectLoop(150, 150)}};
  const PartModel disc_model = trainAlone(disc, 1, "disc");
  const double towards = 30;
  const cv::Point2d disc_at(200, 260);
  const cv::Point2d along(std::cos(towards * M_PI / 180), std::sin(towards * M_PI / 180));
  const cv::Point2d square_at = disc_at + (45 - 1 + 75 * std::sqrt(2.0)) * along;
  const cv::Mat grey = pt::drawParts(
      640, 520, {{disc, disc_at.x, disc_at.y, 0}, {square, square_at.x, square_at.y, towards + 45}},
      17);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const Candidate c = onlyPartFromRest(regions, disc_model);
  CHECK(c.model == &disc_model);
  CHECK(std::hypot(c.pose.centre.x - disc_at.x, c.pose.centre.y - disc_at.y) < 0.5);
}

namespace {
// A public silhouette of the test data (tests/data/`file`), `size` px
// across, as a polygon about its centroid.
ps::Shape drawnShape(const std::string& file, double size) {
  const cv::Mat drawing = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + file, cv::IMREAD_GRAYSCALE);
  REQUIRE(!drawing.empty());
  const ps::SilhouetteType type = ps::silhouetteFromDrawing(file, drawing, size);
  std::vector<std::vector<cv::Point>> outlines;
  cv::findContours(type.mask, outlines, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  REQUIRE(outlines.size() == 1);
  // The mask is drawn finer than the image (supersampled): its outline
  // scaled to `size` across.
  const cv::Rect box = cv::boundingRect(outlines.front());
  const double scale = size / std::max(box.width, box.height);
  pt::Loop loop;
  for (const cv::Point& p : outlines.front()) loop.emplace_back(p.x * scale, p.y * scale);
  return pt::centred(ps::Shape{{loop}});
}
}  // namespace

TEST_CASE("blob search: a part a thinner untaught bar lies over is found about its deepest core",
          "[vision][blob_search]") {
  // A drawing nobody here drew (tari1000 obj21, a bird 200 px across,
  // thickest off its middle: its deepest core's middle lies 19 px from its
  // centroid) with a bar no model knows lying over its side, 30 px of the
  // bar on the bird: one blob, no neck between them, whose middle lies
  // between the two, far beyond the dozen pixels the search about a middle
  // covers. Nothing taken there (as when a faint part's corners lead
  // nowhere), the blob's deepest core is the bird's own: searched about it,
  // each turn putting the bird's reference point where its core's middle
  // says, it is found. Three turns of the pair.
  const ps::Shape bird = drawnShape("shapes/tari1000/obj21_9.png", 200);
  const PartModel model = trainAlone(bird, 1, "bird");
  const ps::Shape bar{{pt::rectLoop(240, 30)}};
  for (const double turn : {0.0, 130.0, 250.0}) {
    CAPTURE(turn);
    const cv::Point2d at(330, 300);
    // The bar along the line at `turn`, its near end 30 px over the bird's
    // outline on that line.
    const cv::Point2d along(std::cos(turn * M_PI / 180), std::sin(turn * M_PI / 180));
    double reach = 0;  // the bird's outline from its centroid along the line
    for (const auto& p : bird.loops.front()) {
      const cv::Point2d q(p.x, p.y);
      const double t = q.dot(along);
      const double off = std::abs(q.x * along.y - q.y * along.x);
      if (off < 2) reach = std::max(reach, t);
    }
    const cv::Point2d bar_at = at + (reach - 30 + 120) * along;
    const cv::Mat grey =
        pt::drawParts(720, 640, {{bird, at.x, at.y, 0}, {bar, bar_at.x, bar_at.y, turn}}, 23);
    const auto regions = findRegions(binarize(grey, {}), {}, grey);
    REQUIRE(regions.size() == 1);
    // The blob's middle as far from the bird's as the scene means.
    REQUIRE(cv::norm(regions[0].centroid - at) > 24);
    const Candidate c = onlyPartFromRest(regions, model);
    CHECK(near(c.pose, {at, 0, false}, model, 0.5, 0.5));
  }
}

TEST_CASE("an outline's edge is bridged across the samples that found no crossing",
          "[vision][edge_fit]") {
  using picksight::vision::touching::bridgedOffsets;
  const auto none = std::nullopt;
  // A straight run between the crossings either side of a gap.
  const auto inner = bridgedOffsets({1.0, none, none, 4.0});
  REQUIRE(inner.size() == 4);
  CHECK(inner[1] == Approx(2.0));
  CHECK(inner[2] == Approx(3.0));
  // Round the loop's start: the gap at 0 lies between samples 4 and 1, the
  // one at 5 between 4 and 1 the other way; crossings themselves kept.
  const auto round = bridgedOffsets({none, 2.0, none, none, 5.0, none});
  REQUIRE(round.size() == 6);
  CHECK(round[0] == Approx(3.0));  // 2 steps from 5.0, 1 from 2.0
  CHECK(round[1] == Approx(2.0));
  CHECK(round[2] == Approx(3.0));
  CHECK(round[3] == Approx(4.0));
  CHECK(round[4] == Approx(5.0));
  CHECK(round[5] == Approx(4.0));
  // One crossing in the loop: the boundary moved by it all round; none:
  // the boundary as it is.
  const auto one = bridgedOffsets({none, -0.5, none});
  CHECK(one == std::vector<double>{-0.5, -0.5, -0.5});
  CHECK(bridgedOffsets({none, none}) == std::vector<double>{0.0, 0.0});
}

TEST_CASE("an outline's centroid is read across a stretch with no crossing from the edge beside it",
          "[vision][edge_fit]") {
  // A plate with a tab of something else against the middle of its right
  // side, 40 px of it further out than the search reaches: no crossing
  // there. The plate's model placed a pixel to the right of the plate: the
  // crossings beside the tab lie a pixel inside the boundary, and so does
  // the edge read across it, not the boundary (which would put 40 px^2 of
  // the tab, 60 px out, into the plate: its centroid a third of a pixel to
  // the right). Against the plate alone read the same way.
  const ps::Shape plate{{pt::rectLoop(120, 60)}};
  const PartModel model = trainAlone(plate, 1, "plate");
  const cv::Mat alone = pt::drawParts(400, 300, {{plate, 200, 150, 0}}, 5);
  const auto by_itself = findRegions(binarize(alone, {}), {}, alone);
  REQUIRE(by_itself.size() == 1);
  const auto truth = outlineCentroid(model, by_itself[0], {{200, 150}, 0, false});
  REQUIRE(truth);
  const ps::Shape tab{{pt::rectLoop(8, 40)}};
  const cv::Mat grey = pt::drawParts(400, 300, {{plate, 200, 150, 0}, {tab, 263, 150, 0}}, 5);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const auto centroid = outlineCentroid(model, regions[0], {{201, 150}, 0, false});
  REQUIRE(centroid);
  INFO("centroid " << *centroid << ", the plate alone " << *truth);
  // Measured 0.10 px (the tab's blurred corners move the crossings at the
  // ends of the stretch outwards); 0.32 with the boundary across the tab.
  CHECK(cv::norm(*centroid - *truth) < 0.17);
}

TEST_CASE("blob search: a mesh running off the frame holds no part whole, and is not searched",
          "[vision][blob_search][front]") {
  // Where the threshold speckles a dark stretch of the surface at a low
  // contrast (gravel's crevices, a vignetted corner), it makes a mesh of
  // strands a few pixels wide that runs off the frame and steps along its
  // outline as a part's edge does. No part lies whole in it: what an
  // erosion of the seam's width leaves of it is crumbs, smaller than any
  // model leaves of its part. Searched, such blobs cost the front-light
  // benchmark's gravel scenes their slowest LOCATEs.
  std::vector<pt::DrawnPart> mesh;
  const ps::Shape strand_down = pt::centred(ps::Shape{{pt::rectLoop(3, 204)}});
  const ps::Shape strand_across = pt::centred(ps::Shape{{pt::rectLoop(262, 3)}});
  for (int k = 0; k <= 18; ++k) mesh.push_back({strand_down, 200.0 + 14 * k, 100, 0});
  for (int k = 0; k <= 13; ++k) mesh.push_back({strand_across, 331, 10.0 + 14 * k, 0});
  RegionOptions keep;
  keep.keep_border_regions = true;
  const auto regionsOf = [&](const std::vector<pt::DrawnPart>& parts) {
    const cv::Mat grey = pt::drawParts(640, 480, parts, 9);
    return findRegions(binarize(grey, {}), keep, grey);
  };
  const auto models_list = all();
  {
    const auto regions = regionsOf(mesh);
    REQUIRE(regions.size() == 1);
    REQUIRE(regions[0].touches_border);
    // As large as the L and the bar both, and as long and wide.
    REQUIRE(regions[0].area > models().l.body.area + models().b.body.area);
    const BlobSearch search(regions, 0, models_list, nullptr);
    CHECK(search.fitting().empty());
  }
  {
    // The L joined to the mesh's lower edge: the blob holds it whole, and it
    // is searched for and found.
    std::vector<pt::DrawnPart> with_l = mesh;
    with_l.push_back({lShape(), 330.3, 226.6, 0});
    const auto regions = regionsOf(with_l);
    REQUIRE(regions.size() == 1);
    const BlobSearch search(regions, 0, models_list, nullptr);
    CHECK(std::find(search.fitting().begin(), search.fitting().end(), &models().l) !=
          search.fitting().end());
    const auto found = locateInBlob(regions, 0, models_list);
    for (const auto& m : found) UNSCOPED_INFO(m.model->name << " at " << m.centroid);
    CHECK(std::any_of(found.begin(), found.end(), [](const Match& m) {
      return m.model == &models().l && std::hypot(m.centroid.x - 330.3, m.centroid.y - 226.6) < 1.0;
    }));
  }
  {
    // A slender rod lying diagonally, hung on the mesh by its tip: the
    // square erosion eats into its long sides by 2.8 px, not 2, and leaves
    // less of it than its area less a 2 px seam (978 px against 1109): it
    // is still searched for, and found.
    const ps::Shape rod_shape = pt::centred(ps::Shape{{pt::rectLoop(160, 12)}});
    static const PartModel rod = trainAlone(rod_shape, 4, "rod");
    std::vector<pt::DrawnPart> with_rod = mesh;
    with_rod.push_back({pt::centred(ps::Shape{{pt::rectLoop(2, 24)}}), 400, 208, 0});
    with_rod.push_back({rod_shape, 455.2, 271.9, 45});
    const auto regions = regionsOf(with_rod);
    REQUIRE(regions.size() == 1);
    const std::vector<const PartModel*> rod_only{&rod};
    const BlobSearch search(regions, 0, rod_only, nullptr);
    CHECK(search.fitting().size() == 1);
    const auto found = locateInBlob(regions, 0, rod_only);
    for (const auto& m : found) UNSCOPED_INFO(m.model->name << " at " << m.centroid);
    CHECK(std::any_of(found.begin(), found.end(), [](const Match& m) {
      return std::hypot(m.centroid.x - 455.2, m.centroid.y - 271.9) < 1.0;
    }));
  }
}
