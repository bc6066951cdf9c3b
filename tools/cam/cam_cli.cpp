// picksight-cam: parses the command line into one control request, sends it
// through ControlClient and prints the reply as text for people or JSON for
// scripts.
#include "cam_cli.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "picksight/common/text.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"

namespace picksight::cam {

const char* errorName(CliErrc e) {
  return e == CliErrc::kUsage ? "usage" : e == CliErrc::kBadReply ? "bad reply" : "save failed";
}

namespace {

constexpr const char* kProgram = "picksight-cam";

// Usage errors are carried in Result as Error{kExitUsage, message}.
Error usageError(std::string message) { return makeError(CliErrc::kUsage, std::move(message)); }

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

// Codes of the errors that printReply returns; both exit with
// kExitServerError, but only a reply the CLI cannot use is the server's fault,
// and only then does the message name the server.

// Index of FILE in "snap CAM FILE": the request has no field for it, so the
// command words carry it to the code that writes the frame.
constexpr size_t kSnapFileArg = 2;

// ------------------------------------------------------------- argument parsing

Result<std::uint32_t> parseUint32(std::string_view command, std::string_view name,
                                  const std::string& text) {
  const std::optional<long long> value = parseInt(text);
  if (!value || *value < 0) {
    return usageError(std::string(command) + ": " + std::string(name) +
                      " must be a non-negative integer, got '" + text + "'");
  }
  if (*value > std::numeric_limits<std::uint32_t>::max()) {
    return usageError(std::string(command) + ": " + std::string(name) + " is too large, got '" +
                      text + "'");
  }
  return static_cast<std::uint32_t>(*value);
}

Result<double> parsePositive(std::string_view command, std::string_view name,
                             const std::string& text) {
  const std::optional<double> value = parseDouble(text);
  if (!value || !(*value > 0)) {
    return usageError(std::string(command) + ": " + std::string(name) +
                      " must be a positive number, got '" + text + "'");
  }
  return *value;
}

Result<std::string> parseWord(std::string_view command, std::string_view name,
                              const std::string& text) {
  if (text.empty()) {
    return usageError(std::string(command) + ": " + std::string(name) + " must not be empty");
  }
  return text;
}

Result<std::string> parseCamera(std::string_view command, const std::string& text) {
  return parseWord(command, "CAM", text);
}

// Checks the argument count of `command`; `synopsis` is its usage line.
Result<void> checkCount(const std::vector<std::string>& command, size_t min_args, size_t max_args,
                        std::string_view synopsis) {
  const size_t n = command.size() - 1;
  if (n >= min_args && n <= max_args) return {};
  std::string what = n < min_args ? "missing arguments" : "too many arguments";
  if (n > max_args) what += " (unexpected '" + command[max_args + 1] + "')";
  return usageError(command[0] + ": " + what + "; usage: " + kProgram + " " +
                    std::string(synopsis));
}

// The camera of a command whose synopsis starts "COMMAND CAM", after checking
// the argument count.
Result<std::string> cameraOf(const std::vector<std::string>& command, size_t min_args,
                             size_t max_args, std::string_view synopsis) {
  if (auto ok = checkCount(command, min_args, max_args, synopsis); !ok) return ok.error();
  return parseCamera(command[0], command[1]);
}

Result<proto::ControlRequest> buildRoi(const std::vector<std::string>& c) {
  if (auto ok = checkCount(c, 5, 5, "roi CAM X Y W H"); !ok) return ok.error();
  auto camera = parseCamera(c[0], c[1]);
  if (!camera) return camera.error();
  const char* names[] = {"X", "Y", "W", "H"};
  std::uint32_t v[4] = {};
  for (int i = 0; i < 4; ++i) {
    auto parsed = parseUint32(c[0], names[i], c[static_cast<size_t>(i) + 2]);
    if (!parsed) return parsed.error();
    v[i] = *parsed;
  }
  proto::ControlRequest request;
  auto* roi_request = request.mutable_set_roi();
  roi_request->set_camera(*camera);
  auto* roi = roi_request->mutable_roi();
  roi->set_x(v[0]);
  roi->set_y(v[1]);
  roi->set_width(v[2]);
  roi->set_height(v[3]);
  return request;
}

Result<proto::ControlRequest> buildSize(const std::vector<std::string>& c) {
  static constexpr std::string_view kSynopsis = "size CAM W H | size CAM --scale S";
  if (auto ok = checkCount(c, 3, 3, kSynopsis); !ok) return ok.error();
  auto camera = parseCamera(c[0], c[1]);
  if (!camera) return camera.error();
  proto::ControlRequest request;
  auto* size = request.mutable_set_size();
  size->set_camera(*camera);
  if (c[2] == "--scale") {
    auto scale = parsePositive(c[0], "S", c[3]);
    if (!scale) return scale.error();
    size->set_scale(*scale);
    return request;
  }
  auto width = parseUint32(c[0], "W", c[2]);
  if (!width) return width.error();
  auto height = parseUint32(c[0], "H", c[3]);
  if (!height) return height.error();
  size->set_width(*width);
  size->set_height(*height);
  return request;
}

Result<proto::ControlRequest> buildMode(const std::vector<std::string>& c) {
  if (auto ok = checkCount(c, 2, 3, "mode CAM freerun|trigger [FPS]"); !ok) return ok.error();
  auto camera = parseCamera(c[0], c[1]);
  if (!camera) return camera.error();
  proto::ControlRequest request;
  auto* mode = request.mutable_set_mode();
  mode->set_camera(*camera);
  if (c[2] == "freerun") {
    mode->set_mode(proto::FREERUN);
  } else if (c[2] == "trigger") {
    mode->set_mode(proto::TRIGGER);
  } else {
    return usageError("mode: mode must be 'freerun' or 'trigger', got '" + c[2] + "'");
  }
  if (c.size() == 4) {
    auto fps = parsePositive(c[0], "FPS", c[3]);
    if (!fps) return fps.error();
    mode->set_fps(*fps);
  }
  return request;
}

Result<proto::ControlRequest> buildFormat(const std::vector<std::string>& c) {
  if (auto ok = checkCount(c, 2, 2, "format CAM mono8|bgr8"); !ok) return ok.error();
  auto camera = parseCamera(c[0], c[1]);
  if (!camera) return camera.error();
  proto::ControlRequest request;
  auto* format = request.mutable_set_format();
  format->set_camera(*camera);
  if (c[2] == "mono8") {
    format->set_pixel_format(proto::MONO8);
  } else if (c[2] == "bgr8") {
    format->set_pixel_format(proto::BGR8);
  } else {
    return usageError("format: format must be 'mono8' or 'bgr8', got '" + c[2] + "'");
  }
  return request;
}

// A command whose one argument is the camera: they differ only in the
// request they fill.
struct CameraCommand {
  std::string_view name;
  std::string_view synopsis;
  void (*fill)(proto::ControlRequest& request, const std::string& camera);
};

const CameraCommand* findCameraCommand(std::string_view name) {
  static const CameraCommand kCommands[] = {
      {"info", "info CAM",
       [](proto::ControlRequest& r, const std::string& c) {
         r.mutable_describe_camera()->set_camera(c);
       }},
      {"trigger", "trigger CAM",
       [](proto::ControlRequest& r, const std::string& c) { r.mutable_trigger()->set_camera(c); }},
      {"features", "features CAM",
       [](proto::ControlRequest& r, const std::string& c) {
         r.mutable_list_features()->set_camera(c);
       }},
      {"open", "open CAM",
       [](proto::ControlRequest& r, const std::string& c) {
         r.mutable_open_stream()->set_camera(c);
       }},
      {"close", "close CAM",
       [](proto::ControlRequest& r, const std::string& c) {
         r.mutable_close_stream()->set_camera(c);
       }},
  };
  for (const CameraCommand& command : kCommands) {
    if (command.name == name) return &command;
  }
  return nullptr;
}

// "get CAM FEATURE" and "set CAM FEATURE VALUE".
Result<proto::ControlRequest> buildFeature(const std::vector<std::string>& c) {
  const bool set = c[0] == "set";
  auto camera =
      cameraOf(c, set ? 3 : 2, set ? 3 : 2, set ? "set CAM FEATURE VALUE" : "get CAM FEATURE");
  if (!camera) return camera.error();
  auto feature = parseWord(c[0], "FEATURE", c[2]);
  if (!feature) return feature.error();
  proto::ControlRequest request;
  if (!set) {
    request.mutable_get_feature()->set_camera(*camera);
    request.mutable_get_feature()->set_name(*feature);
    return request;
  }
  // An empty VALUE stays allowed: it is a legitimate value of a string feature.
  auto* set_feature = request.mutable_set_feature();
  set_feature->set_camera(*camera);
  set_feature->set_name(*feature);
  set_feature->set_value(c[3]);
  return request;
}

Result<proto::ControlRequest> buildSnap(const std::vector<std::string>& c) {
  auto camera = cameraOf(c, 2, 2, "snap CAM FILE");
  if (!camera) return camera.error();
  const std::string& file = c[kSnapFileArg];
  if (auto ok = parseWord(c[0], "FILE", file); !ok) return ok.error();
  // Checked before asking: a snap in trigger mode takes a frame that the
  // vision apps receive too, which should not happen for a file never written.
  if (!cv::haveImageWriter(file)) {
    return usageError("snap: no image writer for '" + file +
                      "'; the extension names the format (.png, .jpg, .tiff, .bmp)");
  }
  proto::ControlRequest request;
  request.mutable_snap()->set_camera(*camera);
  return request;
}

// ------------------------------------------------------------------- output

const char* modeName(proto::AcquisitionMode mode) {
  switch (mode) {
    case proto::FREERUN:
      return "freerun";
    case proto::TRIGGER:
      return "trigger";
    default:
      return "unspecified";
  }
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

void writeRoi(JsonWriter& json, const proto::Roi& roi) {
  json.beginObject();
  json.key("x").uinteger(roi.x()).key("y").uinteger(roi.y());
  json.key("width").uinteger(roi.width()).key("height").uinteger(roi.height());
  json.endObject();
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
void writeFeature(JsonWriter& json, const proto::Feature& f) {
  json.beginObject();
  json.key("name").string(f.name()).key("type").string(featureTypeName(f.type()));
  json.key("value").string(f.value()).key("has_range").boolean(f.has_range());
  json.key("min").real(f.min()).key("max").real(f.max()).key("increment").real(f.increment());
  json.key("choices").beginArray();
  for (const auto& choice : f.choices()) json.string(choice);
  json.endArray();
  json.key("unit").string(f.unit()).key("description").string(f.description());
  json.key("writable").boolean(f.writable());
  json.endObject();
}

void printFeatures(const std::string& camera, const proto::ListFeaturesReply& reply, bool as_json,
                   std::ostream& out) {
  if (as_json) {
    JsonWriter json;
    json.beginObject().key("camera").string(camera).key("features").beginArray();
    for (const auto& f : reply.features()) writeFeature(json, f);
    json.endArray().endObject();
    out << json.str() << '\n';
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
    JsonWriter json;
    writeFeature(json, f);
    out << json.str() << '\n';
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

// Writes the snapped frame to `file` in the format its extension names.
Result<void> saveSnap(const std::string& camera, const proto::SnapReply& snap,
                      const std::string& file, bool as_json, std::ostream& out) {
  const proto::FrameHeader& h = snap.header();
  if (!frameIsConsistent(h, snap.pixels().size())) {
    return makeError(CliErrc::kBadReply,
                     "inconsistent frame: " + std::to_string(h.width()) + "x" +
                         std::to_string(h.height()) + " " + formatName(h.pixel_format()) +
                         " with stride " + std::to_string(h.stride()) + " needs " +
                         std::to_string(std::uint64_t{h.stride()} * h.height()) +
                         " bytes of pixels, got " + std::to_string(snap.pixels().size()));
  }
  // Decoded as a subscriber decodes a published frame, so that the file holds
  // what a vision app would have seen. The copy is one frame, once.
  const auto frame = decodeFrame(h, zmq::message_t(snap.pixels().data(), snap.pixels().size()));
  bool written = false;
  std::string reason = "cannot write the file (does its directory exist, is it writable?)";
  try {
    written = cv::imwrite(file, frame->image);
  } catch (const cv::Exception& e) {
    reason = e.err;  // what() adds OpenCV's source path and line
  }
  if (!written) return makeError(CliErrc::kSaveFailed, "could not save '" + file + "': " + reason);

  if (as_json) {
    JsonWriter json;
    json.beginObject().key("camera").string(camera).key("file").string(file);
    json.key("sequence").uinteger(h.sequence());
    json.key("width").uinteger(h.width()).key("height").uinteger(h.height());
    json.key("pixel_format").string(formatName(h.pixel_format()));
    json.key("triggered").boolean(h.triggered());
    json.key("device_timestamp_ns").uinteger(h.device_timestamp_ns());
    json.key("host_timestamp_ns").uinteger(h.host_timestamp_ns());
    json.endObject();
    out << json.str() << '\n';
    return {};
  }
  out << "saved " << h.width() << 'x' << h.height() << ' ' << formatName(h.pixel_format())
      << " frame #" << h.sequence() << " to " << file << '\n';
  return {};
}

void printList(const proto::ListCamerasReply& reply, bool as_json, std::ostream& out) {
  if (as_json) {
    JsonWriter json;
    json.beginObject().key("cameras").beginArray();
    for (const auto& camera : reply.cameras()) {
      json.beginObject();
      json.key("name").string(camera.name()).key("source").string(camera.source());
      json.key("state").string(camera.state()).key("mode").string(modeName(camera.mode()));
      json.endObject();
    }
    json.endArray().endObject();
    out << json.str() << '\n';
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

void printInfo(const proto::DescribeCameraReply& d, bool as_json, std::ostream& out) {
  const proto::CameraSummary& s = d.summary();
  if (as_json) {
    JsonWriter json;
    json.beginObject();
    json.key("name").string(s.name()).key("source").string(s.source());
    json.key("state").string(s.state()).key("mode").string(modeName(s.mode()));
    json.key("vendor").string(d.vendor()).key("model").string(d.model());
    json.key("serial").string(d.serial());
    json.key("sensor_width").uinteger(d.sensor_width());
    json.key("sensor_height").uinteger(d.sensor_height());
    json.key("roi");
    writeRoi(json, d.roi());
    json.key("output_width").uinteger(d.output_width());
    json.key("output_height").uinteger(d.output_height());
    json.key("pixel_format").string(formatName(d.pixel_format()));
    json.key("fps").real(d.fps());
    json.key("source_formats").beginArray();
    for (const auto& format : d.source_formats()) json.string(format);
    json.endArray().endObject();
    out << json.str() << '\n';
    return;
  }
  std::string formats;
  for (const auto& format : d.source_formats()) formats += (formats.empty() ? "" : ", ") + format;
  printKeyValues(
      out, {{"camera", s.name()},
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
            {"source formats", formats}});
}

void printTrigger(const std::string& camera, const proto::TriggerReply& t, bool as_json,
                  std::ostream& out) {
  if (as_json) {
    JsonWriter json;
    json.beginObject().key("camera").string(camera);
    json.key("sequence").uinteger(t.sequence()).key("triggered").boolean(t.triggered());
    json.endObject();
    out << json.str() << '\n';
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
    JsonWriter json;
    json.beginObject().key("subscribers").uinteger(reply.subscribers());
    json.key("cameras").beginArray();
    for (const auto& c : reply.cameras()) {
      json.beginObject().key("camera").string(c.camera());
      json.key("frames_acquired").uinteger(c.frames_acquired());
      json.key("frames_published").uinteger(c.frames_published());
      json.key("frames_dropped").uinteger(c.frames_dropped());
      json.key("acquisition_errors").uinteger(c.acquisition_errors());
      json.key("reconnects").uinteger(c.reconnects());
      json.key("fps").real(c.fps());
      json.key("last_sequence").uinteger(c.last_sequence());
      json.endObject();
    }
    json.endArray().endObject();
    out << json.str() << '\n';
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
  out << "subscribers: " << reply.subscribers() << '\n';
}

// Confirmation for a set command, built from the request: the server's reply
// to a set carries no data beyond "OK".
void printSetConfirmation(const proto::ControlRequest& request, bool as_json, std::ostream& out) {
  JsonWriter json;
  std::ostringstream text;
  json.beginObject().key("ok").boolean(true);
  switch (request.request_case()) {
    case proto::ControlRequest::kSetRoi: {
      const auto& r = request.set_roi();
      json.key("camera").string(r.camera()).key("roi");
      writeRoi(json, r.roi());
      text << r.camera() << ": ROI set to " << roiText(r.roi());
      break;
    }
    case proto::ControlRequest::kSetSize: {
      const auto& r = request.set_size();
      json.key("camera").string(r.camera());
      if (r.scale() > 0) {
        json.key("scale").real(r.scale());
        text << r.camera() << ": output scale set to " << formatShortest(r.scale());
      } else if (r.width() == 0) {
        json.key("width").uinteger(0).key("height").uinteger(0);
        text << r.camera() << ": output size set to the ROI size";
      } else {
        json.key("width").uinteger(r.width()).key("height").uinteger(r.height());
        text << r.camera() << ": output size set to " << r.width() << "x" << r.height();
      }
      break;
    }
    case proto::ControlRequest::kSetMode: {
      const auto& r = request.set_mode();
      json.key("camera").string(r.camera()).key("mode").string(modeName(r.mode()));
      text << r.camera() << ": mode set to " << modeName(r.mode());
      if (r.fps() > 0) {
        json.key("fps").real(r.fps());
        text << " at " << formatShortest(r.fps()) << " fps";
      }
      break;
    }
    case proto::ControlRequest::kSetFormat: {
      const auto& r = request.set_format();
      json.key("camera").string(r.camera());
      json.key("pixel_format").string(formatName(r.pixel_format()));
      text << r.camera() << ": pixel format set to " << formatName(r.pixel_format());
      break;
    }
    case proto::ControlRequest::kOpenStream:
      json.key("camera").string(request.open_stream().camera()).key("open").boolean(true);
      text << request.open_stream().camera() << ": stream opened";
      break;
    case proto::ControlRequest::kCloseStream:
      json.key("camera").string(request.close_stream().camera()).key("open").boolean(false);
      text << request.close_stream().camera() << ": stream closed, device released";
      break;
    default:
      break;
  }
  json.endObject();
  out << (as_json ? json.str() : text.str()) << '\n';
}

// Prints the reply to `request` (and saves a snap); an error when the reply
// lacks the part the request asks for (a server speaking another protocol
// version) or the snap cannot be saved.
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
      return saveSnap(request.snap().camera(), reply.snap(), options.command[kSnapFileArg], as_json,
                      out);
    default:
      printSetConfirmation(request, as_json, out);
      return {};
  }
}

std::string errorCodeName(int code) {
  if (proto::Error::Code_IsValid(code)) {
    return proto::Error::Code_Name(static_cast<proto::Error::Code>(code));
  }
  return "UNKNOWN";
}

// Recognizes `name` as `--name VALUE` or `--name=VALUE` at args[i]; advances i
// past the value. nullopt when args[i] is another option.
std::optional<Result<std::string>> optionValue(const std::vector<std::string>& args, size_t& i,
                                               const std::string& name) {
  const std::string& arg = args[i];
  if (arg == name) {
    if (i + 1 >= args.size()) return Result<std::string>(usageError(name + ": missing value"));
    return Result<std::string>(args[++i]);
  }
  if (arg.rfind(name + "=", 0) == 0) return Result<std::string>(arg.substr(name.size() + 1));
  return std::nullopt;
}

}  // namespace

// ------------------------------------------------------------------- JSON

std::string escapeJson(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\f':
        out += "\\f";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out;
}

void JsonWriter::separate() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!has_element_.empty()) {
    if (has_element_.back()) text_ += ',';
    has_element_.back() = true;
  }
}

JsonWriter& JsonWriter::beginObject() {
  separate();
  text_ += '{';
  has_element_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endObject() {
  text_ += '}';
  has_element_.pop_back();
  return *this;
}

JsonWriter& JsonWriter::beginArray() {
  separate();
  text_ += '[';
  has_element_.push_back(false);
  return *this;
}

JsonWriter& JsonWriter::endArray() {
  text_ += ']';
  has_element_.pop_back();
  return *this;
}

JsonWriter& JsonWriter::key(std::string_view name) {
  separate();
  text_ += '"' + escapeJson(name) + "\":";
  after_key_ = true;
  return *this;
}

JsonWriter& JsonWriter::string(std::string_view value) {
  separate();
  text_ += '"' + escapeJson(value) + '"';
  return *this;
}

JsonWriter& JsonWriter::uinteger(std::uint64_t value) {
  separate();
  text_ += std::to_string(value);
  return *this;
}

JsonWriter& JsonWriter::real(double value) {
  separate();
  text_ += std::isfinite(value) ? formatShortest(value) : "null";
  return *this;
}

JsonWriter& JsonWriter::boolean(bool value) {
  separate();
  text_ += value ? "true" : "false";
  return *this;
}

// ------------------------------------------------------------------- public

std::string usageText() {
  return std::string("usage: ") + kProgram +
         " [--control ENDPOINT] [--timeout MS] [--json] COMMAND [ARGS]\n"
         "\n"
         "Configures the cameras of a running picksight-video-server through its\n"
         "control socket.\n"
         "\n"
         "commands:\n"
         "  list                            cameras, their sources, states and modes\n"
         "  info CAM                        vendor, model, sensor, ROI, output size, format\n"
         "  roi CAM X Y W H                 crop to a sensor region (W H 0 0 = full sensor)\n"
         "  size CAM W H                    resize the ROI to W x H pixels (0 0 = ROI size)\n"
         "  size CAM --scale S              resize the ROI by the factor S\n"
         "  mode CAM freerun|trigger [FPS]  acquisition mode, and frame rate\n"
         "  format CAM mono8|bgr8           output pixel format\n"
         "  trigger CAM                     acquire one frame; prints its sequence number\n"
         "  stats [CAM]                     frames, drops, errors, reconnects, fps\n"
         "  features CAM                    the camera's features: types, values, ranges\n"
         "  get CAM FEATURE                 a feature's current value\n"
         "  set CAM FEATURE VALUE           set a feature; prints the value the camera took\n"
         "  open CAM                        open the stream (takes the device)\n"
         "  close CAM                       close the stream and release the device\n"
         "  snap CAM FILE                   save the next frame; the extension of FILE\n"
         "                                  names the format (.png, .jpg, .tiff, ...)\n"
         "\n"
         "options:\n"
         "  --control ENDPOINT  the server's control socket (default " +
         kDefaultEndpoint +
         ")\n"
         "  --timeout MS        how long to wait for an answer (default " +
         std::to_string(kDefaultTimeout.count()) +
         ";\n"
         "                      snap waits at least " +
         std::to_string(kSnapMinTimeout.count()) +
         ")\n"
         "  --json              print one JSON object on stdout, for scripts\n"
         "  -h, --help          print this help\n"
         "\n"
         "Errors go to stderr. Exit codes: 0 ok, 1 server or camera error,\n"
         "2 usage error, 3 the server did not answer in time.\n";
}

Result<CamOptions> parseOptions(const std::vector<std::string>& args) {
  CamOptions options;
  bool options_ended = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    // Options are accepted after the command too ("list --json"), which is
    // how people type; "--" lets a camera name start with a dash. "-5" is a
    // word, so that "roi" can say why a negative X is wrong.
    if (options_ended || arg.size() < 2 || arg[0] != '-' ||
        (arg[1] != '-' && !std::isalpha(static_cast<unsigned char>(arg[1])))) {
      options.command.push_back(arg);
      continue;
    }
    if (arg == "--") {
      options_ended = true;
    } else if (arg == "--help" || arg == "-h") {
      options.help = true;
    } else if (arg == "--json") {
      options.json = true;
    } else if (arg == "--scale") {
      options.command.push_back(arg);  // belongs to "size"
    } else if (auto endpoint = optionValue(args, i, "--control")) {
      if (!*endpoint) return endpoint->error();
      if (endpoint->value().empty()) return usageError("--control: ENDPOINT must not be empty");
      options.endpoint = endpoint->value();
    } else if (auto timeout = optionValue(args, i, "--timeout")) {
      if (!*timeout) return timeout->error();
      const std::optional<long long> ms = parseInt(timeout->value());
      if (!ms || *ms <= 0 || *ms > std::numeric_limits<int>::max()) {
        return usageError("--timeout: MS must be a positive integer, got '" + timeout->value() +
                          "'");
      }
      options.timeout = std::chrono::milliseconds(*ms);
    } else {
      return usageError("unknown option '" + arg + "'");
    }
  }
  return options;
}

Result<proto::ControlRequest> buildRequest(const std::vector<std::string>& command) {
  if (command.empty()) return usageError("missing command");
  const std::string& name = command[0];
  proto::ControlRequest request;
  if (name == "list") {
    if (auto ok = checkCount(command, 0, 0, "list"); !ok) return ok.error();
    request.mutable_list_cameras();
  } else if (const CameraCommand* camera_command = findCameraCommand(name)) {
    auto camera = cameraOf(command, 1, 1, camera_command->synopsis);
    if (!camera) return camera.error();
    camera_command->fill(request, *camera);
  } else if (name == "roi") {
    return buildRoi(command);
  } else if (name == "size") {
    return buildSize(command);
  } else if (name == "mode") {
    return buildMode(command);
  } else if (name == "format") {
    return buildFormat(command);
  } else if (name == "get" || name == "set") {
    return buildFeature(command);
  } else if (name == "snap") {
    return buildSnap(command);
  } else if (name == "stats") {
    if (auto ok = checkCount(command, 0, 1, "stats [CAM]"); !ok) return ok.error();
    auto* stats = request.mutable_statistics();
    if (command.size() == 2) {
      auto camera = parseCamera(name, command[1]);
      if (!camera) return camera.error();
      stats->set_camera(*camera);
    }
  } else {
    return usageError("unknown command '" + name + "'");
  }
  return request;
}

int runCamCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              zmq::context_t& ctx) {
  const std::string hint = std::string("run '") + kProgram + " --help' for usage\n";
  auto options = parseOptions(args);
  if (!options) {
    err << kProgram << ": " << options.error().message << '\n' << hint;
    return kExitUsage;
  }
  if (options->help) {
    out << usageText();
    return kExitOk;
  }
  auto request = buildRequest(options->command);
  if (!request) {
    err << kProgram << ": " << request.error().message << '\n' << hint;
    return kExitUsage;
  }
  const std::string& command = options->command[0];
  const std::chrono::milliseconds timeout =
      request->has_snap() ? std::max(options->timeout, kSnapMinTimeout) : options->timeout;

  std::optional<ControlClient> client;
  try {
    client.emplace(ctx, options->endpoint, timeout);
  } catch (const zmq::error_t& e) {
    // connect() rejects malformed endpoints: the user's typo, not the server.
    err << kProgram << ": invalid endpoint '" << options->endpoint << "': " << e.what() << '\n';
    return kExitUsage;
  }

  std::optional<Result<proto::ControlReply>> reply;
  try {
    reply.emplace(client->call(*request));
  } catch (const zmq::error_t& e) {
    err << kProgram << ": " << command << ": " << e.what() << '\n';
    return kExitServerError;
  }
  if (!*reply) {
    const Error& error = reply->error();
    if (error.code == ControlErrc::kNoReply) {
      err << kProgram << ": no answer from " << options->endpoint << " within " << timeout.count()
          << " ms: is picksight-video-server running?\n";
      return kExitTimeout;
    }
    err << kProgram << ": " << command << ": " << error.message << " (server error "
        << errorCodeName(error.code.value()) << ", code " << error.code.value() << ")\n";
    return kExitServerError;
  }

  std::ostringstream text;  // nothing on `out` unless the whole reply printed
  if (auto printed = printReply(*request, reply->value(), *options, text); !printed) {
    err << kProgram << ": " << command << ": " << printed.error().message;
    if (printed.error().code == CliErrc::kBadReply) err << " from " << options->endpoint;
    err << '\n';
    return kExitServerError;
  }
  out << text.str();
  return kExitOk;
}

}  // namespace picksight::cam
