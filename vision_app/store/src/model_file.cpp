// Model file (de)serialization with yaml-cpp; every field is checked on load.
#include "picksight/store/model_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>

namespace picksight::store {

const char* errorName(ModelErrc e) {
  switch (e) {
    case ModelErrc::kUnknownType:
      return "unknown type";
    case ModelErrc::kStorage:
      return "storage";
    case ModelErrc::kInvalidModel:
      return "invalid model";
    case ModelErrc::kBadFile:
      return "bad file";
    case ModelErrc::kNothingToUndo:
      return "nothing to undo";
    case ModelErrc::kUndoRefused:
      return "undo refused";
  }
  return "unknown";
}
namespace {
using vision::PartModel;
using vision::Primitive;
using vision::PrimitiveKind;

void point(YAML::Emitter& out, const char* key, cv::Point2d p) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << p.x << p.y
      << YAML::EndSeq;
}

void range(YAML::Emitter& out, const char* key, const vision::Range& r) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << r.min << r.max
      << YAML::EndSeq;
}

// Reading: a missing or mistyped field throws a message naming the field.
struct FieldError {
  std::string what;
};

const YAML::Node need(const YAML::Node& node, const std::string& key) {
  if (!node.IsMap() || !node[key]) throw FieldError{"missing field '" + key + "'"};
  return node[key];
}

template <typename T>
T as(const YAML::Node& node, const std::string& key) {
  const YAML::Node v = need(node, key);
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw FieldError{"field '" + key + "' has the wrong type"};
  }
}

cv::Point2d asPoint(const YAML::Node& node, const std::string& key) {
  const YAML::Node v = need(node, key);
  if (!v.IsSequence() || v.size() != 2) throw FieldError{"field '" + key + "' must be [x, y]"};
  try {
    return {v[0].as<double>(), v[1].as<double>()};
  } catch (const YAML::Exception&) {
    throw FieldError{"field '" + key + "' must hold two numbers"};
  }
}

vision::Range asRange(const YAML::Node& node, const std::string& key) {
  const cv::Point2d p = asPoint(node, key);
  if (!(p.x <= p.y)) throw FieldError{"range '" + key + "' must be [min, max] with min <= max"};
  return {p.x, p.y};
}
// The boundary's loops of primitives, under "loops".
void writeLoops(YAML::Emitter& out, const std::vector<vision::BoundaryLoop>& loops) {
  out << YAML::Key << "loops" << YAML::Value << YAML::BeginSeq;
  for (const auto& loop : loops) {
    out << YAML::BeginMap;
    out << YAML::Key << "hole" << YAML::Value << loop.hole;
    out << YAML::Key << "weight" << YAML::Value << loop.weight;
    out << YAML::Key << "primitives" << YAML::Value << YAML::BeginSeq;
    for (const auto& p : loop.primitives) {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "kind" << YAML::Value
          << (p.kind == PrimitiveKind::kLine ? "line" : "arc");
      point(out, "start", p.start);
      point(out, "end", p.end);
      if (p.kind == PrimitiveKind::kArc) {
        point(out, "centre", p.centre);
        out << YAML::Key << "radius" << YAML::Value << p.radius;
        out << YAML::Key << "sweep_deg" << YAML::Value << p.sweep_deg;
      }
      out << YAML::Key << "weight" << YAML::Value << p.weight;
      // Optional on reading: files written before them, and models with
      // rotational symmetry, have none.
      if (!p.edge_offsets_mpx.empty()) {
        out << YAML::Key << "edge_offsets_mpx" << YAML::Value << YAML::Flow << YAML::BeginSeq;
        for (const int16_t v : p.edge_offsets_mpx) out << static_cast<int>(v);
        out << YAML::EndSeq;
      }
      if (!p.edge_weights_pct.empty()) {
        out << YAML::Key << "edge_weights_pct" << YAML::Value << YAML::Flow << YAML::BeginSeq;
        for (const uint8_t v : p.edge_weights_pct) out << static_cast<int>(v);
        out << YAML::EndSeq;
      }
      out << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

// The boundary's corners, under "corners".
void writeCorners(YAML::Emitter& out, const std::vector<vision::Corner>& corners) {
  out << YAML::Key << "corners" << YAML::Value << YAML::BeginSeq;
  for (const auto& c : corners) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "class" << YAML::Value << vision::cornerClassName(c.kind);
    out << YAML::Key << "loop" << YAML::Value << c.loop;
    out << YAML::Key << "index" << YAML::Value << c.index;
    point(out, "at", c.at);
    out << YAML::Key << "direction_in_deg" << YAML::Value << c.direction_in_deg;
    out << YAML::Key << "direction_out_deg" << YAML::Value << c.direction_out_deg;
    range(out, "turn_deg", c.turn_deg);
    out << YAML::Key << "convex" << YAML::Value << c.convex;
    range(out, "length_in", c.length_in);
    range(out, "length_out", c.length_out);
    range(out, "radius_in", c.radius_in);
    range(out, "radius_out", c.radius_out);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

// The grasp styles and the gripper's fingers, under "grasp".
void writeGrasp(YAML::Emitter& out, const GraspSetup& grasp) {
  out << YAML::Key << "grasp" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "styles" << YAML::Value << YAML::BeginSeq;
  for (const auto& st : grasp.styles) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "x_mm" << YAML::Value << st.x_mm
        << YAML::Key << "y_mm" << YAML::Value << st.y_mm << YAML::Key << "rz_deg" << YAML::Value
        << st.rz_deg << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "fingers" << YAML::Value << YAML::BeginSeq;
  for (const auto& f : grasp.gripper.fingers) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "x_mm" << YAML::Value << f.x_mm << YAML::Key
        << "y_mm" << YAML::Value << f.y_mm << YAML::Key << "width_mm" << YAML::Value << f.width_mm
        << YAML::Key << "height_mm" << YAML::Value << f.height_mm << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
}
}  // namespace

std::string modelToYaml(const PartModel& m, const GraspSetup& grasp) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // doubles read back bit-exact
  out << YAML::Comment("PickSight part model: see docs/PROTOCOL.md (LEARN)");
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "picksight-part-model";
  out << YAML::Key << "version" << YAML::Value << kModelFormatVersion;
  out << YAML::Key << "type" << YAML::Value << m.type;
  out << YAML::Key << "name" << YAML::Value << m.name;
  out << YAML::Key << "trained" << YAML::Value << YAML::BeginMap;
  point(out, "centroid", m.trained_centroid);
  out << YAML::Key << "angle_deg" << YAML::Value << m.trained_angle_deg;
  // Optional on reading: a model of one view has none.
  if (!m.views.empty()) {
    out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
    for (const auto& v : m.views) {
      out << YAML::Flow << YAML::BeginSeq << v.x << v.y << YAML::EndSeq;
    }
    out << YAML::EndSeq;
    point(out, "origin_shift", m.origin_shift);
  }
  out << YAML::EndMap;

  // Optional on reading: files written before it count every region and hole.
  out << YAML::Key << "regions" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "min_area" << YAML::Value << m.min_region_area;
  out << YAML::Key << "min_hole_area" << YAML::Value << m.min_hole_area;
  // Optional on reading: files written before it do not say.
  if (m.taught_polarity) {
    out << YAML::Key << "polarity" << YAML::Value
        << (*m.taught_polarity == vision::Polarity::kDarkOnLight ? "dark" : "light");
  }
  out << YAML::EndMap;

  // Optional on reading: a model taught in grey levels has none.
  if (m.colour) {
    out << YAML::Key << "colour" << YAML::Value << YAML::BeginMap;
    for (const auto& [key, bgr] :
         {std::pair<const char*, cv::Vec3d>{"part_bgr", m.colour->part},
          std::pair<const char*, cv::Vec3d>{"background_bgr", m.colour->background}}) {
      out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << bgr[0] << bgr[1]
          << bgr[2] << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }

  out << YAML::Key << "body" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "area" << YAML::Value << m.body.area;
  out << YAML::Key << "area_tolerance" << YAML::Value << m.body.area_tolerance;
  out << YAML::Key << "holes" << YAML::Value << m.body.holes;
  out << YAML::Key << "log_hu" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double h : m.body.log_hu) out << h;
  out << YAML::EndSeq;
  out << YAML::Key << "hu_used" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (bool u : m.body.hu_used) out << u;
  out << YAML::EndSeq;
  out << YAML::Key << "hu_tolerance" << YAML::Value << m.body.hu_tolerance;
  out << YAML::Key << "mirror_symmetric" << YAML::Value << m.body.mirror_symmetric;
  out << YAML::EndMap;

  out << YAML::Key << "orientation" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "order" << YAML::Value << m.orientation_order;
  out << YAML::Key << "phase_deg" << YAML::Value << m.orientation_phase_deg;
  out << YAML::Key << "symmetry_order" << YAML::Value << m.symmetry_order;
  out << YAML::EndMap;

  out << YAML::Key << "boundary" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "conformity_px" << YAML::Value << m.conformity;
  out << YAML::Key << "edge_tolerance_px" << YAML::Value << m.edge_tolerance;
  out << YAML::Key << "verify_percent" << YAML::Value << m.verify_percent;
  writeLoops(out, m.loops);
  writeCorners(out, m.corners);
  out << YAML::EndMap;

  writeGrasp(out, grasp);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {
// What is wrong with a grasp set-up; empty when nothing is.
std::string graspProblem(const GraspSetup& grasp) {
  // Beyond a few metres a value is a typo, not a gripper.
  constexpr double kMaxMm = 10000;
  const auto bad = [](double v, double limit) { return !std::isfinite(v) || std::abs(v) > limit; };
  if (grasp.styles.size() > kMaxGraspStyles)
    return "at most " + std::to_string(kMaxGraspStyles) + " grasp styles";
  if (grasp.gripper.fingers.size() > kMaxFingers)
    return "at most " + std::to_string(kMaxFingers) + " fingers";
  for (const auto& s : grasp.styles) {
    if (bad(s.x_mm, kMaxMm) || bad(s.y_mm, kMaxMm) || bad(s.rz_deg, 360))
      return "a grasp style needs |x|, |y| <= 10000 mm and |rz| <= 360 deg";
  }
  for (const auto& f : grasp.gripper.fingers) {
    if (bad(f.x_mm, kMaxMm) || bad(f.y_mm, kMaxMm) || bad(f.width_mm, kMaxMm) ||
        bad(f.height_mm, kMaxMm) || !(f.width_mm > 0) || !(f.height_mm > 0))
      return "a finger needs |x|, |y| <= 10000 mm and a size in (0, 10000] mm";
  }
  return {};
}
}  // namespace

Result<void> validateGrasp(const GraspSetup& grasp) {
  const std::string problem = graspProblem(grasp);
  if (problem.empty()) return {};
  return makeError(ModelErrc::kInvalidModel, problem);
}

Result<PartModel> modelFromYaml(const std::string& text) {
  auto record = modelRecordFromYaml(text);
  if (!record) return record.error();
  return std::move(record->model);
}

namespace {
// The boundary's loops of primitives (FieldError when one is wrong).
std::vector<vision::BoundaryLoop> readLoops(const YAML::Node& boundary) {
  std::vector<vision::BoundaryLoop> loops_out;
  const YAML::Node loops = need(boundary, "loops");
  if (!loops.IsSequence()) throw FieldError{"'loops' must be a list"};
  for (const auto& l : loops) {
    vision::BoundaryLoop loop;
    loop.hole = as<bool>(l, "hole");
    loop.weight = as<double>(l, "weight");
    const YAML::Node prims = need(l, "primitives");
    if (!prims.IsSequence()) throw FieldError{"'primitives' must be a list"};
    for (const auto& p : prims) {
      Primitive prim;
      const std::string kind = as<std::string>(p, "kind");
      if (kind != "line" && kind != "arc")
        throw FieldError{"primitive kind must be line or arc, got '" + kind + "'"};
      prim.kind = kind == "line" ? PrimitiveKind::kLine : PrimitiveKind::kArc;
      prim.start = asPoint(p, "start");
      prim.end = asPoint(p, "end");
      if (prim.kind == PrimitiveKind::kArc) {
        prim.centre = asPoint(p, "centre");
        prim.radius = as<double>(p, "radius");
        prim.sweep_deg = as<double>(p, "sweep_deg");
      }
      prim.weight = as<double>(p, "weight");
      if (p["edge_offsets_mpx"]) {
        const YAML::Node offsets = p["edge_offsets_mpx"];
        if (!offsets.IsSequence())
          throw FieldError{"'edge_offsets_mpx' must be a list of whole thousandths of a pixel"};
        prim.edge_offsets_mpx.reserve(offsets.size());
        for (const auto& v : offsets) {
          try {
            prim.edge_offsets_mpx.push_back(v.as<int16_t>());
          } catch (const YAML::Exception&) {
            throw FieldError{
                "each of 'edge_offsets_mpx' must be a whole number of thousandths of a pixel"};
          }
        }
      }
      if (p["edge_weights_pct"]) {
        const YAML::Node weights = p["edge_weights_pct"];
        if (!weights.IsSequence())
          throw FieldError{"'edge_weights_pct' must be a list of whole percents"};
        prim.edge_weights_pct.reserve(weights.size());
        for (const auto& v : weights) {
          int pct = -1;
          try {
            pct = v.as<int>();
          } catch (const YAML::Exception&) {
            // No whole number: refused below, as one out of range is.
          }
          if (pct < 0 || pct > 100)
            throw FieldError{"each of 'edge_weights_pct' must be a whole percent, 0 to 100"};
          prim.edge_weights_pct.push_back(static_cast<uint8_t>(pct));
        }
      }
      loop.primitives.push_back(std::move(prim));
    }
    loops_out.push_back(std::move(loop));
  }
  return loops_out;
}

// The boundary's corners, each on a primitive of `loops` (FieldError when
// one is wrong).
std::vector<vision::Corner> readCorners(const YAML::Node& boundary,
                                        const std::vector<vision::BoundaryLoop>& loops) {
  std::vector<vision::Corner> corners_out;
  const YAML::Node corners = need(boundary, "corners");
  if (!corners.IsSequence()) throw FieldError{"'corners' must be a list"};
  for (const auto& c : corners) {
    vision::Corner corner;
    const std::string kind = as<std::string>(c, "class");
    bool known = false;
    for (auto k : {vision::CornerClass::kLineLine, vision::CornerClass::kLineArc,
                   vision::CornerClass::kArcLine, vision::CornerClass::kArcArc}) {
      if (kind == vision::cornerClassName(k)) {
        corner.kind = k;
        known = true;
      }
    }
    if (!known) throw FieldError{"unknown corner class '" + kind + "'"};
    corner.loop = as<int>(c, "loop");
    corner.index = as<int>(c, "index");
    if (corner.loop < 0 || static_cast<size_t>(corner.loop) >= loops.size() || corner.index < 0 ||
        static_cast<size_t>(corner.index) >=
            loops[static_cast<size_t>(corner.loop)].primitives.size()) {
      throw FieldError{"a corner refers to a primitive that does not exist"};
    }
    corner.at = asPoint(c, "at");
    corner.direction_in_deg = as<double>(c, "direction_in_deg");
    corner.direction_out_deg = as<double>(c, "direction_out_deg");
    corner.turn_deg = asRange(c, "turn_deg");
    corner.convex = as<bool>(c, "convex");
    corner.length_in = asRange(c, "length_in");
    corner.length_out = asRange(c, "length_out");
    corner.radius_in = asRange(c, "radius_in");
    corner.radius_out = asRange(c, "radius_out");
    corners_out.push_back(corner);
  }
  return corners_out;
}

// The grasp set-up of a version 2 file or later (FieldError when wrong).
GraspSetup readGrasp(const YAML::Node& root) {
  GraspSetup grasp_out;
  const YAML::Node grasp = need(root, "grasp");
  const YAML::Node styles = need(grasp, "styles");
  const YAML::Node fingers = need(grasp, "fingers");
  if (!styles.IsSequence() || !fingers.IsSequence())
    throw FieldError{"'grasp.styles' and 'grasp.fingers' must be lists"};
  for (const auto& st : styles) {
    grasp_out.styles.push_back(
        {as<double>(st, "x_mm"), as<double>(st, "y_mm"), as<double>(st, "rz_deg")});
  }
  for (const auto& f : fingers) {
    grasp_out.gripper.fingers.push_back({as<double>(f, "x_mm"), as<double>(f, "y_mm"),
                                         as<double>(f, "width_mm"), as<double>(f, "height_mm")});
  }
  if (auto valid = validateGrasp(grasp_out); !valid)
    throw FieldError{"grasp: " + valid.error().message};
  return grasp_out;
}
}  // namespace

Result<ModelRecord> modelRecordFromYaml(const std::string& text) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return makeError(ModelErrc::kBadFile,
                     "not YAML: " + e.msg + " (line " + std::to_string(e.mark.line + 1) + ")");
  }
  ModelRecord record;
  PartModel& m = record.model;
  try {
    if (!root.IsMap() || as<std::string>(root, "format") != "picksight-part-model") {
      return makeError(ModelErrc::kBadFile,
                       "not a PickSight part model (format: picksight-part-model)");
    }
    const int version = as<int>(root, "version");
    if (version < kOldestModelFormatVersion || version > kModelFormatVersion) {
      return makeError(ModelErrc::kBadFile, "format version " + std::to_string(version) +
                                                " (this program reads versions " +
                                                std::to_string(kOldestModelFormatVersion) + " to " +
                                                std::to_string(kModelFormatVersion) + ")");
    }
    m.type = as<int>(root, "type");
    m.name = as<std::string>(root, "name");
    const YAML::Node trained = need(root, "trained");
    m.trained_centroid = asPoint(trained, "centroid");
    m.trained_angle_deg = as<double>(trained, "angle_deg");
    if (trained["views"]) {
      const YAML::Node views = trained["views"];
      if (!views.IsSequence()) throw FieldError{"'trained.views' must be a list of [x, y]"};
      // Bounded before reading: the model's own check counts them after.
      if (views.size() > vision::kMaxModelViews)
        throw FieldError{"'trained.views' holds more than " +
                         std::to_string(vision::kMaxModelViews) + " views"};
      for (const auto& v : views) {
        if (!v.IsSequence() || v.size() != 2)
          throw FieldError{"each of 'trained.views' must be [x, y]"};
        try {
          m.views.emplace_back(v[0].as<double>(), v[1].as<double>());
        } catch (const YAML::Exception&) {
          throw FieldError{"each of 'trained.views' must hold two numbers"};
        }
      }
      m.origin_shift = asPoint(trained, "origin_shift");
    }

    if (root["regions"]) {
      const YAML::Node regions = root["regions"];
      m.min_region_area = as<double>(regions, "min_area");
      m.min_hole_area = as<double>(regions, "min_hole_area");
      if (regions["polarity"]) {
        const auto polarity = as<std::string>(regions, "polarity");
        if (polarity != "dark" && polarity != "light")
          throw FieldError{"regions: polarity must be dark or light, got '" + polarity + "'"};
        m.taught_polarity =
            polarity == "dark" ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
      }
    }

    if (root["colour"]) {
      const YAML::Node colour = root["colour"];
      vision::ColourAxis axis;
      for (const auto& [key, bgr] :
           {std::pair<const char*, cv::Vec3d*>{"part_bgr", &axis.part},
            std::pair<const char*, cv::Vec3d*>{"background_bgr", &axis.background}}) {
        const auto v = as<std::vector<double>>(colour, key);
        if (v.size() != 3) throw FieldError{std::string("colour: ") + key + " needs 3 values"};
        *bgr = cv::Vec3d(v[0], v[1], v[2]);
      }
      m.colour = axis;
    }

    const YAML::Node body = need(root, "body");
    m.body.area = as<double>(body, "area");
    m.body.area_tolerance = as<double>(body, "area_tolerance");
    m.body.holes = as<int>(body, "holes");
    const auto hu = as<std::vector<double>>(body, "log_hu");
    const auto used = as<std::vector<bool>>(body, "hu_used");
    if (hu.size() != 7 || used.size() != 7)
      throw FieldError{"log_hu and hu_used need 7 values each"};
    for (size_t i = 0; i < 7; ++i) {
      m.body.log_hu[i] = hu[i];
      m.body.hu_used[i] = used[i];
    }
    m.body.hu_tolerance = as<double>(body, "hu_tolerance");
    m.body.mirror_symmetric = as<bool>(body, "mirror_symmetric");

    const YAML::Node orientation = need(root, "orientation");
    m.orientation_order = as<int>(orientation, "order");
    m.orientation_phase_deg = as<double>(orientation, "phase_deg");
    m.symmetry_order = as<int>(orientation, "symmetry_order");

    const YAML::Node boundary = need(root, "boundary");
    m.conformity = as<double>(boundary, "conformity_px");
    m.edge_tolerance = as<double>(boundary, "edge_tolerance_px");
    m.verify_percent = as<double>(boundary, "verify_percent");
    m.loops = readLoops(boundary);
    m.corners = readCorners(boundary, m.loops);
    if (version >= 2) record.grasp = readGrasp(root);
  } catch (const FieldError& e) {
    return makeError(ModelErrc::kBadFile, e.what);
  } catch (const YAML::Exception& e) {
    return makeError(ModelErrc::kBadFile, e.msg);
  }
  if (auto valid = vision::validateModel(m); !valid)
    return makeError(ModelErrc::kBadFile, valid.error().message);
  vision::prepareModel(m);
  // The symmetry order sets the range every angle of the part is reported
  // in: a wrong one (a file edited, or damaged within its bounds) would
  // turn a chiral part's grasp by a half turn, so it is checked against
  // the boundary, not taken on trust nor replaced by a default.
  if (auto symmetric = vision::checkSymmetry(m); !symmetric)
    return makeError(ModelErrc::kBadFile, symmetric.error().message);
  return record;
}

}  // namespace picksight::store
