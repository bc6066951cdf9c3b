// Grasp clearance through the robot protocol: GRASP and GRIPPER define the
// styles and fingers of a trained bar; LOCATE offers the first style whose
// fingers cover no other part, and no pose at all for a part blocked every
// way (counted in STATUS).
#include <catch2/catch.hpp>

#include <filesystem>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "picksight/app/offline_commands.hpp"
#include "picksight/app/vision_cell.hpp"
#include "picksight/cell/grasp_planner.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;
using namespace picksight::app;
using namespace picksight::cell;
using namespace picksight::store;

namespace {
constexpr int kShift = 4;

cv::Point fixed(cv::Point2d p) {
  return {static_cast<int>(std::lround(p.x * (1 << kShift))),
          static_cast<int>(std::lround(p.y * (1 << kShift)))};
}

struct Scene {
  Scene() = default;
  Scene(const Scene& other) : image(other.image.clone()) {}
  cv::Mat image{480, 640, CV_8UC1, cv::Scalar(200)};
  Scene& bar(cv::Point2d centre) {  // 90 x 30, along the image x axis
    const std::vector<cv::Point> poly{
        fixed(centre + cv::Point2d(-45, -15)), fixed(centre + cv::Point2d(45, -15)),
        fixed(centre + cv::Point2d(45, 15)), fixed(centre + cv::Point2d(-45, 15))};
    cv::fillConvexPoly(image, poly, cv::Scalar(40), cv::LINE_AA, kShift);
    return *this;
  }
  Scene& disc(cv::Point2d centre, double radius) {
    cv::circle(image, fixed(centre), static_cast<int>(radius * (1 << kShift)), cv::Scalar(40),
               cv::FILLED, cv::LINE_AA, kShift);
    return *this;
  }
};

// LOCATE's poses, against the expected ones within 0.05 (pixels, degrees).
bool posesAre(const std::string& reply, const std::vector<cv::Point3d>& expected) {
  const auto w = splitFields(reply, " ");
  if (w.size() != 2 + 3 * expected.size() || w[0] != "OK" ||
      w[1] != std::to_string(expected.size()))
    return false;
  for (size_t i = 0; i < expected.size(); ++i) {
    const double v[3] = {expected[i].x, expected[i].y, expected[i].z};
    for (size_t k = 0; k < 3; ++k) {
      const auto got = parseDouble(w[2 + 3 * i + k]);
      if (!got || std::abs(*got - v[k]) > 0.05) return false;
    }
  }
  return true;
}

struct Cell {
  std::string dir;
  picksight::link::StillCamera* camera = nullptr;  // owned by the cell
  std::unique_ptr<VisionCell> cell;
  Cell() {
    char d[] = "/tmp/picksight-cell-test-XXXXXX";
    REQUIRE(::mkdtemp(d) != nullptr);
    dir = d;
    auto still = std::make_unique<picksight::link::StillCamera>();
    camera = still.get();
    cell = std::make_unique<VisionCell>(dir, std::move(still), VisionOptions{});
    REQUIRE(cell->load().empty());
  }
  ~Cell() {
    cell.reset();
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  std::string ask(const Scene& scene, const std::string& request) {
    camera->setImage(scene.image);
    return cell->handle(request);
  }
  // A bar trained as type 1 with two styles, across it and from its ends
  // (units are pixels until CALCAM), and two fingers `reach` px either side.
  void barWithGripper(int reach) {
    REQUIRE(ask(Scene().bar({320, 240}), "LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
    CHECK(cell->handle("GRASP 1 ADD 0 0 0") == "OK 1");
    CHECK(cell->handle("GRASP 1 ADD 0 0 90") == "OK 2");
    CHECK(cell->handle("GRIPPER 1 FINGER 0 " + std::to_string(reach) + " 10 8") == "OK 1");
    CHECK(cell->handle("GRIPPER 1 FINGER 0 -" + std::to_string(reach) + " 10 8") == "OK 2");
  }
};
}  // namespace

TEST_CASE("the first grasp whose fingers are clear wins and a blocked part is not offered",
          "[cell][grasp]") {
  Cell cell;
  // Style 1 grips across the bar (fingers above and below it), style 2 from
  // its ends.
  cell.barWithGripper(55);
  CHECK(cell.cell->handle("GRASP 1 LIST") == "OK 2 0.000 0.000 0.000 0.000 0.000 90.000");
  CHECK(cell.cell->handle("GRIPPER 1 LIST") ==
        "OK 2 0.000 55.000 10.000 8.000 0.000 -55.000 10.000 8.000");

  // Alone: style 1, at the part's own pose (vision frame: y up).
  CHECK(posesAre(cell.ask(Scene().bar({200, 240}), "LOCATE 1"), {{200.0, -240.0, 0.0}}));
  // A disc under one of style 1's fingers (image y 291..299 below the bar).
  CHECK(posesAre(cell.ask(Scene().bar({200, 240}).disc({200, 306}, 14), "LOCATE 1"),
                 {{200.0, -240.0, 90.0}}));
  CHECK(cell.cell->handle("STATUS").find(" skipped=0 ") != std::string::npos);
  // Discs under style 2's fingers too (image x 141..149 and 251..259).
  const Scene blocked =
      Scene().bar({200, 240}).disc({200, 306}, 14).disc({136, 240}, 10).disc({264, 240}, 10);
  CHECK(posesAre(cell.ask(blocked, "LOCATE 1"), {}));
  const std::string status = cell.cell->handle("STATUS");
  CHECK(status.find(" offered=0 skipped=1 skipped_total=1") != std::string::npos);
  // A second bar far away is still offered, with style 1.
  CHECK(posesAre(cell.ask(Scene(blocked).bar({480, 120}), "LOCATE 1"), {{480, -120, 0}}));

  // Grasps persist with the model, and reload with it.
  VisionCell again(cell.dir, std::make_unique<picksight::link::NoCamera>(), VisionOptions{});
  CHECK(again.load().empty());
  CHECK(again.handle("GRASP 1 LIST") == "OK 2 0.000 0.000 0.000 0.000 0.000 90.000");
  CHECK(cell.cell->handle("GRIPPER 1 CLEAR") == "OK 0");
  // No fingers: every grasp is free, the first style wins.
  CHECK(posesAre(cell.ask(blocked, "LOCATE 1"), {{200.0, -240.0, 0.0}}));
  CHECK(cell.cell->handle("GRASP 1 CLEAR") == "OK 0");
  CHECK(cell.cell->handle("GRASP 7 LIST").rfind("ERROR 32 ", 0) == 0);
}

TEST_CASE("a part found touching another owns only its placed footprint", "[cell][grasp]") {
  Cell cell;
  cell.barWithGripper(30);
  // Alone: style 1 (its fingers 11 px off the bar's long sides).
  CHECK(posesAre(cell.ask(Scene().bar({200, 240}), "LOCATE 1"), {{200.0, -240.0, 0.0}}));
  // A small disc fused to the bar's lower side, under style 1's lower finger
  // (image y 266..274): one region, a fifth larger than the bar, within
  // what an area test alone would take for the bar itself. Vision finds the
  // bar touching the disc, so the disc is another thing under the finger:
  // style 2, the fingers on the bar's own footprint (90 or 270 degrees: the
  // bar is symmetric under a half turn).
  const std::string reply = cell.ask(Scene().bar({200, 240}).disc({200, 266}, 13), "LOCATE 1");
  INFO(reply);
  CHECK((posesAre(reply, {{200.0, -240.0, 90.0}}) || posesAre(reply, {{200.0, -240.0, 270.0}})));
}

TEST_CASE("a grasp whose fingers leave the image is not offered", "[cell][grasp]") {
  Cell cell;
  REQUIRE(cell.ask(Scene().bar({320, 240}), "LEARN 1 bar").rfind("OK ", 0) == 0);
  CHECK(cell.cell->handle("GRIPPER 1 FINGER 0 55 10 8") == "OK 1");
  // The bar's own pose is the grasp; its finger above reaches past the top edge.
  CHECK(posesAre(cell.ask(Scene().bar({320, 40}), "LOCATE 1"), {}));
  CHECK(posesAre(cell.ask(Scene().bar({320, 140}), "LOCATE 1"), {{320.0, -140.0, 0.0}}));
}

TEST_CASE("the lens subcommand stores the chessboard lens model the cell then uses",
          "[cell][lens]") {
  Cell cell;
  std::vector<std::string> args{"lens", "--data-dir", cell.dir, "--corners",
                                "9x6",  "--square",   "25"};
  const std::string boards =
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/calibration/opencv_chessboard/";
  for (const char* name : {"left01.jpg", "left02.jpg", "left03.jpg", "left04.jpg", "left05.jpg",
                           "left06.jpg", "left07.jpg", "left08.jpg", "left09.jpg", "left11.jpg",
                           "left12.jpg", "left13.jpg", "left14.jpg"})
    args.push_back(boards + name);
  std::ostringstream out, err;
  REQUIRE(runOfflineCommand(args, out, err) == 0);
  const std::string reply = out.str();
  INFO(reply);
  // OpenCV's own result, stored beside the images: fx = fy = 535.916,
  // cx = 342.283, cy = 235.571.
  const auto w = splitFields(reply, " \n");
  REQUIRE(w.size() == 7);
  CHECK(parseDouble(w[1]).value_or(0) == Approx(535.916).epsilon(0.01));
  CHECK(parseDouble(w[3]).value_or(0) == Approx(342.283).margin(3));
  CHECK(parseDouble(w[4]).value_or(0) == Approx(235.571).margin(3));
  VisionCell reloaded(cell.dir, std::make_unique<picksight::link::NoCamera>(), VisionOptions{});
  CHECK(reloaded.load().empty());
  CHECK(reloaded.handle("STATUS").find(" lens=1 ") != std::string::npos);
  CHECK(reloaded.calibration().geometry()->vision.calibrated() == false);  // no scale yet
}

namespace {
// A recognized part of type 1 at image (320, 240), turned `angle_deg` from
// its taught pose (as the vision library reports it), with its model's
// symmetry period.
LocatedPart partAt(double angle_deg, double symmetry_deg) {
  LocatedPart p;
  p.x = 320;
  p.y = 240;
  p.angle_deg = angle_deg;
  p.type = 1;
  p.symmetry_deg = symmetry_deg;
  return p;
}

grasp::Pose replied(const CellGeometry& geometry, double angle_deg, double symmetry_deg,
                    const grasp::GraspStyle& style = {}) {
  const LocatedPart part = partAt(angle_deg, symmetry_deg);
  return replyPose(part, partPoseInVisionFrame(part, geometry.vision), style, geometry);
}

CellGeometry robotCell(double rz_deg, bool mirrored) {
  CellGeometry g;
  g.transform = calibration::PlaneTransform::rigid({100, 50, rz_deg, mirrored});
  return g;
}
}  // namespace

TEST_CASE("a part a hair either side of its taught angle gets one reply angle in every frame",
          "[cell][grasp][symmetry]") {
  // The vision library reports the turn nearest the taught pose (a bar
  // lying still there: -0.02 or 0.02 as the noise has it); every frame the
  // cell replies in keeps it so: no half turn (the bar's 0 and 180), no
  // whole turn (0.01 and 359.99) between two LOCATEs of one part.
  for (const double symmetry : {180.0, 90.0, 360.0}) {
    INFO("symmetry " << symmetry);
    // Vision frame, no calibration: y up, so the image's -0.02 is 0.02.
    CHECK(replied(CellGeometry{}, -0.02, symmetry).rz_deg == Approx(0.02).margin(1e-9));
    CHECK(replied(CellGeometry{}, 0.02, symmetry).rz_deg == Approx(-0.02).margin(1e-9));
    // The robot frame at rz 30 (the cell: 30.00 and 209.99).
    CHECK(replied(robotCell(30, false), -0.02, symmetry).rz_deg == Approx(30.02));
    CHECK(replied(robotCell(30, false), 0.02, symmetry).rz_deg == Approx(29.98));
    // A robot frame lined up with the camera: around 0, not 0 and 360.
    CHECK(replied(robotCell(0, false), 0.02, symmetry).rz_deg == Approx(-0.02).margin(1e-9));
    // Across the frame's own wrap at 180: 179.98 and 180.02, not -179.98.
    CHECK(replied(robotCell(180, false), 0.02, symmetry).rz_deg == Approx(179.98));
    CHECK(replied(robotCell(180, false), -0.02, symmetry).rz_deg == Approx(180.02));
  }
  // A grasp style turned a quarter from the part: within half the bar's
  // period of 30 + 90.
  CHECK(replied(robotCell(30, false), 0.02, 180, {0, 0, 90}).rz_deg == Approx(119.98));
  CHECK(replied(robotCell(30, false), -0.02, 180, {0, 0, 90}).rz_deg == Approx(120.02));
}

TEST_CASE(
    "the reply angle turns the way the part does and the other way through a mirrored calibration",
    "[cell][grasp][symmetry]") {
  // A part turned counter-clockwise on screen (image angle -d, y down) turns
  // counter-clockwise in the vision frame (+d); a calibration that holds a
  // mirror turns it the other way in the robot frame. A bar's range is the
  // half turn centred on the taught angle in each frame.
  for (const double d : {10.0, 60.0, 89.0}) {
    INFO("turned " << d);
    CHECK(replied(CellGeometry{}, -d, 180).rz_deg == Approx(d));
    CHECK(replied(robotCell(30, false), -d, 180).rz_deg == Approx(30 + d));
    CHECK(replied(robotCell(30, false), d, 180).rz_deg == Approx(30 - d));
    CHECK(replied(robotCell(30, true), -d, 180).rz_deg == Approx(30 - d));
    CHECK(replied(robotCell(30, true), d, 180).rz_deg == Approx(30 + d));
  }
  // A chiral part (no symmetry) turned 170 either way: the whole turn's
  // range centred on the taught angle, not [0, 360).
  CHECK(replied(robotCell(0, false), 170, 360).rz_deg == Approx(-170));
  CHECK(replied(robotCell(0, false), -170, 360).rz_deg == Approx(170));
}

TEST_CASE("a grasp off a symmetric part's centre stays at the same end of it in every frame",
          "[cell][grasp][symmetry]") {
  // 20 px along the bar from its centre: the bar's turn decides which end
  // that is, so the gripper's place follows the reported turn (the end
  // nearest where it was taught), whichever side of 0 the noise puts it.
  const grasp::GraspStyle style{20, 0, 0};
  for (const double angle : {-0.02, 0.02}) {
    const grasp::Pose p = replied(CellGeometry{}, angle, 180, style);
    CHECK(p.x == Approx(340).margin(0.01));
    CHECK(p.y == Approx(-240).margin(0.02));
  }
}
