// picksight-cam: each reply as aligned text tables and key: value lines for
// people, or as one JSON object (nlohmann-json) for scripts.
#include "reply_printer.hpp"
#include "cam_cli.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "picksight/common/text.hpp"
#include "snap_writer.hpp"

namespace picksight::cam {

namespace {

// Shortest decimal text that reads back to `value`, '.' whatever the locale.
std::string formatShortest(double value) {
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  if (ec != std::errc()) return "nan";
  return std::string(buf, ptr);
}

// Like formatShortest, but without exponents for the numbers people type:
// an exposure range reads "100..1000000", not "100..1e+06". Exponents stay
// for the extremes (GenICam float ranges often end at DBL_MAX).
std::string formatReadable(double value) {
  const double magnitude = std::fabs(value);
  if (magnitude != 0 && (magnitude < 1e-6 || magnitude >= 1e15)) return formatShortest(value);
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::fixed);
  if (ec != std::errc()) return formatShortest(value);
  return std::string(buf, ptr);
}

const char* modeName(proto::AcquisitionMode mode) {
  switch (mode) {
    case proto::FREERUN:
      return "freerun";
    case proto::TRIGGER:
      return "trigger";
    case proto::HARDWARE_TRIGGER:
      return "hardware";
    default:
      return "unspecified";
  }
}

const char* featureTypeName(proto::FeatureType type) {
  switch (type) {
    case proto::INTEGER:
      return "integer";
    case proto::FLOAT:
      return "float";
    case proto::ENUMERATION:
      return "enumeration";
    case proto::BOOLEAN:
      return "boolean";
    case proto::STRING:
      return "string";
    case proto::COMMAND:
      return "command";
    default:
      return "unspecified";
  }
}

struct Column {
  std::string header;
  bool right_aligned;
};

// Columns two spaces apart, no trailing blanks, so that the table survives
// copy-paste into a ticket.
void printTable(std::ostream& out, const std::vector<Column>& columns,
                const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> widths;
  for (const Column& column : columns) widths.push_back(column.header.size());
  for (const auto& row : rows) {
    for (size_t i = 0; i < row.size() && i < widths.size(); ++i) {
      widths[i] = std::max(widths[i], row[i].size());
    }
  }
  auto print_row = [&](const std::vector<std::string>& cells) {
    std::string line;
    for (size_t i = 0; i < columns.size(); ++i) {
      const std::string& cell = i < cells.size() ? cells[i] : std::string();
      const std::string pad(widths[i] - cell.size(), ' ');
      if (i > 0) line += "  ";
      line += columns[i].right_aligned ? pad + cell : cell + pad;
    }
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << '\n';
  };
  std::vector<std::string> headers;
  for (const Column& column : columns) headers.push_back(column.header);
  print_row(headers);
  for (const auto& row : rows) print_row(row);
}

void printKeyValues(std::ostream& out, const std::vector<std::pair<std::string, std::string>>& kv) {
  size_t width = 0;
  for (const auto& [key, value] : kv) width = std::max(width, key.size());
  for (const auto& [key, value] : kv) {
    std::string line = key + ":" + std::string(width - key.size() + 1, ' ') + value;
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << '\n';
  }
}

std::string roiText(const proto::Roi& roi) {
  if (roi.x() == 0 && roi.y() == 0 && roi.width() == 0 && roi.height() == 0) return "full sensor";
  auto dim = [](std::uint32_t v) { return v == 0 ? std::string("full") : std::to_string(v); };
  return "x=" + std::to_string(roi.x()) + " y=" + std::to_string(roi.y()) +
         " width=" + dim(roi.width()) + " height=" + dim(roi.height());
}

Json roiJson(const proto::Roi& roi) {
  return {{"x", roi.x()}, {"y", roi.y()}, {"width", roi.width()}, {"height", roi.height()}};
}

// "min..max, step S" for numeric features, "A|B|C" for enumerations.
std::string rangeText(const proto::Feature& f) {
  std::string text;
  if (f.has_range()) {
    text = formatReadable(f.min()) + ".." + formatReadable(f.max());
    if (f.increment() > 0) text += ", step " + formatReadable(f.increment());
  }
  for (const auto& choice : f.choices()) text += (text.empty() ? "" : "|") + choice;
  return text;
}

// The feature as on the wire: scripts get the same fields whatever the type.
Json featureJson(const proto::Feature& f) {
  return {{"name", f.name()},
          {"type", featureTypeName(f.type())},
          {"value", f.value()},
          {"has_range", f.has_range()},
          {"min", f.min()},
          {"max", f.max()},
          {"increment", f.increment()},
          {"choices", std::vector<std::string>(f.choices().begin(), f.choices().end())},
          {"unit", f.unit()},
          {"description", f.description()},
          {"writable", f.writable()}};
}

void printFeatures(const std::string& camera, const proto::ListFeaturesReply& reply, bool as_json,
                   std::ostream& out) {
  if (as_json) {
    Json features = Json::array();
    for (const auto& f : reply.features()) features.push_back(featureJson(f));
    out << toJson({{"camera", camera}, {"features", std::move(features)}}) << '\n';
    return;
  }
  if (reply.features().empty()) {
    out << camera << ": no features\n";
    return;
  }
  std::vector<std::vector<std::string>> rows;
  for (const auto& f : reply.features()) {
    rows.push_back({f.name(), featureTypeName(f.type()), f.value(), rangeText(f), f.unit(),
                    f.writable() ? "yes" : "no"});
  }
  printTable(out,
             {{"NAME", false},
              {"TYPE", false},
              {"VALUE", false},
              {"RANGE", false},
              {"UNIT", false},
              {"WRITABLE", false}},
             rows);
}

// The reply to get (the bare value, for $(...) in shell scripts) or to set
// (the value read back, which is what the camera took).
void printFeature(const proto::ControlRequest& request, const proto::Feature& f, bool as_json,
                  std::ostream& out) {
  if (as_json) {
    out << toJson(featureJson(f)) << '\n';
    return;
  }
  if (!request.has_set_feature()) {
    out << f.value() << '\n';
    return;
  }
  out << f.name() << " = " << f.value();
  if (!f.unit().empty()) out << ' ' << f.unit();
  // Cameras round to their increment or clamp without saying so: point it out
  // when the number read back is not the one asked for.
  const std::string& asked = request.set_feature().value();
  if (f.type() == proto::INTEGER || f.type() == proto::FLOAT) {
    const std::optional<double> wanted = parseDouble(asked);
    const std::optional<double> got = parseDouble(f.value());
    if (wanted && got && *wanted != *got) out << " (requested " << asked << ')';
  }
  out << '\n';
}

void printList(const proto::ListCamerasReply& reply, bool as_json, std::ostream& out) {
  if (as_json) {
    Json cameras = Json::array();
    for (const auto& camera : reply.cameras()) {
      cameras.push_back({{"name", camera.name()},
                         {"source", camera.source()},
                         {"state", camera.state()},
                         {"mode", modeName(camera.mode())}});
    }
    out << toJson({{"cameras", std::move(cameras)}}) << '\n';
    return;
  }
  if (reply.cameras().empty()) {
    out << "no cameras\n";
    return;
  }
  std::vector<std::vector<std::string>> rows;
  for (const auto& camera : reply.cameras()) {
    rows.push_back({camera.name(), camera.source(), camera.state(), modeName(camera.mode())});
  }
  printTable(out, {{"NAME", false}, {"SOURCE", false}, {"STATE", false}, {"MODE", false}}, rows);
}

// Where the robot's target centre lies on the sensor, through the hidden
// homography; nullopt when the reply lacks it.
std::optional<std::pair<double, double>> targetOnSensor(const proto::SimulatedRobot& r) {
  if (r.robot_to_sensor_size() != 9) return std::nullopt;
  const auto& h = r.robot_to_sensor();
  const double x = r.target_x_mm();
  const double y = r.target_y_mm();
  const double w = h[6] * x + h[7] * y + h[8];
  return std::make_pair((h[0] * x + h[1] * y + h[2]) / w, (h[3] * x + h[4] * y + h[5]) / w);
}

Json robotJson(const proto::SimulatedRobot& r) {
  Json json = {{"target_visible", r.target_visible()},
               {"target_kind", r.target_kind()},
               {"target_radius_mm", r.target_radius_mm()},
               {"mm_per_px", r.mm_per_px()},
               {"rz_deg", r.rz_deg()},
               {"dx_mm", r.dx_mm()},
               {"dy_mm", r.dy_mm()},
               {"tilt_x_deg", r.tilt_x_deg()},
               {"tilt_y_deg", r.tilt_y_deg()},
               {"robot_to_sensor",
                std::vector<double>(r.robot_to_sensor().begin(), r.robot_to_sensor().end())}};
  if (r.target_kind() == "grid") {
    json["grid_rows"] = r.grid_rows();
    json["grid_cols"] = r.grid_cols();
    json["grid_pitch_mm"] = r.grid_pitch_mm();
  }
  if (r.target_visible()) {
    json["target_x_mm"] = r.target_x_mm();
    json["target_y_mm"] = r.target_y_mm();
    if (auto p = targetOnSensor(r)) {
      json["target_sensor_x"] = p->first;
      json["target_sensor_y"] = p->second;
    }
  }
  return json;
}

std::string targetText(const proto::SimulatedRobot& r) {
  std::string text = r.target_kind() + " radius " + formatReadable(r.target_radius_mm()) + " mm";
  if (r.target_kind() == "grid") {
    text += ", " + std::to_string(r.grid_cols()) + "x" + std::to_string(r.grid_rows()) + " dots " +
            formatReadable(r.grid_pitch_mm()) + " mm apart";
  }
  if (!r.target_visible()) return text + ", hidden";
  text += ", at robot " + formatFixed(r.target_x_mm(), 3) + " " + formatFixed(r.target_y_mm(), 3) +
          " mm";
  if (auto p = targetOnSensor(r)) {
    text += " = sensor " + formatFixed(p->first, 3) + " " + formatFixed(p->second, 3) + " px";
  }
  return text;
}

// The hidden transform, as the robot protocol states its own.
std::string transformText(const proto::SimulatedRobot& r) {
  return "robot = R(" + formatReadable(r.rz_deg()) + " deg) * vision + (" +
         formatReadable(r.dx_mm()) + ", " + formatReadable(r.dy_mm()) + ") mm, " +
         formatReadable(r.mm_per_px()) + " mm/px, tilt " + formatReadable(r.tilt_x_deg()) + " " +
         formatReadable(r.tilt_y_deg()) + " deg";
}

void printTarget(const std::string& camera, const proto::SimulatedRobot& r, bool as_json,
                 std::ostream& out) {
  if (as_json) {
    Json json = robotJson(r);
    json["camera"] = camera;
    out << toJson(json) << '\n';
    return;
  }
  out << camera << ": target " << targetText(r) << '\n';
}

void printInfo(const proto::DescribeCameraReply& d, bool as_json, std::ostream& out) {
  const proto::CameraSummary& s = d.summary();
  if (as_json) {
    Json json = {{"name", s.name()},
                 {"source", s.source()},
                 {"state", s.state()},
                 {"mode", modeName(s.mode())},
                 {"vendor", d.vendor()},
                 {"model", d.model()},
                 {"serial", d.serial()},
                 {"sensor_width", d.sensor_width()},
                 {"sensor_height", d.sensor_height()},
                 {"roi", roiJson(d.roi())},
                 {"output_width", d.output_width()},
                 {"output_height", d.output_height()},
                 {"pixel_format", formatName(d.pixel_format())},
                 {"fps", d.fps()},
                 {"source_formats",
                  std::vector<std::string>(d.source_formats().begin(), d.source_formats().end())}};
    if (s.mode() == proto::HARDWARE_TRIGGER) {
      json["trigger_line"] = d.trigger_line();
      json["trigger_activation"] = d.trigger_activation();
      json["trigger_timeout_ms"] = d.trigger_timeout_ms();
    }
    if (d.has_simulated_robot()) json["simulated_robot"] = robotJson(d.simulated_robot());
    out << toJson(json) << '\n';
    return;
  }
  std::string formats;
  for (const auto& format : d.source_formats()) formats += (formats.empty() ? "" : ", ") + format;
  std::vector<std::pair<std::string, std::string>> lines = {
      {"camera", s.name()},
      {"source", s.source()},
      {"state", s.state()},
      {"mode", modeName(s.mode())},
      {"vendor", d.vendor()},
      {"model", d.model()},
      {"serial", d.serial()},
      {"sensor", std::to_string(d.sensor_width()) + "x" + std::to_string(d.sensor_height())},
      {"roi", roiText(d.roi())},
      {"output", std::to_string(d.output_width()) + "x" + std::to_string(d.output_height())},
      {"pixel format", formatName(d.pixel_format())},
      {"fps", formatFixed(d.fps(), 1)},
      {"source formats", formats}};
  if (s.mode() == proto::HARDWARE_TRIGGER) {
    lines.emplace_back("trigger",
                       d.trigger_line() + " " +
                           (d.trigger_activation().empty() ? std::string("(camera's edge)")
                                                           : d.trigger_activation()) +
                           ", snap waits " + std::to_string(d.trigger_timeout_ms()) + " ms");
  }
  if (d.has_simulated_robot()) {
    lines.emplace_back("simulated robot", transformText(d.simulated_robot()));
    lines.emplace_back("target", targetText(d.simulated_robot()));
  }
  printKeyValues(out, lines);
}

void printTrigger(const std::string& camera, const proto::TriggerReply& t, bool as_json,
                  std::ostream& out) {
  if (as_json) {
    out << toJson({{"camera", camera}, {"sequence", t.sequence()}, {"triggered", t.triggered()}})
        << '\n';
    return;
  }
  // In free-run the server cannot promise a dedicated frame, only the first
  // one taken after the request (see TriggerReply): say which one we got.
  if (t.triggered()) {
    out << camera << ": triggered, the frame will carry sequence " << t.sequence() << '\n';
  } else {
    out << camera << ": camera is in free-run, the first frame after the request will carry "
        << "sequence " << t.sequence() << '\n';
  }
}

void printStats(const proto::StatisticsReply& reply, bool as_json, std::ostream& out) {
  if (as_json) {
    Json cameras = Json::array();
    for (const auto& c : reply.cameras()) {
      cameras.push_back({{"camera", c.camera()},
                         {"frames_acquired", c.frames_acquired()},
                         {"frames_published", c.frames_published()},
                         {"frames_dropped", c.frames_dropped()},
                         {"acquisition_errors", c.acquisition_errors()},
                         {"reconnects", c.reconnects()},
                         {"fps", c.fps()},
                         {"last_sequence", c.last_sequence()},
                         {"driver_incomplete_buffers", c.driver_incomplete_buffers()},
                         {"driver_missing_packets", c.driver_missing_packets()},
                         {"driver_resent_packets", c.driver_resent_packets()},
                         {"driver_underruns", c.driver_underruns()},
                         {"driver_sequence_gaps", c.driver_sequence_gaps()},
                         {"frames_skipped_stale", c.frames_skipped_stale()}});
    }
    out << toJson({{"subscribers", reply.subscribers()}, {"cameras", std::move(cameras)}}) << '\n';
    return;
  }
  std::vector<std::vector<std::string>> rows;
  for (const auto& c : reply.cameras()) {
    rows.push_back({c.camera(), std::to_string(c.frames_acquired()),
                    std::to_string(c.frames_published()), std::to_string(c.frames_dropped()),
                    std::to_string(c.acquisition_errors()), std::to_string(c.reconnects()),
                    formatFixed(c.fps(), 1), std::to_string(c.last_sequence())});
  }
  printTable(out,
             {{"CAMERA", false},
              {"ACQUIRED", true},
              {"PUBLISHED", true},
              {"DROPPED", true},
              {"ERRORS", true},
              {"RECONNECTS", true},
              {"FPS", true},
              {"LAST SEQ", true}},
             rows);
  // The driver's own counters: where frames were lost below the server.
  std::vector<std::vector<std::string>> driver_rows;
  for (const auto& c : reply.cameras()) {
    driver_rows.push_back(
        {c.camera(), std::to_string(c.driver_incomplete_buffers()),
         std::to_string(c.driver_missing_packets()), std::to_string(c.driver_resent_packets()),
         std::to_string(c.driver_underruns()), std::to_string(c.driver_sequence_gaps()),
         std::to_string(c.frames_skipped_stale())});
  }
  out << '\n';
  printTable(out,
             {{"CAMERA", false},
              {"INCOMPLETE", true},
              {"MISSING PKTS", true},
              {"RESENT PKTS", true},
              {"UNDERRUNS", true},
              {"SEQ GAPS", true},
              {"SKIPPED OLD", true}},
             driver_rows);
  out << "subscribers: " << reply.subscribers() << '\n';
}

// Confirmation for a set command, built from the request: the server's reply
// to a set carries no data beyond "OK".
void printSetConfirmation(const proto::ControlRequest& request, bool as_json, std::ostream& out) {
  Json json = {{"ok", true}};
  std::ostringstream text;
  switch (request.request_case()) {
    case proto::ControlRequest::kSetRoi: {
      const auto& r = request.set_roi();
      json["camera"] = r.camera();
      json["roi"] = roiJson(r.roi());
      text << r.camera() << ": ROI set to " << roiText(r.roi());
      break;
    }
    case proto::ControlRequest::kSetSize: {
      const auto& r = request.set_size();
      json["camera"] = r.camera();
      if (r.scale() > 0) {
        json["scale"] = r.scale();
        text << r.camera() << ": output scale set to " << formatShortest(r.scale());
      } else if (r.width() == 0) {
        json["width"] = 0;
        json["height"] = 0;
        text << r.camera() << ": output size set to the ROI size";
      } else {
        json["width"] = r.width();
        json["height"] = r.height();
        text << r.camera() << ": output size set to " << r.width() << "x" << r.height();
      }
      break;
    }
    case proto::ControlRequest::kSetMode: {
      const auto& r = request.set_mode();
      json["camera"] = r.camera();
      json["mode"] = modeName(r.mode());
      text << r.camera() << ": mode set to " << modeName(r.mode());
      if (r.mode() == proto::HARDWARE_TRIGGER) {
        // The server's defaults for what was not given.
        const std::string line = r.trigger_line().empty() ? "Line1" : r.trigger_line();
        json["trigger_line"] = line;
        text << " on " << line;
        if (!r.trigger_activation().empty()) {
          json["trigger_activation"] = r.trigger_activation();
          text << " (" << r.trigger_activation() << ")";
        }
      }
      if (r.fps() > 0) {
        json["fps"] = r.fps();
        text << " at " << formatShortest(r.fps()) << " fps";
      }
      break;
    }
    case proto::ControlRequest::kSetFormat: {
      const auto& r = request.set_format();
      json["camera"] = r.camera();
      json["pixel_format"] = formatName(r.pixel_format());
      text << r.camera() << ": pixel format set to " << formatName(r.pixel_format());
      break;
    }
    case proto::ControlRequest::kOpenStream:
      json["camera"] = request.open_stream().camera();
      json["open"] = true;
      text << request.open_stream().camera() << ": stream opened";
      break;
    case proto::ControlRequest::kCloseStream:
      json["camera"] = request.close_stream().camera();
      json["open"] = false;
      text << request.close_stream().camera() << ": stream closed, device released";
      break;
    default:
      break;
  }
  out << (as_json ? toJson(json) : text.str()) << '\n';
}

}  // namespace

std::string toJson(const Json& value) {
  return value.dump(-1, ' ', false, Json::error_handler_t::replace);
}

const char* formatName(proto::PixelFormat format) {
  switch (format) {
    case proto::MONO8:
      return "mono8";
    case proto::BGR8:
      return "bgr8";
    default:
      return "unspecified";
  }
}

Result<void> printReply(const proto::ControlRequest& request, const proto::ControlReply& reply,
                        const CamOptions& options, std::ostream& out) {
  const bool as_json = options.json;
  auto missing = [](const char* what) {
    return makeError(CliErrc::kBadReply, std::string("unexpected reply: no ") + what);
  };
  switch (request.request_case()) {
    // An empty list is a legitimate answer, and reading an absent proto3
    // message gives the empty one: no need to tell them apart.
    case proto::ControlRequest::kListCameras:
      printList(reply.list_cameras(), as_json, out);
      return {};
    case proto::ControlRequest::kStatistics:
      printStats(reply.statistics(), as_json, out);
      return {};
    // Here an absent part would print a made-up camera or sequence number.
    case proto::ControlRequest::kDescribeCamera:
      if (!reply.has_describe_camera()) return missing("camera description");
      printInfo(reply.describe_camera(), as_json, out);
      return {};
    case proto::ControlRequest::kTrigger:
      if (!reply.has_trigger()) return missing("trigger sequence number");
      printTrigger(request.trigger().camera(), reply.trigger(), as_json, out);
      return {};
    case proto::ControlRequest::kListFeatures:
      printFeatures(request.list_features().camera(), reply.list_features(), as_json, out);
      return {};
    case proto::ControlRequest::kGetFeature:
    case proto::ControlRequest::kSetFeature:
      if (!reply.feature().has_feature()) return missing("feature");
      printFeature(request, reply.feature().feature(), as_json, out);
      return {};
    case proto::ControlRequest::kSnap:
      if (!reply.has_snap()) return missing("frame");
      return saveSnap(request.snap().camera(), reply.snap(), options.command.arg("FILE"), as_json,
                      out);
    case proto::ControlRequest::kSetTarget:
      if (!reply.has_simulated_robot()) return missing("simulated robot");
      printTarget(request.set_target().camera(), reply.simulated_robot(), as_json, out);
      return {};
    default:
      printSetConfirmation(request, as_json, out);
      return {};
  }
}

}  // namespace picksight::cam
