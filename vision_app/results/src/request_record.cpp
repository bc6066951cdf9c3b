// Rejections and the WHY line of a LOCATE: every region no offered part
// came from, explained against the asked type's models (or as a part of
// another type, or one with no free grasp), with the tolerance change that
// would accept it where one test alone refuses it, and whether it is
// plainly unlike any part (which WHY says after the near misses).
#include "picksight/results/request_record.hpp"

#include <algorithm>
#include <set>

#include "picksight/common/text.hpp"
#include "picksight/vision/recognition/region_explanation.hpp"

namespace picksight::results {
using cell::CellLocate;
using cell::LocatedPart;
using cell::LocateScene;
using cell::ScreenedRegion;
using cell::VisionOptions;
using store::ModelList;
namespace {

std::string ofType(int type) { return " of type " + std::to_string(type); }

// The sentence WHY prints for a rejection (values in sensor pixels).
std::string rejectionText(const RegionRejection& r) {
  const std::string region = "region " + std::to_string(r.region);
  if (r.test == "area") {
    return region + " area " + formatFixed(r.measured, 0) + " outside " + formatFixed(r.low, 0) +
           ".." + formatFixed(r.high, 0) + ofType(r.nearest_type);
  }
  if (r.test == "holes") {
    return region + " holes " + formatFixed(r.measured, 0) + " not " + formatFixed(r.low, 0) +
           ofType(r.nearest_type);
  }
  if (r.test == "hu") {
    return region + " shape distance " + formatFixed(r.measured, 3) + " > " +
           formatFixed(r.high, 3) + ofType(r.nearest_type);
  }
  if (r.test == "scale") {
    // A copy of the part at another size: its size against the trained one.
    return region + " scaled " + formatFixed(r.measured, 2) + "x outside " + formatFixed(r.low, 2) +
           ".." + formatFixed(r.high, 2) + ofType(r.nearest_type);
  }
  if (r.test == "mirror") return region + " mirror" + ofType(r.nearest_type);
  if (r.test == "verify") {
    return region + " boundary " + formatFixed(r.measured, 1) + "% < " + formatFixed(r.high, 1) +
           "%" + ofType(r.nearest_type);
  }
  if (r.test == "other type") {
    return region + " is type " + std::to_string(r.nearest_type) + " not " +
           formatFixed(r.measured, 0);
  }
  if (r.test == "no grasp") return region + " no free grasp" + ofType(r.nearest_type);
  if (r.test == "edge") return region + " touches the frame border";
  if (r.test == "no model") return region + " no model";
  return region + " passes every test" + ofType(r.nearest_type) + " yet not reported";
}

// The remedy's clause after a rejection's sentence: "<key> <value> would
// accept it" (the change of the nearest type's model, see remedyFor).
std::string remedyText(const RegionRejection& r) {
  if (r.remedy_key.empty()) return "";
  return ", " + r.remedy_key + " " + r.remedy_value + " would accept it";
}

std::vector<const vision::PartModel*> modelsOf(const ModelList& models, int type) {
  std::vector<const vision::PartModel*> list;
  for (const auto& m : models)
    if (type < 0 || m.type == type) list.push_back(&m);
  return list;
}

// WHY's clause counting the regions unlike any part it left unsaid
// (`more`: after some that it said).
std::string unlikeSummary(size_t count, bool more) {
  return std::to_string(count) + (more ? " more" : "") + (count == 1 ? " region" : " regions") +
         " unlike any part";
}

}  // namespace

bool unlikeAnyPart(const RegionRejection& r, const vision::Region& region,
                   const ModelList& models) {
  // The tests read before the part's boundary, by the names the rejection
  // holds (vision::regionTestName's).
  using vision::RegionTest;
  const auto named = [&](RegionTest t) { return r.test == vision::regionTestName(t); };
  if (!named(RegionTest::kHoles) && !named(RegionTest::kArea) && !named(RegionTest::kHu) &&
      !named(RegionTest::kEdge)) {
    return false;
  }
  return r.remedy_key.empty() && vision::unlikeEveryModel(region, modelsOf(models, -1));
}

namespace {
const char* replyFrameName(store::CoordinateFrame frame) {
  switch (frame) {
    case store::CoordinateFrame::kVisionPixels:
      return "pixels";
    case store::CoordinateFrame::kVisionMm:
      return "vision_mm";
    case store::CoordinateFrame::kRobot:
      return "robot_mm";
  }
  return "";
}
}  // namespace

std::string RequestRecord::replyFrame() const {
  return geometry ? replyFrameName(geometry->frame()) : "";
}

bool isReplyFrameName(const std::string& name) {
  for (const auto frame : {store::CoordinateFrame::kVisionPixels, store::CoordinateFrame::kVisionMm,
                           store::CoordinateFrame::kRobot}) {
    if (name == replyFrameName(frame)) return true;
  }
  return false;
}

std::optional<FrameInfo> RequestRecord::frameInfo() const {
  if (locate) return locate->frame;
  if (frame) return frame->info;
  return std::nullopt;
}

const std::vector<RegionRejection>& RequestRecord::rejections() const {
  std::call_once(explained_, [this] { explain(); });
  return rejections_;
}

const std::string& RequestRecord::why() const {
  std::call_once(explained_, [this] { explain(); });
  return why_;
}

void RequestRecord::explain() const {
  if (request != "LOCATE") return;
  if (!locate) {
    why_ = "OK 0 LOCATE failed: " + reply;
    return;
  }
  const LocateScene& scene = locate->scene;
  const ModelList empty;
  const ModelList& models = scene.models ? *scene.models : empty;
  std::set<int> offered;
  for (size_t part : pick.parts) offered.insert(locate->parts[part].region);
  const auto all = modelsOf(models, -1);
  for (size_t i = 0; i < std::min(scene.regions.size(), kMaxResultRegions); ++i) {
    const int index = static_cast<int>(i);
    if (offered.count(index)) continue;
    RegionRejection r;
    r.region = index;
    const auto located = std::find_if(locate->parts.begin(), locate->parts.end(),
                                      [&](const LocatedPart& p) { return p.region == index; });
    const auto screened = std::find_if(scene.screened_out.begin(), scene.screened_out.end(),
                                       [&](const ScreenedRegion& s) { return s.region == index; });
    if (located != locate->parts.end()) {
      r.test = "no grasp";
      r.nearest_type = located->type;
    } else if (screened != scene.screened_out.end()) {
      // Passed the asked type's tests, but the screen across types found
      // it clearly closer to another type.
      r.test = "other type";
      r.nearest_type = screened->closer_type;
      r.measured = r.low = r.high = asked_type;
    } else if (all.empty()) {
      r.test = "no model";
    } else {
      const auto e = vision::explainRegionAsAsked(scene.regions[i], all, asked_type);
      if (e.other_type) {
        r.test = "other type";
        r.nearest_type = e.nearest->type;
        r.nearest_name = e.nearest->name;
        r.measured = r.low = r.high = asked_type;
      } else {
        r.test = vision::regionTestName(e.test);
        r.nearest_type = e.nearest ? e.nearest->type : -1;
        r.nearest_name = e.nearest ? e.nearest->name : "";
        r.measured = e.measured;
        r.low = e.low;
        r.high = e.high;
        if (const auto remedy = vision::remedyFor(scene.regions[i], models, e, asked_type)) {
          r.remedy_key = remedy->key;
          r.remedy_value = formatFixed(remedy->value, remedy->decimals);
        }
        if (e.test == vision::RegionTest::kArea) {
          r.measured = scene.mapping.areaToSensor(r.measured);
          r.low = scene.mapping.areaToSensor(r.low);
          r.high = scene.mapping.areaToSensor(r.high);
        }
      }
    }
    if (r.nearest_name.empty() && r.nearest_type >= 0) {
      for (const auto& m : models)
        if (m.type == r.nearest_type) r.nearest_name = m.name;
    }
    r.text = rejectionText(r) + remedyText(r);
    r.unlike_any_part = unlikeAnyPart(r, scene.regions[i], models);
    rejections_.push_back(std::move(r));
  }
  why_ = "OK " + std::to_string(rejections_.size());
  if (rejections_.empty()) {
    why_ += scene.regions.empty() ? " no region in the frame" : " every region reported";
    return;
  }
  // The near misses' sentences first, then those of the regions unlike any
  // part, each while the line has room, in region order: on a textured belt
  // a sentence per blotch pushed the few regions worth a look out of the
  // line. What did not fit is counted at the end: "; ..." where near misses
  // were left out, and the regions unlike any part left unsaid.
  const size_t unlike = std::count_if(rejections_.begin(), rejections_.end(),
                                      [](const RegionRejection& r) { return r.unlike_any_part; });
  const std::string more = "; ...";
  // Room kept for the count's clause ("; <k> more regions unlike any part").
  const size_t tail = unlike ? 2 + unlikeSummary(unlike, true).size() : 0;
  bool first = true;
  size_t said_unlike = 0;
  bool near_cut = false;
  for (const bool unlike_pass : {false, true}) {
    for (const auto& r : rejections_) {
      if (r.unlike_any_part != unlike_pass) continue;
      const std::string item = (first ? " " : "; ") + r.text;
      // Room after it for what may follow: "; ..." and the count after a
      // near miss, the count after a region unlike any part but the last.
      const size_t keep =
          !unlike_pass ? more.size() + tail : (said_unlike + 1 == unlike ? 0 : tail);
      if (why_.size() + item.size() + keep > kMaxWhyBytes) {
        if (!unlike_pass) {
          why_ += more;
          first = false;
          near_cut = true;
        }
        break;
      }
      why_ += item;
      first = false;
      if (unlike_pass) ++said_unlike;
    }
    if (near_cut) break;
  }
  if (said_unlike < unlike) {
    why_ += (first ? " " : "; ") + unlikeSummary(unlike - said_unlike, said_unlike > 0);
  }
}

std::shared_ptr<RequestRecord> locateRecord(Result<CellLocate>&& located, int type,
                                            const VisionOptions& options) {
  auto record = std::make_shared<RequestRecord>();
  record->request = "LOCATE";
  record->asked_type = type;
  // The settings the location ran with: a VISION change may have come
  // between it and this record.
  record->options = located && located->outcome.settings ? *located->outcome.settings : options;
  if (located) {
    record->locate = std::move(located->outcome);
    // Nothing published or explained reads the mask: a connection's last
    // LOCATE (kept for WHY) holds no frame-sized buffer.
    record->locate->scene.mask.release();
    record->locate->pixels.reset();
    record->pick = std::move(located->pick);
    record->grasps = std::move(located->grasps);
    record->geometry = std::move(located->geometry);
  }
  return record;
}

}  // namespace picksight::results
