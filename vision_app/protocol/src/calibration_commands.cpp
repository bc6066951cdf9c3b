// CALCAM, STORE, DELETE, LIST, COMPUTE, RESIDUALS. Every argument is checked
// before a frame is taken or a file written.
#include "picksight/protocol/calibration_commands.hpp"

#include <cmath>

#include "picksight/calibration/dot_grid_model.hpp"
#include "picksight/calibration/target_measurement.hpp"
#include "picksight/common/text.hpp"

namespace picksight::protocol {

using cell::TargetOutcome;
using cell::VisionService;
using cell::VisionServiceErrc;

using store::CellCalibration;
using store::CellCalibrationErrc;

namespace {
// A disc's area equals that of its equal-moment ellipse; a square's is 4.7%
// smaller, so 3% tells a disc from the usual wrong targets.
constexpr double kDiscTolerance = 0.03;
constexpr double kMaxRadiusMm = 10000;
// Robot coordinates beyond a kilometre are a robot program's bug.
constexpr double kMaxRobotMm = 1e6;

std::string reply(const Error& e) { return errorReply(e); }

bool looksLikeDisc(const cv::Moments& m) {
  const double a = m.mu20 / m.m00, b = m.mu02 / m.m00, c = m.mu11 / m.m00;
  const double det = a * b - c * c;
  if (!(det > 0)) return false;
  const double ellipse_area = 4.0 * M_PI * std::sqrt(det);
  return std::abs(ellipse_area / m.m00 - 1.0) <= kDiscTolerance;
}

// The disc target measured on its edges, in sensor pixels.
Result<calibration::DiscMeasurement> measuredDisc(const TargetOutcome& t) {
  auto disc = calibration::measureDisc(t.image, t.image_centroid, std::sqrt(t.frame_area / M_PI));
  if (!disc) return disc;
  const cv::Point2d frame_centre = disc->centre + cv::Point2d(t.image_origin);
  disc->centre = t.mapping.toSensor(frame_centre);
  disc->radius_x /= t.mapping.scale_x;
  disc->radius_y /= t.mapping.scale_y;
  return disc;
}

// CALCAM GRID <pitch_mm>: the scale from a grid of dots, and with 9 dots
// or more (3 x 3) the camera's tilt; with the whole sensor in view and no
// chessboard lens model, the lens's radial distortion as well.
std::string calcamGrid(const Request& r, VisionService& vision, CellCalibration& calibration) {
  const std::vector<std::string> rest(r.args.begin() + 1, r.args.end());
  const auto pitch = parseNumbers(rest);
  if (!pitch || pitch->size() != 1 || !((*pitch)[0] > 0) || (*pitch)[0] > kMaxRadiusMm)
    return errorReply(ProtocolErrc::kBadArguments,
                      "usage: CALCAM GRID <pitch_mm> (a number in (0, 10000])");
  auto frame = vision.greyFrame();
  if (!frame) return reply(frame.error());
  auto grid = calibration::measureDotGrid(frame->first, (*pitch)[0]);
  if (!grid) return errorReply(VisionServiceErrc::kNotADisc, grid.error().message);
  // Fitted in sensor pixels, where the vision frame starts.
  const SensorMapping& mapping = frame->second;
  std::vector<cv::Point2d> sensor;
  for (const auto& c : grid->centres) sensor.push_back(mapping.toSensor(c));
  // A lens model from chessboard views is trusted. One fitted to an
  // earlier grid is fitted again when this grid can (the whole sensor in
  // view: its middle is the centre of distortion, and dots far enough out),
  // else trusted too, so that the stored lens and the rectification always
  // agree on which pixels they were fitted to.
  const std::optional<calibration::LensModel> stored = calibration.lens();
  const bool whole_sensor =
      mapping.roi_x == 0 && mapping.roi_y == 0 && mapping.scale_x == 1 && mapping.scale_y == 1;
  const bool refit_lens = whole_sensor && !(stored && stored->views > 1);
  auto model = calibration::fitDotGrid(
      sensor, grid->indices, (*pitch)[0], refit_lens ? std::nullopt : stored,
      refit_lens ? std::optional<cv::Size>(frame->first.size()) : std::nullopt);
  if (model && refit_lens && !model->lens && stored)
    model = calibration::fitDotGrid(sensor, grid->indices, (*pitch)[0], stored, std::nullopt);
  if (!model) return errorReply(VisionServiceErrc::kNotADisc, model.error().message);
  if (auto ok = calibration.setGridCalibration(model->scale, model->lens); !ok)
    return reply(ok.error());
  return "OK " + formatFixed(model->scale.mm_per_px_x, 6) + " " +
         formatFixed(model->scale.mm_per_px_y, 6);
}

std::string calcam(const Request& r, VisionService& vision, CellCalibration& calibration) {
  if (!r.args.empty() && toUpper(r.args[0]) == "GRID") return calcamGrid(r, vision, calibration);
  const auto radius = parseNumbers(r.args);
  if (!radius || radius->size() != 1 || !((*radius)[0] > 0) || (*radius)[0] > kMaxRadiusMm)
    return errorReply(ProtocolErrc::kBadArguments,
                      "usage: CALCAM <radius_mm> (a number in (0, 10000])");
  auto target = vision.target();
  if (!target) return reply(target.error());
  if (!looksLikeDisc(target->moments))
    return errorReply(VisionServiceErrc::kNotADisc,
                      "the target is not a disc (check the target and the lighting)");
  auto disc = measuredDisc(*target);
  if (!disc) return errorReply(VisionServiceErrc::kNotADisc, disc.error().message);
  auto scale = calibration::scaleFromDisc(*disc, (*radius)[0]);
  if (!scale) return errorReply(VisionServiceErrc::kNotADisc, scale.error().message);
  if (auto ok = calibration.setScale(*scale); !ok) return reply(ok.error());
  return "OK " + formatFixed(scale->mm_per_px_x, 6) + " " + formatFixed(scale->mm_per_px_y, 6);
}

std::string store(const Request& r, VisionService& vision, CellCalibration& calibration) {
  const auto robot = parseNumbers(r.args);
  if (!robot || robot->size() != 2 || !std::isfinite((*robot)[0]) || !std::isfinite((*robot)[1]) ||
      std::abs((*robot)[0]) > kMaxRobotMm || std::abs((*robot)[1]) > kMaxRobotMm)
    return errorReply(ProtocolErrc::kBadArguments,
                      "usage: STORE <x> <y> (robot mm, each within +-1000000)");
  // Checked before a frame is taken: a damaged calibration or a full list
  // costs no camera time.
  auto geometry = calibration.geometry();
  if (!geometry) return reply(geometry.error());
  if (calibration.summary().points >= CellCalibration::kMaxPoints) {
    return errorReply(
        CellCalibrationErrc::kTooManyPoints,
        std::to_string(CellCalibration::kMaxPoints) + " points are stored already (DELETE some)");
  }
  auto target = vision.target();
  if (!target) return reply(target.error());
  // A disc's centre from its edges (unbiased by uneven light); any other
  // target's grey-weighted centroid.
  cv::Point2d centre = target->centroid;
  if (looksLikeDisc(target->moments)) {
    if (auto disc = measuredDisc(*target)) centre = disc->centre;
  }
  const calibration::PointPair pair{geometry->vision.toMm(centre), {(*robot)[0], (*robot)[1]}};
  auto id = calibration.addPoint(pair, centre);
  if (!id) return reply(id.error());
  return "OK " + std::to_string(*id);
}

std::string list(const Request& r, CellCalibration& calibration) {
  if (!r.args.empty()) return errorReply(ProtocolErrc::kBadArguments, "LIST takes no arguments");
  const auto points = calibration.points();
  std::string out = "OK " + std::to_string(points.size());
  for (const auto& [id, p] : points) {
    out += " " + std::to_string(id) + " " + formatFixed(p.vision.x) + " " +
           formatFixed(p.vision.y) + " " + formatFixed(p.robot.x) + " " + formatFixed(p.robot.y);
  }
  return out;
}

std::optional<calibration::Method> parseMethod(const std::vector<std::string>& args) {
  if (args.empty()) return calibration::Method::kBest;
  if (args.size() != 1) return std::nullopt;
  const std::string m = toUpper(args[0]);
  if (m == "BEST") return calibration::Method::kBest;
  if (m == "LSQ") return calibration::Method::kLeastSquares;
  if (m == "GEOMETRIC") return calibration::Method::kGeometric;
  if (m == "SIMILARITY") return calibration::Method::kSimilarity;
  if (m == "TILT") return calibration::Method::kTilt;
  if (m == "HOMOGRAPHY") return calibration::Method::kHomography;
  return std::nullopt;
}
}  // namespace

void addCalibrationCommands(CommandTable& table, VisionService& vision,
                            CellCalibration& calibration) {
  table.add(
      "CALCAM", "CALCAM <radius_mm> or CALCAM GRID <pitch_mm>",
      [&](const Request& r) { return calcam(r, vision, calibration); }, alwaysChanges,
      Publishes::kFrame);
  table.add(
      "STORE", "STORE <x> <y>", [&](const Request& r) { return store(r, vision, calibration); },
      alwaysChanges, Publishes::kFrame);
  table.add("DELETE", "DELETE <id>", [&](const Request& r) {
    const auto id = r.args.size() == 1 ? parseInt(r.args[0]) : std::nullopt;
    if (!id || *id < 0 || *id > 1000000000)
      return errorReply(ProtocolErrc::kBadArguments, "usage: DELETE <id> (see LIST)");
    auto ok = calibration.deletePoint(static_cast<int>(*id));
    return ok ? std::string("OK") : reply(ok.error());
  });
  table.add(
      "LIST", "LIST", [&](const Request& r) { return list(r, calibration); }, neverChanges);
  constexpr const char* kComputeUsage = "COMPUTE [BEST|LSQ|GEOMETRIC|SIMILARITY|TILT|HOMOGRAPHY]";
  table.add("COMPUTE", kComputeUsage, [&](const Request& r) {
    const auto method = parseMethod(r.args);
    if (!method)
      return errorReply(ProtocolErrc::kBadArguments, std::string("usage: ") + kComputeUsage);
    auto result = calibration.compute(*method);
    if (!result) return reply(result.error());
    // Four fields whatever the model, as robot programs parse them; the
    // model and its scale are in the calibration file (and picksight-calib).
    const auto& t = result->transform;
    return "OK " + formatFixed(t.dx) + " " + formatFixed(t.dy) + " " + formatFixed(t.rz_deg) + " " +
           formatFixed(result->rms);
  });
  table.add("CLEARCAL", "CLEARCAL", [&](const Request& r) {
    if (!r.args.empty())
      return errorReply(ProtocolErrc::kBadArguments, "CLEARCAL takes no arguments");
    auto ok = calibration.clear();
    return ok ? std::string("OK") : reply(ok.error());
  });
  table.add(
      "RESIDUALS", "RESIDUALS",
      [&](const Request& r) {
        if (!r.args.empty())
          return errorReply(ProtocolErrc::kBadArguments, "RESIDUALS takes no arguments");
        const auto geometry = calibration.geometry();
        if (!geometry) return reply(geometry.error());
        if (!geometry->transform)
          return errorReply(CellCalibrationErrc::kNotComputed,
                            "no robot-camera transform yet (see COMPUTE)");
        const auto points = calibration.points();
        std::string out = "OK " + std::to_string(points.size());
        for (const auto& [id, p] : points) {
          const cv::Point2d d = geometry->transform->apply(p.vision) - p.robot;
          out += " " + std::to_string(id) + " " + formatFixed(d.x) + " " + formatFixed(d.y) + " " +
                 formatFixed(std::hypot(d.x, d.y));
        }
        return out;
      },
      neverChanges);
}

}  // namespace picksight::protocol
