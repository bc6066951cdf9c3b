// picksight-cam: the `snap` command's file writer. The frame is decoded from
// the proto FrameHeader as a subscriber decodes a published frame.
#include "snap_writer.hpp"
#include "cam_cli.hpp"

#include <cstdint>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/transport/frame_message.hpp"
#include "reply_printer.hpp"

namespace picksight::cam {

using transport::decodeFrame;
using transport::frameIsConsistent;

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
    written = picksight::codecs::imwrite(file, frame->image);
  } catch (const cv::Exception& e) {
    reason = e.err;  // what() adds OpenCV's source path and line
  } catch (const std::exception& e) {
    reason = e.what();  // the codecs module missing from the installation
  }
  if (!written) return makeError(CliErrc::kSaveFailed, "could not save '" + file + "': " + reason);

  if (as_json) {
    const Json json = {{"camera", camera},
                       {"file", file},
                       {"sequence", h.sequence()},
                       {"width", h.width()},
                       {"height", h.height()},
                       {"pixel_format", formatName(h.pixel_format())},
                       {"triggered", h.triggered()},
                       {"device_timestamp_ns", h.device_timestamp_ns()},
                       {"host_timestamp_ns", h.host_timestamp_ns()}};
    out << toJson(json) << '\n';
    return {};
  }
  out << "saved " << h.width() << 'x' << h.height() << ' ' << formatName(h.pixel_format())
      << " frame #" << h.sequence() << " to " << file << '\n';
  return {};
}

}  // namespace picksight::cam
