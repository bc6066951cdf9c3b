// Grasp clearance through the robot protocol: GRASP and GRIPPER define the
// styles and fingers of a trained bar; LOCATE offers the first style whose
// fingers cover no other part, and no pose at all for a part blocked every
// way (counted in STATUS).
#include <catch2/catch.hpp>

#include <filesystem>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "picksight/common/text.hpp"
#include "picksight/vision_app/offline_commands.hpp"
#include "picksight/vision_app/vision_cell.hpp"

using namespace picksight;
using namespace picksight::app;

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
  StillCamera* camera = nullptr;  // owned by the cell
  std::unique_ptr<VisionCell> cell;
  Cell() {
    char d[] = "/tmp/picksight-cell-test-XXXXXX";
    REQUIRE(::mkdtemp(d) != nullptr);
    dir = d;
    auto still = std::make_unique<StillCamera>();
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
  VisionCell again(cell.dir, std::make_unique<NoCamera>(), VisionOptions{});
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
  VisionCell reloaded(cell.dir, std::make_unique<NoCamera>(), VisionOptions{});
  CHECK(reloaded.load().empty());
  CHECK(reloaded.handle("STATUS").find(" lens=1 ") != std::string::npos);
  CHECK(reloaded.calibration().geometry()->vision.calibrated() == false);  // no scale yet
}
