// VisionResult from a request record: frame and mapping, binarization,
// regions with simplified outlines, parts with the placed model outline,
// grasp and fingers, rejections.
#include "result_message.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "picksight/grasp/grasp.hpp"

namespace picksight::results {
using cell::greyImage;
using cell::LocatedPart;
using cell::LocateOutcome;
using cell::LocateScene;
using cell::modelOf;
using cell::partPoseInVisionFrame;
using store::GraspSetup;
namespace {

constexpr size_t kMaxOutlinePoints = 512;
constexpr size_t kMaxRequestLine = 256;
constexpr size_t kMaxReply = 4096;

void setPoint(proto::Point2* out, cv::Point2d p) {
  out->set_x(p.x);
  out->set_y(p.y);
}

const char* methodName(vision::ThresholdMethod method) {
  switch (method) {
    case vision::ThresholdMethod::kAdaptive:
      return "adaptive";
    case vision::ThresholdMethod::kOtsu:
      return "otsu";
    case vision::ThresholdMethod::kFixed:
      return "fixed";
  }
  return "adaptive";
}

// A region's outer boundary simplified to about a pixel, coarser until it
// has at most kMaxOutlinePoints, in sensor pixels.
void setOutline(proto::Polygon* out, const std::vector<cv::Point>& outer,
                const SensorMapping& mapping) {
  std::vector<cv::Point> simple = outer;
  for (double epsilon = 1.0; simple.size() > kMaxOutlinePoints && epsilon < 1e6; epsilon *= 2)
    cv::approxPolyDP(outer, simple, epsilon, true);
  if (simple.size() > kMaxOutlinePoints) simple.resize(kMaxOutlinePoints);
  for (const auto& p : simple) setPoint(out->add_points(), mapping.toSensor(cv::Point2d(p)));
}

void addRegions(proto::VisionResult& out, const std::vector<vision::Region>& regions,
                const SensorMapping& mapping) {
  out.set_regions_total(static_cast<uint32_t>(regions.size()));
  const size_t n = std::min(regions.size(), kMaxResultRegions);
  for (size_t i = 0; i < n; ++i) {
    const vision::Region& r = regions[i];
    auto* region = out.add_regions();
    region->set_index(static_cast<uint32_t>(i));
    const cv::Rect box = mapping.boxToSensor(r.bbox);
    region->set_box_x(box.x);
    region->set_box_y(box.y);
    region->set_box_width(box.width);
    region->set_box_height(box.height);
    region->set_area(mapping.areaToSensor(r.area));
    setPoint(region->mutable_centroid(), mapping.toSensor(r.centroid));
    region->set_holes(static_cast<uint32_t>(r.holes));
    setOutline(region->mutable_outline(), r.outer, mapping);
  }
}

// The model's loops placed at the part's pose (sensor pixels), outer first.
void addPlacedOutline(proto::ResultPart* out, const vision::PartModel& model,
                      const LocatedPart& part) {
  const double a = part.angle_deg * M_PI / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  for (int hole = 0; hole < 2; ++hole) {
    for (const auto& loop : model.loops) {
      if (loop.hole != (hole == 1)) continue;
      auto* polygon = out->add_outline();
      for (const auto& prim : loop.primitives) {
        const int steps = prim.kind == vision::PrimitiveKind::kLine
                              ? 1
                              : std::clamp(static_cast<int>(prim.length() / 2.0), 2, 64);
        for (int k = 0; k < steps; ++k) {
          const cv::Point2d p = prim.pointAt(static_cast<double>(k) / steps);
          setPoint(polygon->add_points(), {part.x + c * p.x - s * p.y, part.y + s * p.x + c * p.y});
        }
      }
    }
  }
}

// Regions (indices) under a finger polygon given in sensor pixels, other
// than the part's own; -1 when the finger reaches outside the frame.
std::vector<int> blockersOf(const std::vector<cv::Point2d>& finger, const LocateScene& scene,
                            const FrameInfo& frame, int own_region) {
  std::vector<int> blockers;
  std::vector<cv::Point2f> poly;
  bool outside = false;
  for (const auto& p : finger) {
    const cv::Point2d f = scene.mapping.toFrame(p);
    outside = outside || f.x < 0 || f.y < 0 || f.x > frame.width - 1.0 || f.y > frame.height - 1.0;
    poly.emplace_back(f);
  }
  if (outside) blockers.push_back(-1);
  if (poly.size() < 3) return blockers;
  const cv::Rect reach = cv::boundingRect(poly);
  for (size_t i = 0; i < std::min(scene.regions.size(), kMaxResultRegions); ++i) {
    const vision::Region& r = scene.regions[i];
    if (static_cast<int>(i) == own_region || (r.bbox & reach).empty()) continue;
    bool under = std::any_of(r.outer.begin(), r.outer.end(), [&](const cv::Point& q) {
      return cv::pointPolygonTest(poly, cv::Point2f(q), false) >= 0;
    });
    for (size_t k = 0; !under && k < poly.size(); ++k)
      under = cv::pointPolygonTest(r.outer, poly[k], false) >= 0;
    if (under) blockers.push_back(static_cast<int>(i));
  }
  return blockers;
}

void addParts(proto::VisionResult& out, const RequestRecord& record) {
  const LocateOutcome& locate = *record.locate;
  const LocateScene& scene = locate.scene;
  for (size_t index = 0; index < locate.parts.size(); ++index) {
    const LocatedPart& part = locate.parts[index];
    auto* p = out.add_parts();
    p->set_type(part.type);
    p->set_region(part.region);
    setPoint(p->mutable_position(), {part.x, part.y});
    p->set_angle_deg(part.angle_deg);
    p->set_symmetry_deg(part.symmetry_deg);
    p->set_score(part.score);
    p->set_touching(part.touching);
    p->set_grasp_style(-1);
    const vision::PartModel* model = modelOf(scene, part.type);
    if (model) {
      p->set_name(model->name);
      addPlacedOutline(p, *model, part);
    }
    const auto offered = std::find(record.pick.parts.begin(), record.pick.parts.end(), index);
    const size_t pose_index = static_cast<size_t>(offered - record.pick.parts.begin());
    p->set_offered(offered != record.pick.parts.end());
    if (p->offered()) {
      const grasp::Pose& reply = record.pick.poses[pose_index];
      auto* pose = p->mutable_reply_pose();
      pose->set_x(reply.x);
      pose->set_y(reply.y);
      pose->set_rz_deg(reply.rz_deg);
    }
    if (!record.geometry) continue;
    const auto& vision = record.geometry->vision;
    const grasp::Pose part_pose = partPoseInVisionFrame(part, vision);
    const GraspSetup* setup = nullptr;
    if (record.grasps && part.type >= 0) {
      const auto it = record.grasps->find(part.type);
      if (it != record.grasps->end()) setup = &it->second;
    }
    int style = -1;
    if (p->offered() && pose_index < record.pick.styles.size())
      style = record.pick.styles[pose_index];
    p->set_grasp_style(style);
    grasp::GraspStyle chosen;
    if (style >= 0 && setup && static_cast<size_t>(style) < setup->styles.size())
      chosen = setup->styles[static_cast<size_t>(style)];
    else if (!p->offered() && setup && !setup->styles.empty())
      chosen = setup->styles.front();  // the first style tried
    const grasp::Pose gripper = grasp::gripperPose(part_pose, chosen);
    setPoint(p->mutable_grasp_position(), vision.toPixels({gripper.x, gripper.y}));
    p->set_grasp_angle_deg(vision.directionToImage(gripper.rz_deg, {gripper.x, gripper.y}));
    if (!setup || setup->gripper.fingers.empty()) continue;
    for (const auto& polygon : grasp::fingerPolygons(gripper, setup->gripper, vision)) {
      auto* finger = p->add_fingers();
      for (const auto& q : polygon) setPoint(finger->mutable_footprint()->add_points(), q);
      // An offered grasp is clear by construction: no blocker to look for.
      if (p->offered()) continue;
      const auto blockers = blockersOf(polygon, scene, locate.frame, part.region);
      finger->set_blocked(!blockers.empty());
      for (int b : blockers) finger->add_blocked_by(b);
    }
  }
}

}  // namespace

void buildVisionResult(const RequestRecord& record, const std::string& app, uint64_t request_id,
                       proto::VisionResult& out) {
  out.Clear();
  out.set_app(app);
  out.set_request_id(request_id);
  out.set_request(record.request);
  out.set_request_line(record.request_line.substr(0, kMaxRequestLine));
  out.set_client(record.client);
  out.set_reply(record.reply.substr(0, kMaxReply));
  out.set_why(record.why());
  out.set_elapsed_ms(record.elapsed_ms);
  out.set_asked_type(record.asked_type);
  out.set_changed(record.changed);
  const vision::BinarizeOptions& binarize = record.options.binarize;
  auto* settings = out.mutable_binarize();
  settings->set_method(methodName(binarize.method));
  settings->set_threshold(
      binarize.method == vision::ThresholdMethod::kFixed ? binarize.fixed_threshold : 0);
  settings->set_dark_parts(binarize.polarity == vision::Polarity::kDarkOnLight);
  settings->set_window(binarize.method == vision::ThresholdMethod::kAdaptive
                           ? static_cast<uint32_t>(binarize.adaptive_window)
                           : 0);
  settings->set_min_region_area(record.options.regions.min_area);
  const auto info = record.frameInfo();
  if (info) {
    out.set_camera(info->camera);
    out.set_frame_sequence(info->sequence);
    out.set_frame_host_timestamp_ns(info->host_timestamp_ns);
    out.set_frame_width(info->width);
    out.set_frame_height(info->height);
  }
  const SensorMapping* mapping = record.locate  ? &record.locate->scene.mapping
                                 : record.frame ? &record.frame->mapping
                                                : nullptr;
  if (mapping) {
    out.set_roi_x(static_cast<uint32_t>(std::lround(mapping->roi_x)));
    out.set_roi_y(static_cast<uint32_t>(std::lround(mapping->roi_y)));
    out.set_scale_x(mapping->scale_x);
    out.set_scale_y(mapping->scale_y);
  }
  out.set_reply_frame(record.replyFrame());
  if (record.locate) {
    addRegions(out, record.locate->scene.regions, record.locate->scene.mapping);
    addParts(out, record);
    for (const auto& r : record.rejections()) {
      auto* rejection = out.add_rejections();
      rejection->set_region(r.region);
      rejection->set_nearest_type(r.nearest_type);
      rejection->set_nearest_name(r.nearest_name);
      rejection->set_test(r.test);
      rejection->set_measured(r.measured);
      rejection->set_low(r.low);
      rejection->set_high(r.high);
      rejection->set_remedy_key(r.remedy_key);
      rejection->set_remedy_value(r.remedy_value);
      rejection->set_text(r.text);
      rejection->set_unlike_any_part(r.unlike_any_part);
    }
  } else if (record.frame) {
    const cv::Mat grey = greyImage(*record.frame);
    addRegions(out,
               vision::findRegions(vision::binarize(grey, record.options.binarize),
                                   record.options.regions, grey),
               record.frame->mapping);
  }
}

}  // namespace picksight::results
