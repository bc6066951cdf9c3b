// Aravis camera source: open, describe, acquire and hand buffers over.
#include "aravis_source.hpp"

#include <algorithm>
#include <set>
#include <thread>

#include "genicam_features.hpp"
#include "gige_tuning.hpp"
#include "picksight/common/log.hpp"

namespace picksight::video {
namespace {
// Enough buffers that the stream thread always has a free one while we hold
// one and the camera sends a burst.
constexpr int kBufferCount = 8;
// Loopback and GigE bursts overflow the kernel's default socket buffer (frames
// then arrive with missing packets), and Aravis's "auto" size (= one payload)
// is too small for small ROIs: a few packets overflow it. Two payloads, never
// less than 1 MiB; the kernel caps it at net.core.rmem_max.
constexpr gint kMinSocketBuffer = 1 << 20;
constexpr guint kFrameRetentionUs = 500000;
// A free-running camera silent for this long gets a control read.
constexpr std::chrono::seconds kLivenessCheck{2};
// A software trigger whose frame has not come for this long is taken as lost
// and sent again.
constexpr std::chrono::seconds kTriggerRetry{3};

// Features that change the payload or its layout: most devices refuse them
// while acquiring (TLParamsLocked), and the buffer pool must follow them.
const std::set<std::string>& streamFeatures() {
  static const std::set<std::string> kNames = {"Width",
                                               "Height",
                                               "OffsetX",
                                               "OffsetY",
                                               "BinningHorizontal",
                                               "BinningVertical",
                                               "DecimationHorizontal",
                                               "DecimationVertical",
                                               "PixelFormat",
                                               "RegionSelector",
                                               "RegionMode"};
  return kNames;
}

struct LayoutInfo {
  PixelLayout layout;
  int cv_type;
  int bits_per_pixel;  // on the wire; packed rows are width * bits / 8 bytes
};

// GenICam PFNC ids Aravis 0.8 has no names for.
constexpr ArvPixelFormat kMono10p = 0x010A0046u;
constexpr ArvPixelFormat kMono12p = 0x010C0047u;

// Aravis (PFNC) pixel format ids to our layouts; nullopt for formats the
// converter does not take (RGB 10/12, YUV 4:1:1, packed Bayer...).
std::optional<LayoutInfo> layoutOf(ArvPixelFormat format) {
  static const std::pair<ArvPixelFormat, LayoutInfo> kLayouts[] = {
      {ARV_PIXEL_FORMAT_MONO_8, {PixelLayout::kMono8, CV_8UC1, 8}},
      {ARV_PIXEL_FORMAT_MONO_10, {PixelLayout::kMono10, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_MONO_12, {PixelLayout::kMono12, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_MONO_16, {PixelLayout::kMono16, CV_16UC1, 16}},
      {kMono10p, {PixelLayout::kMono10p, CV_8UC1, 10}},
      {kMono12p, {PixelLayout::kMono12p, CV_8UC1, 12}},
      {ARV_PIXEL_FORMAT_MONO_10_PACKED, {PixelLayout::kMono10Packed, CV_8UC1, 12}},
      {ARV_PIXEL_FORMAT_MONO_12_PACKED, {PixelLayout::kMono12Packed, CV_8UC1, 12}},
      {ARV_PIXEL_FORMAT_BAYER_RG_8, {PixelLayout::kBayerRG8, CV_8UC1, 8}},
      {ARV_PIXEL_FORMAT_BAYER_GR_8, {PixelLayout::kBayerGR8, CV_8UC1, 8}},
      {ARV_PIXEL_FORMAT_BAYER_BG_8, {PixelLayout::kBayerBG8, CV_8UC1, 8}},
      {ARV_PIXEL_FORMAT_BAYER_GB_8, {PixelLayout::kBayerGB8, CV_8UC1, 8}},
      {ARV_PIXEL_FORMAT_BAYER_RG_10, {PixelLayout::kBayerRG10, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GR_10, {PixelLayout::kBayerGR10, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_BG_10, {PixelLayout::kBayerBG10, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GB_10, {PixelLayout::kBayerGB10, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_RG_12, {PixelLayout::kBayerRG12, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GR_12, {PixelLayout::kBayerGR12, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_BG_12, {PixelLayout::kBayerBG12, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GB_12, {PixelLayout::kBayerGB12, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_RG_16, {PixelLayout::kBayerRG16, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GR_16, {PixelLayout::kBayerGR16, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_BG_16, {PixelLayout::kBayerBG16, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_BAYER_GB_16, {PixelLayout::kBayerGB16, CV_16UC1, 16}},
      {ARV_PIXEL_FORMAT_RGB_8_PACKED, {PixelLayout::kRGB8, CV_8UC3, 24}},
      {ARV_PIXEL_FORMAT_BGR_8_PACKED, {PixelLayout::kBGR8, CV_8UC3, 24}},
      {ARV_PIXEL_FORMAT_YUV_422_YUYV_PACKED, {PixelLayout::kYUYV, CV_8UC2, 16}},
      {ARV_PIXEL_FORMAT_YUV_422_PACKED, {PixelLayout::kUYVY, CV_8UC2, 16}},
  };
  for (const auto& [id, info] : kLayouts) {
    if (id == format) return info;
  }
  return std::nullopt;
}

const char* statusName(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "timed out before all packets arrived";
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "larger than the buffer";
    case ARV_BUFFER_STATUS_ABORTED:
      return "aborted";
    default:
      return "not completed";
  }
}

std::string orEmpty(const char* text) { return text != nullptr ? text : ""; }

// Runs on Aravis's heartbeat thread: only flags, never throws.
void onControlLost(ArvDevice* /*device*/, gpointer data) noexcept {
  (*static_cast<std::shared_ptr<std::atomic<bool>>*>(data))->store(true);
}

void freeFlag(gpointer data, GClosure* /*closure*/) noexcept {
  delete static_cast<std::shared_ptr<std::atomic<bool>>*>(data);
}

// Aravis opens a device by its id ("<vendor>-<model>-<serial>" for GigE),
// its physical id (MAC), its address, or (USB3 Vision) its GUID, but not by a
// bare serial number, which is what the label on a camera says: the id of
// the device with that serial, if one is listed.
std::optional<std::string> deviceIdOfSerial(const std::string& serial) {
  arv_update_device_list();
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    if (orEmpty(arv_get_device_serial_nbr(i)) == serial) return orEmpty(arv_get_device_id(i));
  }
  return std::nullopt;
}
}  // namespace

AravisSource::AravisSource(std::string device_id) : device_id_(std::move(device_id)) {}

AravisSource::~AravisSource() { close(); }

Error AravisSource::lost(const std::string& why) const {
  return makeError(SourceErrc::kUnavailable, label() + ": " + why);
}

Result<void> AravisSource::open() {
  close();
  GErrorSlot error;
  camera_.reset(arv_camera_new(device_id_.empty() ? nullptr : device_id_.c_str(), error.out()));
  if (!camera_ && !device_id_.empty()) {
    if (const auto id = deviceIdOfSerial(device_id_)) {
      error.clear();
      camera_.reset(arv_camera_new(id->c_str(), error.out()));
    }
  }
  if (!camera_) {
    const std::string why = error ? error.message() : std::string("no such device");
    return lost(device_id_.empty() ? "no camera found: " + why : "cannot open: " + why);
  }
  ArvDevice* device = arv_camera_get_device(camera_.get());
  control_lost_ = std::make_shared<std::atomic<bool>>(false);
  control_lost_handler_ = g_signal_connect_data(
      device, "control-lost", G_CALLBACK(onControlLost),
      new std::shared_ptr<std::atomic<bool>>(control_lost_), freeFlag, GConnectFlags(0));
  if (arv_camera_is_gv_device(camera_.get())) {
    // Packet sockets need CAP_NET_RAW and see nothing on loopback.
    const ArvGvStreamOption option = gigeStreamOption(ARV_GV_DEVICE(device));
    arv_gv_device_set_stream_options(ARV_GV_DEVICE(device), option);
    if (option == ARV_GV_STREAM_OPTION_NONE) logInfo(label(), ": stream on packet sockets");
  }

  SourceInfo i;
  i.vendor = orEmpty(arv_camera_get_vendor_name(camera_.get(), error.out()));
  i.model = orEmpty(arv_camera_get_model_name(camera_.get(), error.out()));
  i.serial = orEmpty(arv_camera_get_device_serial_number(camera_.get(), error.out()));
  if (i.serial.empty()) i.serial = orEmpty(arv_camera_get_device_id(camera_.get(), error.out()));
  gint width = 0;
  gint height = 0;
  arv_camera_get_sensor_size(camera_.get(), &width, &height, error.out());
  if (error) return lost("cannot read the sensor size: " + error.message());
  i.sensor_width = width;
  i.sensor_height = height;
  guint n = 0;
  GArrayPtr<const char*> formats(
      arv_camera_dup_available_pixel_formats_as_strings(camera_.get(), &n, error.out()));
  for (guint k = 0; formats && k < n; ++k) i.formats.emplace_back(orEmpty(formats.get()[k]));
  info_ = std::move(i);
  last_alive_ = Clock::now();
  return {};
}

void AravisSource::close() {
  stopAcquisition();
  held_.reset();
  retireStream();  // frees the buffers still queued in it
  buffer_size_ = 0;
  mode_.reset();
  configure_error_.reset();
  if (camera_ && control_lost_handler_ != 0) {
    g_signal_handler_disconnect(arv_camera_get_device(camera_.get()), control_lost_handler_);
  }
  control_lost_handler_ = 0;
  camera_.reset();
  control_lost_.reset();
}

Result<void> AravisSource::createStream() {
  held_.reset();
  retireStream();
  GErrorSlot error;
  const guint payload = arv_camera_get_payload(camera_.get(), error.out());
  if (error) return lost("cannot read the payload size: " + error.message());
  stream_priority_ = 0;
  stream_.reset(
      arv_camera_create_stream(camera_.get(), onStreamEvent, &stream_priority_, error.out()));
  if (!stream_) return lost("cannot open the stream: " + error.message());
  if (ARV_IS_GV_STREAM(stream_.get())) {
    const gint socket_buffer = static_cast<gint>(
        std::min<guint>(std::max<guint>(2 * payload, kMinSocketBuffer), 1u << 30));
    // Aravis asks for it and the kernel silently grants at most rmem_max.
    const auto granted = grantedSocketBuffer(static_cast<size_t>(socket_buffer));
    const std::string capped =
        granted ? socketBufferWarning(static_cast<size_t>(socket_buffer), *granted) : "";
    if (!capped.empty() && !socket_buffer_warned_) logWarning(label(), ": ", capped);
    socket_buffer_warned_ = socket_buffer_warned_ || !capped.empty();
    // A loaded host can leave the stream thread unscheduled for longer than
    // the default 100 ms retention, and complete frames are then dropped.
    g_object_set(stream_.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                 "socket-buffer-size", socket_buffer, "frame-retention", kFrameRetentionUs,
                 nullptr);
  }
  for (int k = 0; k < kBufferCount; ++k) {
    // The stream takes over the reference.
    arv_stream_push_buffer(stream_.get(), arv_buffer_new_allocate(payload));
  }
  buffer_size_ = payload;
  return {};
}

Result<void> AravisSource::startAcquisition() {
  GErrorSlot error;
  if (stream_) {
    // Width, height or format may have changed since the pool was made.
    const guint payload = arv_camera_get_payload(camera_.get(), error.out());
    if (error) return lost("cannot read the payload size: " + error.message());
    if (payload != buffer_size_) retireStream();
  }
  if (!stream_) {
    if (auto made = createStream(); !made) return made;
  }
  arv_camera_set_acquisition_mode(camera_.get(), ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
  if (error) return lost("cannot set continuous acquisition: " + error.message());
  arv_camera_start_acquisition(camera_.get(), error.out());
  if (error) return lost("cannot start acquisition: " + error.message());
  acquiring_ = true;
  last_alive_ = Clock::now();
  return {};
}

void AravisSource::stopAcquisition() {
  if (!acquiring_ || !camera_) return;
  acquiring_ = false;
  GErrorSlot error;
  arv_camera_stop_acquisition(camera_.get(),
                              error.out());  // a lost device cannot stop: nothing to do
  returnHeldBuffer();
  // Frames taken before the stop (free-run frames before a switch to
  // trigger) must not be handed out afterwards.
  if (stream_) {
    while (ArvBuffer* stale = arv_stream_try_pop_buffer(stream_.get())) {
      arv_stream_push_buffer(stream_.get(), stale);
    }
  }
  triggers_in_flight_ = 0;
}

void AravisSource::takeNewest(GObjectPtr<ArvBuffer>& buffer) {
  // Buffers queue first in, first out: under load the one popped may be
  // several periods old while newer complete ones wait behind it. In
  // free-run only the newest matters (a request wants a frame taken after
  // it); the older go back to the stream. Triggered frames are each owed to
  // a request or a pulse, and are never passed over.
  while (ArvBuffer* newer = arv_stream_try_pop_buffer(stream_.get())) {
    if (arv_buffer_get_status(newer) != ARV_BUFFER_STATUS_SUCCESS) {
      arv_stream_push_buffer(stream_.get(), newer);  // Aravis counted it already
      continue;
    }
    arv_stream_push_buffer(stream_.get(), buffer.release());
    buffer.reset(newer);
    ++skipped_stale_;
  }
}

DriverCounters AravisSource::driverCounters() const {
  DriverCounters sum = retired_;
  sum.skipped_stale = skipped_stale_;
  if (!stream_) return sum;
  guint64 completed = 0;
  guint64 failures = 0;
  guint64 underruns = 0;
  arv_stream_get_statistics(stream_.get(), &completed, &failures, &underruns);
  sum.incomplete_buffers += failures;
  sum.underruns += underruns;
  if (ARV_IS_GV_STREAM(stream_.get())) {
    guint64 resent = 0;
    guint64 missing = 0;
    arv_gv_stream_get_statistics(ARV_GV_STREAM(stream_.get()), &resent, &missing);
    sum.resent_packets += resent;
    sum.missing_packets += missing;
  }
  return sum;
}

void AravisSource::retireStream() {
  // The stream's counters die with it: the totals keep them.
  retired_ = driverCounters();
  stream_.reset();
}

void AravisSource::returnHeldBuffer() {
  if (held_ && stream_) arv_stream_push_buffer(stream_.get(), held_.release());
  held_.reset();
}

Result<void> AravisSource::checkDevice() {
  GErrorSlot error;
  // PayloadSize is computed from live registers: a real read on every call.
  arv_camera_get_payload(camera_.get(), error.out());
  if (error) return lost("the camera does not answer: " + error.message());
  return {};
}

Result<void> AravisSource::configureAcquisition(const AcquisitionRequest& request) {
  if (!camera_) return lost("not open");
  stopAcquisition();
  mode_.reset();
  configure_error_ = configureTriggerAndRate(request);
  if (configure_error_) return *configure_error_;
  mode_ = request.mode;
  return startAcquisition();
}

std::optional<Error> AravisSource::configureTriggerAndRate(const AcquisitionRequest& request) {
  GErrorSlot error;
  const double fps = request.fps;
  if (request.mode == AcquisitionMode::kFreeRun) {
    // Free-run by default leaves the trigger alone: a camera configured for
    // a hardware trigger (TriggerMode On, TriggerSource Line1) keeps it.
    if (request.mode_asked) {
      // Sets TriggerMode Off under every TriggerSelector.
      arv_camera_clear_triggers(camera_.get(), error.out());
      if (error)
        return makeError(SourceErrc::kNotSupported,
                         label() + ": free-run: cannot set TriggerMode to Off: " + error.message());
    }
    const bool has_rate =
        request.fps_asked && arv_camera_is_frame_rate_available(camera_.get(), error.out());
    if (has_rate && fps > 0) {
      double lo = 0;
      double hi = 0;
      arv_camera_get_frame_rate_bounds(camera_.get(), &lo, &hi, error.out());
      const double rate = !error && hi > lo ? std::clamp(fps, lo, hi) : fps;
      arv_camera_set_frame_rate(camera_.get(), rate, error.out());
      // A camera whose rate is fixed still streams: not worth failing over.
      error.clear();
    }
  } else if (request.mode == AcquisitionMode::kHardwareTrigger) {
    return configureHardwareTrigger(request.input);
  } else {
    if (!arv_camera_is_software_trigger_supported(camera_.get(), error.out())) {
      return makeError(SourceErrc::kNotSupported, label() + ": the camera has no software trigger");
    }
    // TriggerSelector FrameStart, TriggerMode On, TriggerSource Software.
    arv_camera_set_trigger(camera_.get(), "Software", error.out());
    if (error)
      return makeError(SourceErrc::kNotSupported,
                       label() +
                           ": trigger: cannot set TriggerMode On with TriggerSource "
                           "Software: " +
                           error.message());
  }
  return std::nullopt;
}

std::optional<Error> AravisSource::configureHardwareTrigger(const TriggerInput& input) {
  // Feature by feature, so that a failure names the one the camera refused
  // (and its choices); the selector first, as the others are indexed by it.
  // TriggerMode last: the camera waits for the line only once it is wired.
  GenicamFeatures features(arv_camera_get_device(camera_.get()));
  std::vector<std::pair<std::string, std::string>> writes = {{"TriggerSelector", "FrameStart"},
                                                             {"TriggerSource", input.line}};
  if (!input.activation.empty()) writes.emplace_back("TriggerActivation", input.activation);
  writes.emplace_back("TriggerMode", "On");
  for (const auto& [name, value] : writes) {
    if (auto set = features.set(name, value); !set) {
      return makeError(SourceErrc::kNotSupported, label() + ": hardware trigger: cannot set " +
                                                      name + " to " + value + ": " +
                                                      set.error().message);
    }
  }
  return std::nullopt;
}

Result<void> AravisSource::softwareTrigger() {
  if (!camera_) return lost("not open");
  if (control_lost_ && control_lost_->load()) return lost("control lost");
  if (!acquiring_) {
    if (auto started = startAcquisition(); !started) return started;
  }
  const auto now = Clock::now();
  if (triggers_in_flight_ > 0 && now - last_trigger_ < kTriggerRetry) return {};
  GErrorSlot error;
  arv_camera_software_trigger(camera_.get(), error.out());
  if (error) {
    if (auto alive = checkDevice(); !alive) return alive;
    return makeError(SourceErrc::kNotSupported,
                     label() + ": software trigger failed: " + error.message());
  }
  triggers_in_flight_ = 1;
  last_trigger_ = now;
  return {};
}

Result<SourceFrame> AravisSource::grab(std::chrono::milliseconds timeout) {
  if (!camera_) return lost("not open");
  // The Camera has converted or copied the previous frame by now.
  returnHeldBuffer();
  if (control_lost_->load())
    return lost("control lost (the camera stopped answering its heartbeat)");
  if (configure_error_) {
    // The mode asked for could not be set: no frames, as from a silent
    // camera, so the camera reports it (with this reason) and reopens at
    // its pace rather than at the loop's.
    std::this_thread::sleep_for(timeout);
    return *configure_error_;
  }
  if (!acquiring_) {
    if (!mode_) {
      // Nothing asked: the device streams as it is configured.
      if (auto configured = configureAcquisition(AcquisitionRequest{}); !configured) {
        return configured.error();
      }
    } else if (auto started = startAcquisition(); !started) {
      return started.error();
    }
  }

  auto buffer = nextBuffer(timeout);
  if (!buffer) return buffer.error();
  return frameFrom(std::move(*buffer));
}

Result<GObjectPtr<ArvBuffer>> AravisSource::nextBuffer(std::chrono::milliseconds timeout) {
  GObjectPtr<ArvBuffer> buffer(arv_stream_timeout_pop_buffer(
      stream_.get(), static_cast<guint64>(std::max<int64_t>(0, timeout.count())) * 1000));
  if (!buffer) {
    // Waiting for a trigger that was never sent is not a sign of loss; a
    // camera waiting for a pulse on its line is still asked, so that one
    // unplugged meanwhile is found.
    const bool expecting = mode_ != AcquisitionMode::kTrigger || triggers_in_flight_ > 0;
    if (expecting && Clock::now() - last_alive_ > kLivenessCheck) {
      if (auto alive = checkDevice(); !alive) return alive.error();
      last_alive_ = Clock::now();
    }
    return makeError(SourceErrc::kTimeout,
                     label() + ": no frame within " + std::to_string(timeout.count()) + " ms");
  }
  last_alive_ = Clock::now();
  triggers_in_flight_ = 0;
  if (mode_ == AcquisitionMode::kFreeRun) takeNewest(buffer);
  if (!priority_logged_ && stream_priority_.load() != 0) {
    priority_logged_ = true;
    logInfo(label(), stream_priority_.load() > 0
                         ? ": stream thread runs real-time (SCHED_FIFO)"
                         : ": stream thread at normal priority (real time needs CAP_SYS_NICE "
                           "or LimitRTPRIO; see docs/CAMERAS.md)");
  }
  return buffer;
}

Result<SourceFrame> AravisSource::frameFrom(GObjectPtr<ArvBuffer> buffer) {
  const ArvBufferStatus status = arv_buffer_get_status(buffer.get());
  if (status != ARV_BUFFER_STATUS_SUCCESS) {
    const uint64_t id = arv_buffer_get_frame_id(buffer.get());
    arv_stream_push_buffer(stream_.get(), buffer.release());
    return makeError(SourceErrc::kBadValue, label() + ": frame " + std::to_string(id) +
                                                " incomplete: " + statusName(status));
  }
  const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer.get());
  const auto layout = layoutOf(format);
  if (!layout) {
    arv_stream_push_buffer(stream_.get(), buffer.release());
    char hex[16];
    g_snprintf(hex, sizeof hex, "0x%08x", static_cast<unsigned>(format));
    return makeError(SourceErrc::kNotSupported,
                     label() + ": pixel format " + hex +
                         " is not supported (set PixelFormat to Mono8/10/12/16, Mono10p/12p, "
                         "Mono10Packed/12Packed, Bayer**8/10/12/16, RGB8, BGR8, YUV422)");
  }
  const int width = arv_buffer_get_image_width(buffer.get());
  const int height = arv_buffer_get_image_height(buffer.get());
  gint x_padding = 0;
  gint y_padding = 0;
  arv_buffer_get_image_padding(buffer.get(), &x_padding, &y_padding);
  size_t size = 0;
  const void* data = arv_buffer_get_image_data(buffer.get(), &size);
  const size_t row_bits = static_cast<size_t>(std::max(0, width)) * layout->bits_per_pixel;
  if (row_bits % 8 != 0) {
    // Packed rows of this width end inside a byte: the converter takes
    // whole rows only (Width in steps of 4 for Mono10p, of 2 otherwise).
    arv_stream_push_buffer(stream_.get(), buffer.release());
    return makeError(SourceErrc::kNotSupported,
                     label() + ": a width of " + std::to_string(width) +
                         " splits packed pixels across rows: set Width to a multiple of 4");
  }
  const size_t row_bytes = row_bits / 8;
  const size_t stride = row_bytes + static_cast<size_t>(std::max(0, x_padding));
  if (data == nullptr || width <= 0 || height <= 0 ||
      size < stride * static_cast<size_t>(height - 1) + row_bytes) {
    arv_stream_push_buffer(stream_.get(), buffer.release());
    return makeError(SourceErrc::kBadValue, label() + ": frame smaller than its " +
                                                std::to_string(width) + "x" +
                                                std::to_string(height) + " header says");
  }

  SourceFrame frame;
  // Read-only view on the buffer's bytes, valid until the next grab(). Packed
  // layouts: rows of bytes, unpacked by the converter.
  const int cols = layout->cv_type == CV_8UC1 && layout->bits_per_pixel != 8
                       ? static_cast<int>(row_bytes)
                       : width;
  frame.image = cv::Mat(height, cols, layout->cv_type, const_cast<void*>(data), stride);
  frame.layout = layout->layout;
  frame.device_timestamp_ns = arv_buffer_get_timestamp(buffer.get());
  held_ = std::move(buffer);
  return frame;
}

std::vector<Feature> AravisSource::features() {
  if (!camera_) return {};
  return GenicamFeatures(arv_camera_get_device(camera_.get())).list();
}

std::vector<std::string> AravisSource::featureNames() {
  if (!camera_) return {};
  return GenicamFeatures(arv_camera_get_device(camera_.get())).names();
}

std::optional<Feature> AravisSource::listedFeature(const std::string& name) {
  if (!camera_ || control_lost_->load()) return std::nullopt;
  return GenicamFeatures(arv_camera_get_device(camera_.get())).listed(name);
}

Result<Feature> AravisSource::feature(const std::string& name) {
  if (!camera_) return lost("not open");
  if (control_lost_->load()) return lost("control lost");
  return GenicamFeatures(arv_camera_get_device(camera_.get())).get(name);
}

Result<void> AravisSource::setFeature(const std::string& name, const std::string& value) {
  if (!camera_) return lost("not open");
  if (control_lost_->load()) return lost("control lost");
  GenicamFeatures features(arv_camera_get_device(camera_.get()));
  const bool restart = acquiring_ && streamFeatures().count(name) > 0;
  if (restart) stopAcquisition();
  Result<void> set = features.set(name, value);
  if (restart) {
    // startAcquisition() remakes the pool if the payload size changed.
    if (auto started = startAcquisition(); !started) return started;
  }
  if (!set && set.error().code == SourceErrc::kBadValue) {
    if (auto alive = checkDevice(); !alive) return alive;
  }
  return set;
}

}  // namespace picksight::video
