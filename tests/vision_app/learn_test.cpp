// Teaching that cannot break silently: a part learned from a tight crop has
// no phantom holes and is found in a full frame, LEARN AT picks one part of
// a scene without touching the camera, a resized frame finds the parts at
// the same sensor positions, and suspicious models are named in the reply.
#include <catch2/catch.hpp>

#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "../vision/drawn_parts.hpp"
#include "cell_fixture.hpp"
#include "picksight/app/offline_commands.hpp"
#include "picksight/app/vision_cell.hpp"
#include "picksight/cell/scaled_model_cache.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/model_commands.hpp"
#include "picksight/store/model_file.hpp"

using namespace picksight;
using namespace picksight::app;
using namespace picksight::cell;
using namespace picksight::store;
using picksight::test::DrawnPart;

namespace {
// Parts larger than the default adaptive window of a 1280 x 960 frame's
// crops: two long bars and a disc wider than a sixth of the frame.
const synthetic::Shape kBar{{test::rectLoop(320, 100)}};
const synthetic::Shape kDisc{{test::circleLoop(110)}};
const std::vector<DrawnPart> kParts{
    {kBar, 400, 300, 20}, {kDisc, 900, 600, 0}, {kBar, 320, 700, 100}};

const cv::Mat& fullFrame() {
  static const cv::Mat image = test::drawParts(1280, 960, kParts, 7);
  return image;
}

// The box of a drawn part with `margin` pixels around it.
cv::Rect boxAround(const DrawnPart& part, int margin) {
  const auto placed = synthetic::placedShape(part.shape, part.x, part.y, part.angle_deg);
  std::vector<cv::Point2f> points;
  for (const auto& p : placed.loops[0]) points.emplace_back(p);
  const cv::Rect box = cv::boundingRect(points);
  return {box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin};
}

std::string rectArgs(const cv::Rect& r) {
  return std::to_string(r.x) + " " + std::to_string(r.y) + " " + std::to_string(r.width) + " " +
         std::to_string(r.height);
}

// The located part nearest to (x, y), sensor pixels; REQUIREs one.
const LocatedPart& nearest(const std::vector<LocatedPart>& parts, double x, double y) {
  REQUIRE(!parts.empty());
  const LocatedPart* best = &parts.front();
  for (const auto& p : parts) {
    if (std::hypot(p.x - x, p.y - y) < std::hypot(best->x - x, best->y - y)) best = &p;
  }
  return *best;
}

struct StillCell {
  std::string dir;
  picksight::link::StillCamera* camera = nullptr;  // owned by the cell
  std::unique_ptr<VisionCell> cell;
  explicit StillCell(const cv::Mat& image, VisionOptions options = {}) {
    char d[] = "/tmp/picksight-learn-test-XXXXXX";
    REQUIRE(::mkdtemp(d) != nullptr);
    dir = d;
    auto still = std::make_unique<picksight::link::StillCamera>(image);
    camera = still.get();
    cell = std::make_unique<VisionCell>(dir, std::move(still), std::move(options));
    REQUIRE(cell->load().empty());
  }
  ~StillCell() {
    cell.reset();
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  std::string ask(const std::string& line) { return cell->handle(line); }
};

bool hasPointNear(const std::vector<e2e::Pose>& points, double x, double y, double tolerance) {
  for (const auto& p : points)
    if (std::hypot(p.x - x, p.y - y) <= tolerance) return true;
  return false;
}
}  // namespace

TEST_CASE("a part taught from a tight camera ROI has no phantom holes and is found in a full frame",
          "[learn][tight_crop]") {
  for (size_t k : {size_t{0}, size_t{1}}) {
    const DrawnPart& part = kParts[k];
    INFO("part " << k);
    const cv::Rect roi = boxAround(part, 12);
    const cv::Mat crop = fullFrame()(roi).clone();
    // The cause, reproduced: the crop binarized with its own default window
    // (a sixth of its smaller side, narrower than the part) breaks the
    // part's middle into holes, and such a model never matches.
    const auto naive = vision::trainModel(crop, 1, "naive");
    CHECK((!naive || naive->body.holes > 0));
    WARN("part " << k << " in a " << crop.cols << " x " << crop.rows << " crop: "
                 << (naive ? std::to_string(naive->body.holes) + " phantom holes"
                           : naive.error().message)
                 << " with the crop's own window");

    SensorMapping mapping;
    mapping.roi_x = roi.x;
    mapping.roi_y = roi.y;
    const auto learned =
        learnInImage(crop, mapping, {}, std::make_shared<const ModelList>(), 1, "part", {});
    REQUIRE(learned);
    CHECK(learned->model.body.holes == 0);
    CHECK(learned->warnings.empty());
    CHECK(learned->model.trained_centroid.x == Approx(part.x).margin(0.1));
    CHECK(learned->model.trained_centroid.y == Approx(part.y).margin(0.1));

    const auto models = std::make_shared<const ModelList>(ModelList{learned->model});
    const auto outcome = locateInFrame(frameFromImage(fullFrame(), "cam", 1), {}, models, 1);
    const size_t same = k == 0 ? 2 : 1;  // two bars, one disc
    CHECK(outcome.parts.size() == same);
    const LocatedPart& found = nearest(outcome.parts, part.x, part.y);
    CHECK(std::hypot(found.x - part.x, found.y - part.y) < 0.1);
  }
}

TEST_CASE("a part taught from a small image of it alone has no phantom holes",
          "[learn][tight_crop]") {
  // A picture of the disc alone, as an integrator would crop it: no camera,
  // identity mapping, the image barely larger than the part.
  const cv::Mat crop = fullFrame()(boxAround(kParts[1], 6)).clone();
  StillCell cell(crop);
  const std::string reply = cell.ask("LEARN 2 disc");
  INFO(reply);
  REQUIRE(reply.rfind("OK 2 disc ", 0) == 0);
  CHECK(reply.find(';') == std::string::npos);  // nothing suspicious
  const auto fields = splitFields(reply, " ");
  REQUIRE(fields.size() == 7);
  CHECK(fields[4] == "0");  // holes
  cell.camera->setImage(fullFrame());
  const auto points = e2e::imagePoses(cell.ask("LOCATE 2"));
  CHECK(points.size() == 1);
  CHECK(hasPointNear(points, kParts[1].x, kParts[1].y, 0.1));
}

TEST_CASE("LEARN AT learns one part of a scene with several", "[learn][learn_at]") {
  StillCell cell(fullFrame());
  std::string reply = cell.ask("LEARN 1 bar AT " + rectArgs(boxAround(kParts[0], 4)));
  INFO(reply);
  REQUIRE(reply.rfind("OK 1 bar ", 0) == 0);
  CHECK(reply.find(';') == std::string::npos);
  // A rectangle cutting a little off the part still selects it: the whole
  // frame is binarized, the rectangle only picks the region.
  const cv::Rect tight = boxAround(kParts[1], -8);
  reply = cell.ask("LEARN 2 AT " + rectArgs(tight));
  REQUIRE(reply.rfind("OK 2 type2 ", 0) == 0);
  const auto fields = splitFields(reply, " ");
  REQUIRE(fields.size() == 7);
  CHECK(fields[4] == "0");
  CHECK(*parseDouble(fields[3]) == Approx(M_PI * 110 * 110).epsilon(0.01));

  auto points = e2e::imagePoses(cell.ask("LOCATE 1"));
  CHECK(points.size() == 2);
  CHECK(hasPointNear(points, kParts[0].x, kParts[0].y, 0.1));
  CHECK(hasPointNear(points, kParts[2].x, kParts[2].y, 0.1));
  points = e2e::imagePoses(cell.ask("LOCATE 2"));
  CHECK(points.size() == 1);
  CHECK(hasPointNear(points, kParts[1].x, kParts[1].y, 0.1));
  // The camera was never asked to crop (a still camera refuses settings).
  CHECK(cell.ask("MODELS").rfind("OK 2 ", 0) == 0);
}

TEST_CASE("LEARN AT refuses rectangles outside the frame or without exactly one part",
          "[learn][learn_at]") {
  StillCell cell(fullFrame());
  const auto code = [&](const std::string& line) {
    const std::string reply = cell.ask(line);
    INFO(line << " -> " << reply);
    const auto w = splitFields(reply, " ");
    REQUIRE(w.size() >= 2);
    REQUIRE(w[0] == "ERROR");
    return std::string(w[1]);
  };
  CHECK(code("LEARN 1 AT 5000 5000 10 10") == "34");
  CHECK(code("LEARN 1 AT 1280 0 10 10") == "34");
  CHECK(code("LEARN 1 AT 0 0 60 60") == "35");  // an empty corner
  CHECK(code("LEARN 1 AT 0 0 1280 960") == "36");
  CHECK(code("LEARN 1 bar AT 0 0 1280 960") == "36");
  CHECK(code("LEARN 1 AT 1 2 3") == "11");
  CHECK(code("LEARN 1 AT 1 2 3 4 5") == "11");
  CHECK(code("LEARN 1 AT -1 0 5 5") == "11");
  CHECK(code("LEARN 1 AT 0 0 0 5") == "11");
  CHECK(code("LEARN 1 AT 0 0 70000 5") == "11");
  CHECK(code("LEARN 1 AT 0 0 x 5") == "11");
  CHECK(code("LEARN 1 a b AT 0 0 5 5") == "11");
  CHECK(code("LEARN AT 0 0 5 5") == "11");
  CHECK(code("LEARN 1 AT") == "11");
  // Without AT, several parts in the frame are refused as before.
  CHECK(code("LEARN 1") == "31");
  CHECK(cell.ask("MODELS") == "OK 0");  // nothing was stored
  CHECK(cell.ask("HELP").find("LEARN <type> [name] [AT <x> <y> <w> <h>]") != std::string::npos);
}

TEST_CASE("LEARN warns about phantom-looking holes a touched border and a tiny area",
          "[learn][warnings]") {
  // A plate with three pinholes: learned, but said to look suspicious.
  synthetic::Shape plate{{test::rectLoop(200, 160), test::circleLoop(2.5, {-50, 0}, 24),
                          test::circleLoop(2.5, {0, 30}, 24),
                          test::circleLoop(2.5, {60, -40}, 24)}};
  StillCell cell(test::drawParts(640, 480, {{plate, 320, 240, 0}}, 3));
  std::string reply = cell.ask("LEARN 1 plate");
  INFO(reply);
  REQUIRE(reply.rfind("OK 1 plate ", 0) == 0);
  // The leading fields are those of a reply without warnings.
  const std::string head = reply.substr(0, reply.find(" ;"));
  CHECK(splitFields(head, " ").size() == 7);
  CHECK(splitFields(head, " ")[4] == "3");
  // 0.5 % of the plate's area (as measured, about 32000 px).
  const double area = std::stod(std::string(splitFields(head, " ")[3]));
  CHECK(area == Approx(200 * 160).epsilon(0.01));
  const std::string warning = " ; warning: 3 holes smaller than " +
                              std::to_string(std::lround(0.005 * area)) +
                              " px (noise or uneven light? every LOCATE needs the same count; "
                              "VISION min_hole_area ";
  REQUIRE(reply.substr(head.size(), warning.size()) == warning);
  // The setting it names: just over the largest pinhole (pi 2.5^2, about
  // 20 px drawn), under the holes a part is made with.
  const std::string named = reply.substr(head.size() + warning.size());
  const int leave_out = std::stoi(named);
  CHECK(named == std::to_string(leave_out) + " and LEARN again leaves them out)");
  CHECK(leave_out > 12);
  CHECK(leave_out < 40);

  // Doing what it says: the pinholes are not counted, nothing is warned,
  // and the setting is stored with the model.
  CHECK(cell.ask("VISION min_hole_area " + std::to_string(leave_out)).rfind("OK ", 0) == 0);
  reply = cell.ask("LEARN 1 plate");
  CHECK(reply.rfind("OK 1 plate ", 0) == 0);
  CHECK(splitFields(reply, " ")[4] == "0");
  CHECK(reply.find(';') == std::string::npos);
  const auto models = cell.cell->models().snapshot();
  REQUIRE(models->size() == 1);
  CHECK(models->front().min_hole_area == leave_out);
  CHECK(models->front().min_region_area == 50);

  // A part cut by the frame edge, alone in the frame.
  StillCell edge(test::drawParts(640, 480, {{kBar, 100, 240, 0}}, 3));
  reply = edge.ask("LEARN 3");
  CHECK(reply.rfind("OK 3 type3 ", 0) == 0);
  CHECK(reply.find(" ; warning: the part touches the frame border") != std::string::npos);

  // A part of a few hundred pixels.
  StillCell tiny(
      test::drawParts(640, 480, {{synthetic::Shape{{test::rectLoop(18, 18)}}, 300, 200, 0}}, 3));
  reply = tiny.ask("LEARN 4");
  INFO(reply);
  CHECK(reply.rfind("OK 4 type4 ", 0) == 0);
  CHECK(reply.find(" ; warning: area 3") != std::string::npos);
  CHECK(reply.find(" px is under 10 times the minimum region area") != std::string::npos);
}

TEST_CASE("model files keep the region settings and read files without them",
          "[learn][model_file]") {
  const auto learned = learnInImage(fullFrame(), {}, {}, std::make_shared<const ModelList>(), 1,
                                    "bar", boxAround(kParts[0], 4));
  REQUIRE(learned);
  vision::PartModel model = learned->model;
  model.min_hole_area = 12.5;
  const std::string text = modelToYaml(model);
  auto back = modelFromYaml(text);
  REQUIRE(back);
  CHECK(back->min_region_area == 50);
  CHECK(back->min_hole_area == 12.5);
  // A file written before the settings existed: every region and hole counted.
  const size_t from = text.find("regions:");
  const size_t to = text.find("body:");
  REQUIRE(from != std::string::npos);
  REQUIRE(to > from);
  back = modelFromYaml(text.substr(0, from) + text.substr(to));
  REQUIRE(back);
  CHECK(back->min_region_area == 0);
  CHECK(back->min_hole_area == 0);
  // A bad value names the field.
  std::string bad = text;
  bad.replace(bad.find("min_hole_area: 12.5"), 19, "min_hole_area: -1");
  const auto refused = modelFromYaml(bad);
  REQUIRE(!refused);
  CHECK(refused.error().message.find("hole area") != std::string::npos);
}

TEST_CASE(
    "a resized or cropped frame finds the parts trained at full size at the same sensor "
    "positions",
    "[learn][resized]") {
  const auto learned = learnInImage(fullFrame(), {}, {}, std::make_shared<const ModelList>(), 1,
                                    "bar", boxAround(kParts[0], 4));
  REQUIRE(learned);
  const auto models = std::make_shared<const ModelList>(ModelList{learned->model});

  for (double scale : {0.5, 0.75}) {
    INFO("scale " << scale);
    Frame frame;
    cv::resize(fullFrame(), frame.image, cv::Size(), scale, scale, cv::INTER_AREA);
    frame.mapping.scale_x = frame.mapping.scale_y = scale;
    const auto outcome = locateInFrame(frame, {}, models, 1);
    CHECK(outcome.parts.size() == 2);
    for (size_t k : {size_t{0}, size_t{2}}) {
      const LocatedPart& p = nearest(outcome.parts, kParts[k].x, kParts[k].y);
      // Half the pixels: a few tenths of a sensor pixel.
      CHECK(std::hypot(p.x - kParts[k].x, p.y - kParts[k].y) < 0.3);
      WARN("scale " << scale << ": position error "
                    << std::hypot(p.x - kParts[k].x, p.y - kParts[k].y) << " sensor px");
      CHECK(p.area == Approx(learned->model.body.area).epsilon(0.03));
    }
    // Trained on the resized frame: the model is in sensor pixels all the same.
    const auto half =
        learnInImage(frame.image, frame.mapping, {}, std::make_shared<const ModelList>(), 1, "bar",
                     boxAround(kParts[0], 4));
    REQUIRE(half);
    CHECK(half->model.body.area == Approx(learned->model.body.area).epsilon(0.03));
    CHECK(half->model.trained_centroid.x == Approx(kParts[0].x).margin(0.3));
    CHECK(half->model.trained_centroid.y == Approx(kParts[0].y).margin(0.3));
  }

  // A crop narrower than the bars: its own default window would be too.
  Frame crop;
  const cv::Rect roi(200, 120, 420, 360);
  crop.image = fullFrame()(roi).clone();
  crop.mapping.roi_x = roi.x;
  crop.mapping.roi_y = roi.y;
  const auto outcome = locateInFrame(crop, {}, models, 1);
  REQUIRE(outcome.parts.size() == 1);
  CHECK(std::hypot(outcome.parts[0].x - kParts[0].x, outcome.parts[0].y - kParts[0].y) < 0.1);
}

TEST_CASE(
    "the models scaled for a resized frame are built once per scale and again after the library "
    "changes",
    "[learn][resized][scaled_cache]") {
  char d[] = "/tmp/picksight-scaled-cache-test-XXXXXX";
  REQUIRE(::mkdtemp(d) != nullptr);
  const std::string dir = d;
  ModelLibrary library(dir + "/models");
  const auto learned = learnInImage(fullFrame(), {}, {}, std::make_shared<const ModelList>(), 1,
                                    "bar", boxAround(kParts[0], 4));
  REQUIRE(learned);
  REQUIRE(library.store(learned->model));

  const auto resized = [](double scale) {
    Frame frame;
    cv::resize(fullFrame(), frame.image, cv::Size(), scale, scale, cv::INTER_AREA);
    frame.mapping.scale_x = frame.mapping.scale_y = scale;
    return frame;
  };
  const Frame half = resized(0.5);
  const Frame three_quarters = resized(0.75);
  // Every LOCATE of a resized camera finds both bars, from one scaled list.
  const auto findsBars = [&](const Frame& frame, ScaledModelCache& cache,
                             std::shared_ptr<const ModelList> models) {
    const auto outcome = locateInFrame(frame, {}, std::move(models), 1, &cache);
    CHECK(outcome.parts.size() == 2);
    for (size_t k : {size_t{0}, size_t{2}}) {
      const LocatedPart& p = nearest(outcome.parts, kParts[k].x, kParts[k].y);
      CHECK(std::hypot(p.x - kParts[k].x, p.y - kParts[k].y) < 0.3);
    }
    return outcome.scene.models;
  };
  ScaledModelCache cache;
  const auto first = findsBars(half, cache, library.snapshot());
  for (int i = 0; i < 3; ++i) CHECK(findsBars(half, cache, library.snapshot()) == first);
  CHECK(cache.builds() == 1);
  // Another scale is built once and the first is still kept.
  const auto other = findsBars(three_quarters, cache, library.snapshot());
  CHECK(other != first);
  CHECK(findsBars(half, cache, library.snapshot()) == first);
  CHECK(cache.builds() == 2);
  // The full size needs no scaled list.
  CHECK(cache.forFrame(library.snapshot(), {}) == library.snapshot());
  CHECK(cache.builds() == 2);

  // LEARN (a new model) and DELETE publish new lists: each is scaled anew.
  auto disc =
      learnInImage(fullFrame(), {}, {}, library.snapshot(), 2, "disc", boxAround(kParts[1], 4));
  REQUIRE(disc);
  REQUIRE(library.store(disc->model));
  const auto with_disc = findsBars(half, cache, library.snapshot());
  CHECK(with_disc != first);
  CHECK(with_disc->size() == 2);
  CHECK(cache.builds() == 3);
  CHECK(findsBars(half, cache, library.snapshot()) == with_disc);
  const auto discs = locateInFrame(half, {}, library.snapshot(), 2, &cache);
  REQUIRE(discs.parts.size() == 1);
  CHECK(std::hypot(discs.parts[0].x - kParts[1].x, discs.parts[0].y - kParts[1].y) < 0.3);
  REQUIRE(library.remove(2));
  const auto without_disc = findsBars(half, cache, library.snapshot());
  CHECK(without_disc->size() == 1);
  CHECK(cache.builds() == 4);
  // A reload from disk is a new generation too.
  REQUIRE(library.load().empty());
  findsBars(half, cache, library.snapshot());
  CHECK(cache.builds() == 5);

  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
}

TEST_CASE("LEARN's errors say what is wrong with a name and how to write it", "[learn][errors]") {
  StillCell cell(test::drawParts(640, 480, {{kBar, 320, 240, 0}}, 7));
  std::string reply = cell.ask("LEARN 1 my part");
  INFO(reply);
  CHECK_THAT(reply, Catch::StartsWith("ERROR 11 LEARN: the name is one word"));
  CHECK_THAT(reply, Catch::Contains("got 2 words 'my part': write it as LEARN 1 my_part ("));
  reply = cell.ask("LEARN 1 my big part at 10 10 600 400");
  CHECK_THAT(reply, Catch::Contains("write it as LEARN 1 my_big_part AT <x> <y> <w> <h>"));
  reply = cell.ask("LEARN 1 my/part");
  CHECK_THAT(reply, Catch::StartsWith("ERROR 11 LEARN: name must be 1-32 of"));
  CHECK_THAT(reply, Catch::EndsWith("got 'my/part' ('/')"));
  CHECK(cell.ask("MODELS") == "OK 0");
  // AT in any case, as robot programs write it.
  CHECK(cell.ask("LEARN 1 bar at 10 10 600 400").rfind("OK 1 bar ", 0) == 0);
}

TEST_CASE("LEARN warns when the part is one another type's model already recognizes",
          "[learn][warnings]") {
  StillCell cell(test::drawParts(640, 480, {{kBar, 320, 240, 0}}, 7));
  std::string reply = cell.ask("LEARN 1 bar");
  INFO(reply);
  REQUIRE(reply.rfind("OK 1 bar ", 0) == 0);
  CHECK(reply.find("looks like") == std::string::npos);
  // The same bar taught again as type 1: itself, no warning.
  CHECK(cell.ask("LEARN 1 bar").find("looks like") == std::string::npos);
  // As a second type: LOCATE ALL would split such bars between the two.
  reply = cell.ask("LEARN 2 copy");
  CHECK_THAT(reply, Catch::StartsWith("OK 2 copy "));
  CHECK_THAT(reply, Catch::Contains(" ; warning: looks like type 1 (bar): this part passes "
                                    "every test of that model"));
  CHECK_THAT(reply, Catch::Contains("split parts of this shape between types 1 and 2"));
  // Another shape as a second type: no warning.
  cell.camera->setImage(test::drawParts(640, 480, {{kDisc, 320, 240, 0}}, 7));
  reply = cell.ask("LEARN 3 disc");
  CHECK_THAT(reply, Catch::StartsWith("OK 3 disc "));
  CHECK(reply.find("looks like") == std::string::npos);
}

TEST_CASE("offline learn --at learns the one part inside a rectangle as LEARN AT does",
          "[learn][learn_at][offline]") {
  StillCell cell(fullFrame());
  const std::string image = cell.dir + "/scene.png";
  REQUIRE(picksight::codecs::imwrite(image, fullFrame()));
  const auto run = [&](std::vector<std::string> extra, std::string* err_text = nullptr) {
    std::vector<std::string> args{"learn", "--data-dir", cell.dir + "/offline", "--type", "4"};
    args.insert(args.end(), extra.begin(), extra.end());
    args.push_back(image);
    std::ostringstream out, err;
    const int status = runOfflineCommand(args, out, err);
    if (err_text) *err_text = err.str();
    return std::make_pair(status, out.str());
  };
  // Three parts: refused, and the reply says how to pick one offline.
  auto [status, out] = run({});
  CHECK(status == 1);
  CHECK_THAT(out, Catch::StartsWith("ERROR 31 3 parts in the frame"));
  CHECK_THAT(out, Catch::Contains("offline: learn --at <x> <y> <w> <h>"));
  const cv::Rect box = boxAround(kParts[1], 4);
  std::tie(status, out) =
      run({"--name", "disc", "--at", std::to_string(box.x), std::to_string(box.y),
           std::to_string(box.width), std::to_string(box.height)});
  INFO(out);
  CHECK(status == 0);
  CHECK_THAT(out, Catch::StartsWith("OK 4 disc "));
  const auto fields = splitFields(out, " \n");
  REQUIRE(fields.size() >= 4);
  CHECK(*parseDouble(fields[3]) == Approx(M_PI * 110 * 110).epsilon(0.01));
  CHECK(std::filesystem::exists(cell.dir + "/offline/models/type_4.yaml"));
  // Its teach image beside it, the 1280 x 960 image shrunk to fit 1024.
  const cv::Mat taught =
      picksight::codecs::imread(cell.dir + "/offline/models/type_4.png", cv::IMREAD_UNCHANGED);
  CHECK(taught.cols == 1024);
  CHECK(taught.rows == 768);
  std::string err;
  std::tie(status, out) = run({"--at", "1", "2", "x", "4"}, &err);
  CHECK(status == 2);
  CHECK_THAT(err, Catch::Contains("--at needs four integers X Y W H"));
  std::tie(status, out) = run({"--at", "0", "0", "60", "60"});
  CHECK(status == 1);
  CHECK_THAT(out, Catch::StartsWith("ERROR 35 no part inside LEARN AT"));
}

TEST_CASE("TRYLEARN says what LEARN would teach and LOCATE ALL then find and stores nothing",
          "[learn][learn_at][trylearn]") {
  StillCell cell(fullFrame());
  const std::string bar = "AT " + rectArgs(boxAround(kParts[0], 4));
  std::string reply = cell.ask("TRYLEARN 1 bar " + bar);
  INFO(reply);
  // The two bars found with the new model; nothing else is a part yet.
  // The fields before the first ';' (kept: splitFields returns views).
  std::string head = reply.substr(0, reply.find(" ;"));
  auto fields = splitFields(head, " ");
  REQUIRE(fields.size() == 9);
  CHECK(fields[0] == "OK");
  CHECK(fields[1] == "1");
  CHECK(fields[2] == "bar");
  CHECK(fields[7] == "2");
  CHECK(fields[8] == "2");
  CHECK_THAT(reply, Catch::EndsWith(" ; note: nothing stored"));
  CHECK(cell.ask("MODELS") == "OK 0");
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 37 "));
  CHECK(!std::filesystem::exists(cell.dir + "/models/type_1.yaml"));

  REQUIRE(cell.ask("LEARN 1 bar " + bar).rfind("OK 1 bar ", 0) == 0);
  const std::string file = cell.dir + "/models/type_1.yaml";
  // The disc tried as type 2: one of it, three parts in all.
  reply = cell.ask("TRYLEARN 2 disc AT " + rectArgs(boxAround(kParts[1], 4)));
  head = reply.substr(0, reply.find(" ;"));
  fields = splitFields(head, " ");
  REQUIRE(fields.size() == 9);
  CHECK(fields[7] == "1");
  CHECK(fields[8] == "3");
  // The disc tried over type 1: the bars are no longer type 1's.
  reply = cell.ask("TRYLEARN 1 disc AT " + rectArgs(boxAround(kParts[1], 4)));
  head = reply.substr(0, reply.find(" ;"));
  fields = splitFields(head, " ");
  REQUIRE(fields.size() == 9);
  CHECK(fields[7] == "1");
  CHECK(fields[8] == "1");
  CHECK_THAT(cell.ask("MODELS"), Catch::StartsWith("OK 1 1 bar "));
  // Errors as LEARN's, named for TRYLEARN; on a read-only port it is allowed.
  CHECK_THAT(cell.ask("TRYLEARN 1 my part"),
             Catch::StartsWith("ERROR 11 TRYLEARN: the name is one word"));
  CHECK_THAT(cell.ask("TRYLEARN 3"), Catch::StartsWith("ERROR 31 "));
  CHECK(cell.cell->handle("TRYLEARN 3 AT " + rectArgs(boxAround(kParts[1], 4)), true)
            .rfind("OK 3 type3 ", 0) == 0);
  CHECK(cell.ask("MODELS").rfind("OK 1 1 bar ", 0) == 0);
  CHECK(std::filesystem::exists(file));
}
