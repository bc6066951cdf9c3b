// picksight-cam: each reply as aligned text tables and key: value lines for
// people, or as one JSON object (nlohmann-json) for scripts.
#include "reply_printer.hpp"
#include "cam_cli.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
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

// One field of a reply, listed once for both outputs: its JSON key ("" =
// text only) and its text label or column header ("" = JSON only), with
// its value for each. Without a text function the text is the JSON value's
// own (a string as it is, a number in decimal).
template <typename T>
struct Field {
  const char* key;
  const char* label;
  std::function<Json(const T&)> json;
  std::function<std::string(const T&)> text = {};
  bool right_aligned = false;
  int table = 0;  // which of the reply's text tables shows it

  std::string textOf(const T& item) const {
    if (text) return text(item);
    const Json value = json(item);
    return value.is_string() ? value.template get<std::string>() : value.dump();
  }
};

template <typename T>
using Fields = std::vector<Field<T>>;

// The item's JSON object: its fields that have a key, in their order.
template <typename T>
Json fieldsJson(const Fields<T>& fields, const T& item) {
  Json json = Json::object();
  for (const auto& f : fields)
    if (*f.key) json[f.key] = f.json(item);
  return json;
}

// A table of the items: a column per field of `table` that has a label.
template <typename T, typename Items>
void printFieldTable(std::ostream& out, const Fields<T>& fields, const Items& items,
                     int table = 0) {
  std::vector<Column> columns;
  for (const auto& f : fields)
    if (*f.label && f.table == table) columns.push_back({f.label, f.right_aligned});
  std::vector<std::vector<std::string>> rows;
  for (const T& item : items) {
    rows.emplace_back();
    for (const auto& f : fields)
      if (*f.label && f.table == table) rows.back().push_back(f.textOf(item));
  }
  printTable(out, columns, rows);
}

// "label: value" lines of the item's fields that have a label.
template <typename T>
std::vector<std::pair<std::string, std::string>> fieldLines(const Fields<T>& fields,
                                                            const T& item) {
  std::vector<std::pair<std::string, std::string>> lines;
  for (const auto& f : fields)
    if (*f.label) lines.emplace_back(f.label, f.textOf(item));
  return lines;
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
const Fields<proto::Feature>& featureFields() {
  using F = proto::Feature;
  static const Fields<F> fields = {
      {"name", "NAME", [](const F& f) { return Json(f.name()); }},
      {"type", "TYPE", [](const F& f) { return Json(featureTypeName(f.type())); }},
      {"value", "VALUE", [](const F& f) { return Json(f.value()); }},
      {"", "RANGE", {}, rangeText},
      {"has_range", "", [](const F& f) { return Json(f.has_range()); }},
      {"min", "", [](const F& f) { return Json(f.min()); }},
      {"max", "", [](const F& f) { return Json(f.max()); }},
      {"increment", "", [](const F& f) { return Json(f.increment()); }},
      {"choices", "",
       [](const F& f) {
         return Json(std::vector<std::string>(f.choices().begin(), f.choices().end()));
       }},
      {"unit", "UNIT", [](const F& f) { return Json(f.unit()); }},
      {"description", "", [](const F& f) { return Json(f.description()); }},
      {"writable", "WRITABLE", [](const F& f) { return Json(f.writable()); },
       [](const F& f) { return std::string(f.writable() ? "yes" : "no"); }},
  };
  return fields;
}

Json featureJson(const proto::Feature& f) { return fieldsJson(featureFields(), f); }

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
  printFieldTable(out, featureFields(), reply.features());
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

const Fields<proto::CameraSummary>& cameraFields() {
  using C = proto::CameraSummary;
  static const Fields<C> fields = {
      {"name", "NAME", [](const C& c) { return Json(c.name()); }},
      {"source", "SOURCE", [](const C& c) { return Json(c.source()); }},
      {"state", "STATE", [](const C& c) { return Json(c.state()); }},
      {"mode", "MODE", [](const C& c) { return Json(modeName(c.mode())); }},
  };
  return fields;
}

void printList(const proto::ListCamerasReply& reply, bool as_json, std::ostream& out) {
  if (as_json) {
    Json cameras = Json::array();
    for (const auto& camera : reply.cameras())
      cameras.push_back(fieldsJson(cameraFields(), camera));
    out << toJson({{"cameras", std::move(cameras)}}) << '\n';
    return;
  }
  if (reply.cameras().empty()) {
    out << "no cameras\n";
    return;
  }
  printFieldTable(out, cameraFields(), reply.cameras());
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

std::string sizeText(uint32_t width, uint32_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

const Fields<proto::DescribeCameraReply>& describeFields() {
  using D = proto::DescribeCameraReply;
  static const Fields<D> fields = {
      {"name", "camera", [](const D& d) { return Json(d.summary().name()); }},
      {"source", "source", [](const D& d) { return Json(d.summary().source()); }},
      {"state", "state", [](const D& d) { return Json(d.summary().state()); }},
      {"mode", "mode", [](const D& d) { return Json(modeName(d.summary().mode())); }},
      {"vendor", "vendor", [](const D& d) { return Json(d.vendor()); }},
      {"model", "model", [](const D& d) { return Json(d.model()); }},
      {"serial", "serial", [](const D& d) { return Json(d.serial()); }},
      {"sensor_width", "", [](const D& d) { return Json(d.sensor_width()); }},
      {"sensor_height", "", [](const D& d) { return Json(d.sensor_height()); }},
      {"", "sensor", {}, [](const D& d) { return sizeText(d.sensor_width(), d.sensor_height()); }},
      {"roi", "roi", [](const D& d) { return roiJson(d.roi()); },
       [](const D& d) { return roiText(d.roi()); }},
      {"output_width", "", [](const D& d) { return Json(d.output_width()); }},
      {"output_height", "", [](const D& d) { return Json(d.output_height()); }},
      {"", "output", {}, [](const D& d) { return sizeText(d.output_width(), d.output_height()); }},
      {"pixel_format", "pixel format",
       [](const D& d) { return Json(formatName(d.pixel_format())); }},
      {"fps", "fps", [](const D& d) { return Json(d.fps()); },
       [](const D& d) { return formatFixed(d.fps(), 1); }},
      {"source_formats", "source formats",
       [](const D& d) {
         return Json(
             std::vector<std::string>(d.source_formats().begin(), d.source_formats().end()));
       },
       [](const D& d) {
         std::string formats;
         for (const auto& format : d.source_formats())
           formats += (formats.empty() ? "" : ", ") + format;
         return formats;
       }},
  };
  return fields;
}

void printInfo(const proto::DescribeCameraReply& d, bool as_json, std::ostream& out) {
  const bool hardware = d.summary().mode() == proto::HARDWARE_TRIGGER;
  if (as_json) {
    Json json = fieldsJson(describeFields(), d);
    if (hardware) {
      json["trigger_line"] = d.trigger_line();
      json["trigger_activation"] = d.trigger_activation();
      json["trigger_timeout_ms"] = d.trigger_timeout_ms();
    }
    if (d.has_simulated_robot()) json["simulated_robot"] = robotJson(d.simulated_robot());
    out << toJson(json) << '\n';
    return;
  }
  auto lines = fieldLines(describeFields(), d);
  if (hardware) {
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

// A camera's counters: the server's (table 0) and its driver's, where
// frames were lost below the server (table 1); the camera names both.
const Fields<proto::CameraStatistics>& statisticsFields() {
  using C = proto::CameraStatistics;
  using Getter = uint64_t (C::*)() const;
  const auto counter = [](const char* key, const char* header, Getter get, int table) {
    return Field<C>{key, header, [get](const C& c) { return Json((c.*get)()); }, {}, true, table};
  };
  static const Fields<C> fields = {
      {"camera", "CAMERA", [](const C& c) { return Json(c.camera()); }},
      counter("frames_acquired", "ACQUIRED", &C::frames_acquired, 0),
      counter("frames_published", "PUBLISHED", &C::frames_published, 0),
      counter("frames_dropped", "DROPPED", &C::frames_dropped, 0),
      counter("acquisition_errors", "ERRORS", &C::acquisition_errors, 0),
      counter("reconnects", "RECONNECTS", &C::reconnects, 0),
      {"fps", "FPS", [](const C& c) { return Json(c.fps()); },
       [](const C& c) { return formatFixed(c.fps(), 1); }, true},
      counter("last_sequence", "LAST SEQ", &C::last_sequence, 0),
      counter("driver_incomplete_buffers", "INCOMPLETE", &C::driver_incomplete_buffers, 1),
      counter("driver_missing_packets", "MISSING PKTS", &C::driver_missing_packets, 1),
      counter("driver_resent_packets", "RESENT PKTS", &C::driver_resent_packets, 1),
      counter("driver_underruns", "UNDERRUNS", &C::driver_underruns, 1),
      counter("driver_sequence_gaps", "SEQ GAPS", &C::driver_sequence_gaps, 1),
      counter("frames_skipped_stale", "SKIPPED OLD", &C::frames_skipped_stale, 1),
  };
  return fields;
}

void printStats(const proto::StatisticsReply& reply, bool as_json, std::ostream& out) {
  if (as_json) {
    Json cameras = Json::array();
    for (const auto& c : reply.cameras()) cameras.push_back(fieldsJson(statisticsFields(), c));
    out << toJson({{"subscribers", reply.subscribers()}, {"cameras", std::move(cameras)}}) << '\n';
    return;
  }
  // The camera's column heads both tables.
  Fields<proto::CameraStatistics> driver = statisticsFields();
  driver.front().table = 1;
  printFieldTable(out, statisticsFields(), reply.cameras(), 0);
  out << '\n';
  printFieldTable(out, driver, reply.cameras(), 1);
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
