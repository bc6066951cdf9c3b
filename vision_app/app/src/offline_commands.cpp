// Offline subcommands over image files.
#include "picksight/app/offline_commands.hpp"

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <ostream>
#include <variant>

#include "picksight/app/app_options.hpp"
#include "picksight/calibration/camera_calibration.hpp"
#include "picksight/cell/cell_locate.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/cell_commands.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/protocol/model_commands.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::app {

using protocol::blobSummary;
using protocol::errorReply;
using protocol::learnReply;
using protocol::learnViewReply;
using protocol::locateReply;
using protocol::parseType;
using protocol::printable;
using protocol::ProtocolErrc;
using protocol::validModelName;

using cell::blobsInImage;
using cell::learnInImage;
using cell::locateAndPick;
using cell::locateInFrame;
using cell::LocateOutcome;
using cell::parseVisionSettingsJson;
using cell::teachImagePng;
using cell::VisionOptions;
using cell::VisionServiceErrc;

using store::CellCalibration;
using store::CellCalibrationErrc;
using store::ModelLibrary;

std::string offlineUsage() {
  return "usage: picksight-vision learn --type N [--name NAME] [--at X Y W H] [options] IMAGE\n"
         "       picksight-vision learnview --type N [--at X Y W H] [options] IMAGE...\n"
         "       picksight-vision locate [--type N] [options] IMAGE...\n"
         "       picksight-vision blobs [options] IMAGE...\n"
         "       picksight-vision lens [--data-dir DIR] [--corners 9x6] [--square MM] IMAGE...\n"
         "       picksight-vision test-run --models DIR --images DIR --expect N [--type N] "
         "[options]\n"
         "\n"
         "  learn   trains type N from the single part in IMAGE into DATA_DIR/models\n"
         "          (with --at, the one part inside that rectangle, as LEARN ... AT)\n"
         "  learnview reads type N's part again in each IMAGE (alone, or inside --at), as\n"
         "          LEARNVIEW: the model's origin moves to the median of the views\n"
         "  locate  prints one 'OK <n> x y rz ...' line per image: grasp poses of type N\n"
         "          (all trained types without --type; every region without models), in\n"
         "          the frame the data dir's calibration gives (docs/PROTOCOL.md)\n"
         "  blobs   prints one BLOBS reply line per image\n"
         "  lens    calibrates the lens from chessboard views (inner corners, square size)\n"
         "          into DATA_DIR/calibration.yaml: 'OK fx fy cx cy rms_px views'; stop the\n"
         "          vision app first, it reads the file at start\n"
         "  test-run LOCATE (of type N, or all types) on every image of a folder with the\n"
         "          models, settings and calibration of data dir DIR: a table of the poses\n"
         "          found per image against N expected, pass or FAIL; exit 1 on any FAIL\n"
         "Options: --data-dir DIR, --threshold, --polarity, --window, --min-area, "
         "--min-hole-area as in server mode; DATA_DIR/vision.json (VISION) supplies those "
         "not given.\n";
}

bool isOfflineCommand(const std::vector<std::string>& args) {
  return !args.empty() && (args[0] == "learn" || args[0] == "learnview" || args[0] == "locate" ||
                           args[0] == "blobs" || args[0] == "lens" || args[0] == "test-run");
}

namespace {
// picksight-vision lens: chessboard views to the lens model in the data dir.
int runLens(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  calibration::ChessboardOptions board;
  std::string data_dir = "picksight-data";
  std::vector<cv::Mat> views;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a.rfind("--", 0) == 0 && i + 1 >= args.size()) {
      err << "picksight-vision lens: " << a << ": missing value\n";
      return 2;
    }
    if (a == "--data-dir") {
      data_dir = args[++i];
    } else if (a == "--corners") {
      const auto wh = splitFields(args[++i], "x");
      const auto w = wh.size() == 2 ? parseInt(wh[0]) : std::nullopt;
      const auto h = wh.size() == 2 ? parseInt(wh[1]) : std::nullopt;
      if (!w || !h || *w < 2 || *h < 2 || *w > 100 || *h > 100) {
        err << "picksight-vision lens: --corners must be WxH inner corners, e.g. 9x6\n";
        return 2;
      }
      board.inner_corners = cv::Size(static_cast<int>(*w), static_cast<int>(*h));
    } else if (a == "--square") {
      const auto mm = parseDouble(args[++i]);
      if (!mm || !(*mm > 0)) {
        err << "picksight-vision lens: --square must be a positive size in mm\n";
        return 2;
      }
      board.square_mm = *mm;
    } else if (a.rfind("--", 0) == 0) {
      err << "picksight-vision lens: unknown option '" << a << "'\n";
      return 2;
    } else {
      views.push_back(picksight::codecs::imread(a, cv::IMREAD_GRAYSCALE));
      if (views.back().empty()) err << "picksight-vision lens: cannot read '" << a << "'\n";
    }
  }
  if (views.empty()) {
    err << offlineUsage();
    return 2;
  }
  std::vector<int> skipped;
  auto lens = calibration::calibrateChessboard(views, board, &skipped);
  for (int i : skipped) err << "picksight-vision lens: no board in view " << i + 1 << "\n";
  if (!lens) {
    out << errorReply(ProtocolErrc::kBadArguments, lens.error().message) << "\n";
    return 1;
  }
  std::error_code ec;
  std::filesystem::create_directories(data_dir, ec);
  CellCalibration store(data_dir + "/calibration.yaml");
  auto loaded = store.load();
  auto saved = loaded ? store.setLens(*lens) : Result<void>(loaded.error());
  if (!saved) {
    out << errorReply(CellCalibrationErrc::kCalibrationStorage, saved.error().message) << "\n";
    return 1;
  }
  const auto& k = lens->camera_matrix;
  out << "OK " << formatFixed(k(0, 0)) << " " << formatFixed(k(1, 1)) << " " << formatFixed(k(0, 2))
      << " " << formatFixed(k(1, 2)) << " " << formatFixed(lens->rms_reprojection_px) << " "
      << lens->views << "\n";
  return 0;
}
}  // namespace

namespace {
// An image file as a camera delivers it: 8-bit grey, or 8-bit BGR for a
// colour one (a colour camera's frame is read in colour where a model was
// taught by its colour); empty when it cannot be read.
cv::Mat readFrameImage(const std::string& path) {
  cv::Mat image = picksight::codecs::imread(path, cv::IMREAD_ANYCOLOR);
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  return image;
}

// learn, locate or blobs as the command line asks them.
struct OfflineRequest {
  std::string command;
  std::vector<std::string> images;
  int type = -1;
  std::string name;
  std::optional<cv::Rect> at;
  AppOptions options;
};

// The request in `args` (a command but lens), or the exit status (2) once
// what is wrong with it is written to `err`.
std::variant<OfflineRequest, int> parseOfflineRequest(const std::vector<std::string>& args,
                                                      std::ostream& err) {
  OfflineRequest r;
  r.command = args[0];
  const std::string& command = r.command;
  std::vector<std::string> rest;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--at") {
      // As LEARN ... AT: x y in [0, 65535], w h in [1, 65535] image pixels.
      int v[4];
      for (int k = 0; k < 4; ++k) {
        const auto n = i + 1 < args.size() ? parseInt(args[i + 1]) : std::nullopt;
        if (!n || *n < (k < 2 ? 0 : 1) || *n > 65535) {
          err << "picksight-vision " << command
              << ": --at needs four integers X Y W H (x y in [0, 65535], w h in [1, 65535] "
                 "pixels of the image), got '"
              << (i + 1 < args.size() ? printable(args[i + 1]) : std::string("nothing")) << "'\n";
          return 2;
        }
        v[k] = static_cast<int>(*n);
        ++i;
      }
      r.at = cv::Rect(v[0], v[1], v[2], v[3]);
      continue;
    }
    if ((a == "--type" || a == "--name") && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (a == "--name") {
        r.name = v;
        continue;
      }
      const auto t = parseType(v);
      if (!t) {
        err << "picksight-vision " << command << ": --type must be an integer in [0, 9999], got '"
            << v << "'\n";
        return 2;
      }
      r.type = *t;
    } else if (a.rfind("--", 0) == 0) {
      rest.push_back(a);
      if (i + 1 < args.size()) rest.push_back(args[++i]);
    } else {
      r.images.push_back(a);
    }
  }
  auto options = parseAppArgs(rest, nullptr);
  if (!options) {
    err << "picksight-vision " << command << ": " << options.error().message << "\n\n"
        << offlineUsage();
    return 2;
  }
  if (r.at && command != "learn" && command != "learnview") {
    err << "picksight-vision " << command << ": --at is an option of learn and learnview\n";
    return 2;
  }
  if (r.images.empty() || (command == "learn" && (r.images.size() != 1 || r.type < 0)) ||
      (command == "learnview" && r.type < 0)) {
    err << offlineUsage();
    return 2;
  }
  r.options = std::move(*options);
  return r;
}

// test-run's command line as a locate over the folder's images (regular,
// not hidden, in name order, as a dir: camera serves them) and the count
// expected; or the exit status (2) once what is wrong is written to `err`.
std::variant<std::pair<std::vector<std::string>, int>, int> testRunRequest(
    const std::vector<std::string>& args, std::ostream& err) {
  std::vector<std::string> locate{"test-run"};
  std::string images;
  std::optional<int> expect;
  bool models = false;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool has_value = i + 1 < args.size();
    if (a == "--images" && has_value) {
      images = args[++i];
    } else if (a == "--expect" && has_value) {
      const auto n = parseInt(args[++i]);
      if (!n || *n < 0 || *n > 100000) {
        err << "picksight-vision test-run: --expect must be a number of parts in [0, 100000], got '"
            << printable(args[i]) << "'\n";
        return 2;
      }
      expect = static_cast<int>(*n);
    } else if (a == "--models" && has_value) {
      locate.push_back("--data-dir");
      locate.push_back(args[++i]);
      models = true;
    } else if (a.rfind("--", 0) == 0) {
      // --type and the vision settings, as locate takes them.
      locate.push_back(a);
      if (has_value) locate.push_back(args[++i]);
    } else {
      err << "picksight-vision test-run: images come from --images DIR, got '" << printable(a)
          << "'\n";
      return 2;
    }
  }
  if (images.empty() || !expect || !models) {
    err << "picksight-vision test-run: needs --models DIR, --images DIR and --expect N\n\n"
        << offlineUsage();
    return 2;
  }
  std::error_code ec;
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(images, ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.' || !e.is_regular_file(ec)) continue;
    files.push_back(e.path().string());
  }
  if (ec) {
    err << "picksight-vision test-run: --images " << images << ": " << ec.message() << "\n";
    return 2;
  }
  if (files.empty()) {
    err << "picksight-vision test-run: --images " << images << " holds no image\n";
    return 2;
  }
  std::sort(files.begin(), files.end());
  locate.insert(locate.end(), files.begin(), files.end());
  return std::make_pair(locate, *expect);
}

// LOCATE on each image against the count expected: one row per image
// (image, poses found, expected, pass or FAIL) and a last line with the
// totals. 0 when every image passed, else 1.
int testRun(const OfflineRequest& r, int expect, ModelLibrary& library,
            const CellCalibration& calibration, std::ostream& out) {
  size_t width = 5;
  for (const auto& path : r.images)
    width = std::max(width, std::filesystem::path(path).filename().string().size());
  const auto row = [&](const std::string& image, const std::string& found,
                       const std::string& result) {
    out << image << std::string(width - image.size() + 2, ' ')
        << std::string(5 - std::min<size_t>(5, found.size()), ' ') << found << "  " << std::setw(8)
        << expect << "  " << result << "\n";
  };
  out << "image" << std::string(width - 5 + 2, ' ') << "found  expected  result\n";
  size_t passed = 0;
  for (const auto& path : r.images) {
    const std::string name = std::filesystem::path(path).filename().string();
    const cv::Mat image = readFrameImage(path);
    if (image.empty()) {
      row(name, "-", "FAIL not an image");
      continue;
    }
    const auto located = locateAndPick(calibration, &library, [&]() -> Result<LocateOutcome> {
      return locateInFrame(frameFromImage(image, path, 1), r.options.vision, library.snapshot(),
                           r.type);
    });
    if (!located) {
      row(name, "-", "FAIL " + errorReply(located.error()));
      continue;
    }
    const int found = static_cast<int>(located->pick.poses.size());
    passed += found == expect;
    row(name, std::to_string(found), found == expect ? "pass" : "FAIL");
  }
  out << (passed == r.images.size() ? "PASS " : "FAIL ") << passed << " of " << r.images.size()
      << " images with " << expect
      << (r.type < 0 ? " parts of any type" : " parts of type " + std::to_string(r.type)) << "\n";
  return passed == r.images.size() ? 0 : 1;
}

// picksight-vision learn on its one image: the model stored as LEARN
// stores it. The exit status.
int learnOffline(const OfflineRequest& r, const cv::Mat& image, const std::string& path,
                 ModelLibrary& library, std::ostream& out, std::ostream& err) {
  const std::string name = r.name.empty() ? "type" + std::to_string(r.type) : r.name;
  if (!validModelName(name)) {
    err << "picksight-vision learn: name must be 1-32 of A-Z a-z 0-9 _ - .\n";
    return 2;
  }
  // As LEARN does it: the whole image binarized the way LOCATE will see it.
  const SensorMapping full;
  auto learned =
      learnInImage(image, full, r.options.vision, library.snapshot(), r.type, name, r.at);
  if (!learned) {
    out << errorReply(learned.error()) << "\n";
    return 1;
  }
  warnOfCompressedColour(isJpegFile(path), &*learned);
  std::string change =
      "picksight-vision learn --type " + std::to_string(r.type) + " --name " + name;
  if (r.at) {
    change += " --at " + std::to_string(r.at->x) + " " + std::to_string(r.at->y) + " " +
              std::to_string(r.at->width) + " " + std::to_string(r.at->height);
  }
  auto stored = library.store(learned->model, change + " " + path, teachImagePng(image));
  if (!stored) {
    out << errorReply(VisionServiceErrc::kStorageFailed,
                      "cannot store the model: " + stored.error().message)
        << "\n";
    return 1;
  }
  out << learnReply(*learned) << "\n";
  return 0;
}

// picksight-vision learnview on one of its images: the view added to the
// stored model as LEARNVIEW adds it. The exit status.
int learnViewOffline(const OfflineRequest& r, const cv::Mat& image, const std::string& path,
                     ModelLibrary& library, std::ostream& out) {
  auto view = cell::viewInFrame(frameFromImage(image, path, 1), r.options.vision,
                                library.snapshot(), r.type, r.at);
  if (!view) {
    out << errorReply(view.error()) << "\n";
    return 1;
  }
  std::string change = "picksight-vision learnview --type " + std::to_string(r.type);
  if (r.at) {
    change += " --at " + std::to_string(r.at->x) + " " + std::to_string(r.at->y) + " " +
              std::to_string(r.at->width) + " " + std::to_string(r.at->height);
  }
  if (auto stored = cell::storeView(library, r.type, *view, change + " " + path); !stored) {
    out << errorReply(stored.error()) << "\n";
    return 1;
  }
  out << learnViewReply(*view) << "\n";
  return 0;
}
}  // namespace

int runOfflineCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (!isOfflineCommand(args)) {
    err << offlineUsage();
    return 2;
  }
  if (args[0] == "lens") return runLens(args, out, err);
  std::optional<int> expect;
  std::vector<std::string> request = args;
  if (args[0] == "test-run") {
    auto rewritten = testRunRequest(args, err);
    if (const int* status = std::get_if<int>(&rewritten)) return *status;
    std::tie(request, expect) = std::get<std::pair<std::vector<std::string>, int>>(rewritten);
  }
  auto parsed = parseOfflineRequest(request, err);
  if (const int* status = std::get_if<int>(&parsed)) return *status;
  OfflineRequest& r = std::get<OfflineRequest>(parsed);
  // The vision settings the data dir's vision app runs with (VISION), the
  // options given here winning, as at its start; a damaged file is refused.
  const std::string settings_file = r.options.data_dir + "/vision.json";
  if (std::error_code ec; std::filesystem::exists(settings_file, ec)) {
    auto text = readFile(settings_file);
    auto settings =
        text ? parseVisionSettingsJson(*text, r.options.vision, r.options.vision_settings_given)
             : Result<VisionOptions>(text.error());
    if (!settings) {
      err << "picksight-vision " << r.command << ": " << settings_file << ": "
          << settings.error().message
          << " (repair it, or VISION RESET on the vision app of that data dir)\n";
      return 2;
    }
    r.options.vision = std::move(*settings);
  }
  ModelLibrary library(r.options.data_dir + "/models");
  for (const auto& problem : library.load())
    err << "picksight-vision: model rejected: " << problem << "\n";
  CellCalibration calibration(r.options.data_dir + "/calibration.yaml");
  if (auto loaded = calibration.load(); !loaded)
    err << "picksight-vision: calibration rejected: " << loaded.error().message << "\n";

  if (expect) return testRun(r, *expect, library, calibration, out);
  int status = 0;
  for (const auto& path : r.images) {
    const cv::Mat image = readFrameImage(path);
    if (image.empty()) {
      out << errorReply(ProtocolErrc::kBadArguments,
                        "cannot read image '" + printable(path, 200) + "'")
          << "\n";
      status = 1;
      continue;
    }
    if (r.command == "learn") {
      if (const int learned = learnOffline(r, image, path, library, out, err); learned != 0)
        return learned;
    } else if (r.command == "learnview") {
      // Each image a view; one refused is said and the next read.
      if (learnViewOffline(r, image, path, library, out) != 0) status = 1;
    } else if (r.command == "locate") {
      // The robot's LOCATE path on the image: same frame (calibration of
      // the data dir), same grasps.
      const auto located = locateAndPick(calibration, &library, [&]() -> Result<LocateOutcome> {
        return locateInFrame(frameFromImage(image, path, 1), r.options.vision, library.snapshot(),
                             r.type);
      });
      if (!located) {
        out << errorReply(located.error()) << "\n";
        return 1;
      }
      out << locateReply(located->pick) << "\n";
    } else {
      const auto blobs =
          blobsInImage(cell::greyImage(frameFromImage(image, path, 1)), r.options.vision);
      std::string line = "OK " + std::to_string(blobs.size());
      for (const auto& b : blobs) line += " " + blobSummary(b);
      out << line << "\n";
    }
  }
  return status;
}

}  // namespace picksight::app
