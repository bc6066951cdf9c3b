// What one vision request saw and answered, as the request thread hands it
// to the results publisher (and keeps it for the robot's WHY): the LOCATE
// outcome with its grasps, or the frame other requests worked on, the
// request and reply lines. The explanation of the regions left out (the
// rejections) is computed on first use, after the reply, never on the
// robot's critical path.
//
// Threading: filled by one thread, then shared read-only (shared_ptr);
// rejections() and why() may be called from any thread, computed once.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "picksight/cell/cell_locate.hpp"
#include "picksight/cell/grasp_planner.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::results {

// Why one region was not reported as a part of the asked type (see
// Rejection in proto/results.proto; sensor pixels).
struct RegionRejection {
  int region = -1;
  int nearest_type = -1;  // -1: no model at all
  std::string nearest_name;
  // "area", "holes", "hu", "verify", "scale", "mirror", "other type",
  // "no grasp", "edge", "no model", "passes" (passes every test and yet
  // was not reported).
  std::string test;
  double measured = 0;
  double low = 0;
  double high = 0;
  // The smallest change of one tolerance of the nearest model with which
  // LOCATE accepts the region, when one test alone refuses it
  // (vision::remedyFor): `TOLERANCE <nearest_type> <remedy_key>
  // <remedy_value>`; empty when there is none.
  std::string remedy_key;
  std::string remedy_value;  // as written, the text TOLERANCE reads
  std::string text;          // as WHY prints it, the remedy included
  // Plainly unlike every trained part (unlikeAnyPart): belt texture, a
  // shadow, dirt. WHY says these after the near misses, while its line has
  // room, and the web HMI draws them without a label, so the near misses
  // stand out.
  bool unlike_any_part = false;
};

// Whether a rejected region is plainly unlike every part of `models`
// (vision::unlikeEveryModel, frame pixels): it fails a test read before the
// part's boundary ("holes", "area", "hu", or "edge"; a scaled copy or a
// mirror image is the part's own shape), and no remedy accepts it.
bool unlikeAnyPart(const RegionRejection& r, const vision::Region& region,
                   const store::ModelList& models);

// Regions published (and explained) per request, largest first.
constexpr size_t kMaxResultRegions = 1024;
// Longest WHY line: the near misses that fit (then "; ..."), the regions
// unlike any part that fit, then the count of those left unsaid.
constexpr size_t kMaxWhyBytes = 1000;

class RequestRecord {
 public:
  std::string request;       // "LOCATE", "LEARN", "BLOBS", "STORE", "CALCAM"
  std::string request_line;  // as received
  std::string client;        // "robot 10.0.0.5:41234", "plc 10.0.0.9"
  std::string reply;         // set once the reply is known
  double elapsed_ms = 0;     // request to reply
  int asked_type = -1;       // LOCATE: -1 every type
  bool changed = false;      // a change answered OK (Session::changed)

  // LOCATE: its outcome and what the grasps were chosen with (none when
  // the request failed before a frame).
  std::optional<cell::LocateOutcome> locate;
  cell::CellPick pick;
  std::shared_ptr<const store::GraspMap> grasps;
  std::optional<store::CellGeometry> geometry;

  // Other requests: the frame they worked on (regions are found from it by
  // the publisher) and the settings to find them with.
  std::shared_ptr<const Frame> frame;
  cell::VisionOptions options;

  // The frame the request worked on, if any.
  std::optional<FrameInfo> frameInfo() const;
  // The frame of the reply's poses, as results (VisionResult.reply_frame)
  // and the filmstrip name it: "pixels", "vision_mm" or "robot_mm"; ""
  // for a request that replies no pose (no cell geometry with it).
  std::string replyFrame() const;
  // Every region of a LOCATE not reported as a part of the asked type, in
  // region order; empty for other requests.
  const std::vector<RegionRejection>& rejections() const;
  // The WHY line: "OK <n> <text>; <text>...[; <k> more regions unlike any
  // part]" (n rejections: the near misses' sentences in region order, then
  // those of the regions unlike any part, then the count of those left
  // unsaid), at most kMaxWhyBytes; empty for requests other than LOCATE.
  const std::string& why() const;

 private:
  void explain() const;

  mutable std::once_flag explained_;
  mutable std::vector<RegionRejection> rejections_;
  mutable std::string why_;
};

// Whether `name` is one of the names RequestRecord::replyFrame gives to a
// frame ("" is none of them).
bool isReplyFrameName(const std::string& name);

// A LOCATE's record (robot port or PLC trigger), the outcome moved in
// (`located` may be an error); the caller fills in the request line and
// the client, the reply and the time once they are known. Its settings are
// those the location ran with when it says (LocateOutcome::settings), else
// `options`.
std::shared_ptr<RequestRecord> locateRecord(Result<cell::CellLocate>&& located, int type,
                                            const cell::VisionOptions& options);

}  // namespace picksight::results
