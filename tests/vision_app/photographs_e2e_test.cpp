// The photographs in tests/data/scenes, each through a file camera and the
// robot protocol as an integrator would use them: LEARN ... AT a box around
// a part (after the vision settings the scene needs), then LOCATE ALL, which
// must report exactly the parts a person sees, each where it is. The truth
// (counts and centres, image pixels) was read off the photographs by eye,
// within a few pixels; coins.png has its own test
// (vision_settings_e2e_test.cpp).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "picksight/codecs/codecs.hpp"

#include "cell_fixture.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;

namespace {
struct Located {
  int type = 0;
  double x = 0;  // image pixels, y down
  double y = 0;
};

// LOCATE ALL's parts; the reply is in vision pixels, y up.
std::vector<Located> parts(const std::string& reply) {
  INFO(reply);
  REQUIRE(reply.rfind("OK ", 0) == 0);
  std::istringstream fields(reply.substr(3));
  int count = 0;
  fields >> count;
  std::vector<Located> out(static_cast<size_t>(count));
  for (auto& p : out) {
    double angle = 0;
    fields >> p.type >> p.x >> p.y >> angle;
    p.y = -p.y;
  }
  REQUIRE(fields);
  return out;
}

struct Expected {
  int type;
  double x;
  double y;
};

struct Photograph {
  std::string file;
  std::vector<std::string> setup;  // VISION and LEARN ... AT lines, in order
  std::vector<Expected> parts;     // every part LOCATE ALL must report
  double within_px;                // of the centre read by eye
};

void check(const Photograph& photo) {
  INFO(photo.file);
  PhotographCell cell(photo.file);
  const auto ask = [&](const std::string& request) { return cell.ask(request); };
  for (const auto& line : photo.setup) {
    const std::string reply = ask(line);
    INFO(line << " -> " << reply);
    REQUIRE(reply.rfind("OK", 0) == 0);
  }
  const std::string reply = ask("LOCATE ALL");
  INFO(reply);
  const auto found = parts(reply);
  CHECK(found.size() == photo.parts.size());
  // Each part seen once, of its type, where it lies.
  std::vector<bool> used(found.size(), false);
  for (const auto& e : photo.parts) {
    bool seen = false;
    for (size_t i = 0; i < found.size() && !seen; ++i) {
      if (used[i] || found[i].type != e.type) continue;
      if (std::hypot(found[i].x - e.x, found[i].y - e.y) > photo.within_px) continue;
      used[i] = seen = true;
    }
    INFO("type " << e.type << " at " << e.x << " " << e.y);
    CHECK(seen);
  }
}
}  // namespace

TEST_CASE("photographs: shapes cut from card, each taught and found once", "[e2e][photographs]") {
  // pic1.png (OpenCV samples): a tilted tile, a triangle, a head, a blurred
  // bar, beside a plate with seven holes and a question mark.
  check({"pic1.png",
         {"LEARN 1 tile AT 245 35 150 155", "LEARN 2 triangle AT 238 200 148 86",
          "LEARN 3 head AT 8 155 100 135", "LEARN 4 bar AT 148 172 55 110"},
         {{1, 319, 112}, {2, 310, 228}, {3, 55, 219}, {4, 175, 228}},
         4});
}

TEST_CASE("photographs: the small painted square and not the large one", "[e2e][photographs]") {
  // pic3.png (OpenCV samples): four outlines painted in colour on white; two
  // squares of different sizes.
  check({"pic3.png", {"LEARN 1 square AT 230 160 135 135"}, {{1, 295, 227}}, 4});
}

TEST_CASE("photographs: a pencil, a cap and a lighter on a wooden desk", "[e2e][photographs]") {
  // stuff.jpg (OpenCV samples): a front-lit desk with grain and vignetting;
  // the dark objects (the white ball and the coin are lighter than the desk).
  check({"stuff.jpg",
         {"LEARN 1 pencil AT 50 80 300 180", "LEARN 2 cap AT 180 10 100 100",
          "LEARN 3 lighter AT 300 300 80 170"},
         {{1, 196, 172}, {2, 228, 56}, {3, 337, 395}},
         5});
}

TEST_CASE("photographs: one wooden block among blocks of other shapes and poses",
          "[e2e][photographs]") {
  // blox.jpg (OpenCV samples): blocks on a table and a platform.
  check({"blox.jpg", {"LEARN 1 block AT 70 185 55 60"}, {{1, 99, 217}}, 4});
}

TEST_CASE("photographs: the horse silhouette", "[e2e][photographs]") {
  // horse.png (scikit-image data).
  check({"horse.png", {"LEARN 1 horse AT 5 0 395 328"}, {{1, 187, 145}}, 5});
}

TEST_CASE("photographs: a lone disc and the discs of a pile that show most of their rim",
          "[e2e][photographs]") {
  // detect_blob.png (OpenCV samples): light shapes on black; a pile of about
  // twenty discs as large as the lone one at (181, 61). Thirteen of the
  // pile show more than 0.6 of their rim, the others lie under them.
  check({"detect_blob.png",
         {"VISION polarity light", "LEARN 1 dot AT 160 40 45 45"},
         {{1, 181, 61},
          {1, 405, 475},
          {1, 445, 478},
          {1, 483, 487},
          {1, 362, 517},
          {1, 472, 522},
          {1, 363, 542},
          {1, 447, 563},
          {1, 465, 567},
          {1, 373, 577},
          {1, 367, 597},
          {1, 412, 603},
          {1, 438, 617},
          {1, 375, 623}},
         4});
}

TEST_CASE("photographs: every whole sweet from one taught in colour", "[e2e][photographs]") {
  // smarties.png (OpenCV samples): glossy sweets of six colours on white,
  // two pairs touching; the three cut by the frame's edge are not whole.
  check({"smarties.png",
         {"LEARN 1 sweet AT 236 85 64 64"},
         {{1, 377, 81},
          {1, 269, 117},
          {1, 205, 211},
          {1, 287, 213},
          {1, 347, 238},
          {1, 33, 228},
          {1, 98, 259},
          {1, 152, 271},
          {1, 219, 306},
          {1, 294, 320},
          {1, 134, 327}},
         5});
}

TEST_CASE("photographs: a part taught on its colour from a JPEG frame is warned of",
          "[e2e][photographs][colour]") {
  // The sweets photograph as an IP camera, a phone or an MJPEG webcam sends
  // it (JPEG at quality 90: colour at half resolution, quantised in blocks),
  // through a file camera: the green sweet is taught on its colour, and
  // LEARN says the frame came compressed and what that costs. The same
  // photograph lossless, and a part taught on its grey levels through JPEG,
  // are not warned of. The file camera tells a JPEG by its first bytes: the
  // copies are named .png.
  const test::TempDir dir;
  const auto asJpeg = [&](const std::string& scene) {
    const cv::Mat photo = picksight::codecs::imread(
        std::string(PICKSIGHT_TEST_DATA_DIR) + "/scenes/" + scene, cv::IMREAD_COLOR);
    REQUIRE(!photo.empty());
    std::vector<uint8_t> bytes;
    REQUIRE(picksight::codecs::imencode(".jpg", photo, bytes, {cv::IMWRITE_JPEG_QUALITY, 90}));
    return dir.write(scene, std::string(bytes.begin(), bytes.end()));
  };
  const std::string warned = "this frame came compressed";
  // A colour camera: the video server sends bgr8.
  const auto inColour = [](const PhotographCell& cell) {
    const CommandResult set =
        run({binPath("picksight-cam"), "--control", cell.server.control, "format", "cam0", "bgr8"});
    INFO(set.out);
    REQUIRE(set.exit_code == 0);
  };
  {
    PhotographCell cell(asJpeg("smarties.png"));
    inColour(cell);
    const std::string reply = cell.ask("LEARN 1 sweet AT 236 85 64 64");
    INFO(reply);
    CHECK(reply.rfind("OK 1 sweet ", 0) == 0);
    CHECK(reply.find(warned) != std::string::npos);
    CHECK(reply.find("half resolution") != std::string::npos);
  }
  {
    PhotographCell cell("smarties.png");
    inColour(cell);
    const std::string reply = cell.ask("LEARN 1 sweet AT 236 85 64 64");
    INFO(reply);
    CHECK(reply.rfind("OK 1 sweet ", 0) == 0);
    CHECK(reply.find(warned) == std::string::npos);
  }
  {
    // pic3.png: an outline painted on white, dark enough to be taught on
    // its grey levels.
    PhotographCell cell(asJpeg("pic3.png"));
    inColour(cell);
    const std::string reply = cell.ask("LEARN 1 square AT 230 160 135 135");
    INFO(reply);
    CHECK(reply.rfind("OK 1 square ", 0) == 0);
    CHECK(reply.find(warned) == std::string::npos);
  }
}

TEST_CASE("photographs: six bars on a light table seen at a slant, the two nearest by WHY's remedy",
          "[e2e][photographs]") {
  // pca_test1.jpg (OpenCV samples): six identical bars with a waist on a
  // light table, five lying across and one upright, photographed at a
  // slant: the two nearest the camera (lowest in the image) look 14 and 16
  // percent larger than the top one taught, past the model's default area
  // tolerance of 10 percent. LOCATE reports the four within it; WHY names
  // the two others with the tolerance that would accept them, and with it
  // LOCATE reports all six. (A camera looking straight down, or CALCAM
  // GRID's rectification, keeps the parts one size.) The nearest bar shows
  // one pixel of level 107 inside (the bar 10, the table 230): a pinhole,
  // not a hole of the bar.
  PhotographCell cell("pca_test1.jpg");
  const auto ask = [&](const std::string& request) { return cell.ask(request); };
  REQUIRE(ask("LEARN 1 bar AT 230 60 380 70").rfind("OK 1 bar", 0) == 0);
  const std::vector<Expected> four{{1, 408, 90}, {1, 421, 169}, {1, 433, 240}, {1, 191, 292}};
  const std::vector<Expected> nearest{{1, 440, 326}, {1, 431, 408}};
  const auto count = [](const std::vector<Located>& found, const Expected& e) {
    return std::count_if(found.begin(), found.end(), [&](const Located& p) {
      return p.type == e.type && std::hypot(p.x - e.x, p.y - e.y) <= 4;
    });
  };
  const auto first = parts(ask("LOCATE ALL"));
  CHECK(first.size() == four.size());
  for (const auto& e : four) CHECK(count(first, e) == 1);
  // Both left out for their size alone, each with the remedy; and the
  // dark room round the light table, a region the frame's edge cuts, far
  // larger than a bar (searched for bars lying against it: none), unlike
  // any part: said after them.
  const std::string why = ask("WHY");
  INFO(why);
  CHECK(why.rfind("OK 3 region 1 scaled ", 0) == 0);
  CHECK_THAT(why, Catch::EndsWith("; region 0 touches the frame border"));
  const std::string remedy = ", area_tolerance ";
  size_t at = why.find(remedy);
  double widest = 0;
  int remedies = 0;
  for (; at != std::string::npos; at = why.find(remedy, at + 1)) {
    widest = std::max(widest, std::stod(why.substr(at + remedy.size())));
    ++remedies;
  }
  REQUIRE(remedies == 2);
  CHECK(widest < 0.25);
  std::ostringstream set;
  set << "TOLERANCE 1 area_tolerance " << widest;
  REQUIRE(ask(set.str()).rfind("OK 1 bar", 0) == 0);
  const auto all = parts(ask("LOCATE ALL"));
  CHECK(all.size() == four.size() + nearest.size());
  for (const auto& e : four) CHECK(count(all, e) == 1);
  for (const auto& e : nearest) CHECK(count(all, e) == 1);
}
