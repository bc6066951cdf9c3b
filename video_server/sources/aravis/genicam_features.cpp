// GenICam features by name through Aravis's node tree.
#include "genicam_features.hpp"

#include <cmath>
#include <locale>
#include <sstream>

#include "glib_ptr.hpp"
#include "picksight/common/text.hpp"

namespace picksight::video {
namespace {
// Categories nest a few levels deep; a loop in a broken XML must not recurse forever.
constexpr int kMaxCategoryDepth = 16;

// '.' as decimal point whatever the locale, and no trailing zeros: "10000",
// "0.5", "1e+07".
std::string formatNumber(double value) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out.precision(12);
  out << value;
  return out.str();
}

std::string rangeText(double min, double max) {
  return "[" + formatNumber(min) + ", " + formatNumber(max) + "]";
}

Error badValue(const std::string& name, const std::string& why) {
  return makeError(SourceErrc::kBadValue, "feature '" + name + "': " + why);
}

// GenICam writes that the device refuses come back as a GError; the device's
// text is the best description there is.
Error writeError(const std::string& name, const std::string& value, const GErrorSlot& error) {
  return badValue(name, "cannot set '" + value + "': " + error.message());
}

std::string orEmpty(const char* text) { return text != nullptr ? text : ""; }
}  // namespace

Result<ArvGcFeatureNode*> GenicamFeatures::node(const std::string& name) const {
  ArvGcNode* found = arv_device_get_feature(device_, name.c_str());
  // Categories are features in GenICam's tree but carry no value.
  if (found == nullptr || !ARV_IS_GC_FEATURE_NODE(found) || ARV_IS_GC_CATEGORY(found)) {
    return makeError(SourceErrc::kUnknownFeature,
                     "unknown feature '" + name + "': the camera has no such GenICam feature");
  }
  return ARV_GC_FEATURE_NODE(found);
}

Feature GenicamFeatures::describe(ArvGcFeatureNode* node) const {
  Feature f;
  f.name = orEmpty(arv_gc_feature_node_get_name(node));
  f.description = orEmpty(arv_gc_feature_node_get_description(node));
  const ArvGcAccessMode access = arv_gc_feature_node_get_actual_access_mode(node);
  GErrorSlot error;
  const bool locked = arv_gc_feature_node_is_locked(node, error.out());
  f.writable = (access == ARV_GC_ACCESS_MODE_RW || access == ARV_GC_ACCESS_MODE_WO) && !locked;
  const bool readable = access != ARV_GC_ACCESS_MODE_WO;

  // Enumerations also implement the integer interface: test them first.
  if (ARV_IS_GC_ENUMERATION(node)) {
    auto* e = ARV_GC_ENUMERATION(node);
    f.type = FeatureType::kEnumeration;
    if (readable) f.value = orEmpty(arv_gc_enumeration_get_string_value(e, error.out()));
    guint n = 0;
    GArrayPtr<const char*> choices(
        arv_gc_enumeration_dup_available_string_values(e, &n, error.out()));
    for (guint i = 0; choices && i < n; ++i) f.choices.emplace_back(orEmpty(choices.get()[i]));
  } else if (ARV_IS_GC_BOOLEAN(node)) {
    f.type = FeatureType::kBoolean;
    if (readable)
      f.value = arv_gc_boolean_get_value(ARV_GC_BOOLEAN(node), error.out()) ? "true" : "false";
    f.choices = {"false", "true"};
  } else if (ARV_IS_GC_COMMAND(node)) {
    f.type = FeatureType::kCommand;
  } else if (ARV_IS_GC_INTEGER(node)) {
    auto* i = ARV_GC_INTEGER(node);
    f.type = FeatureType::kInteger;
    if (readable) f.value = std::to_string(arv_gc_integer_get_value(i, error.out()));
    f.min = static_cast<double>(arv_gc_integer_get_min(i, error.out()));
    const bool has_min = !error;
    f.max = static_cast<double>(arv_gc_integer_get_max(i, error.out()));
    f.has_range = has_min && !error;
    const gint64 inc = arv_gc_integer_get_inc(i, error.out());
    f.increment = !error && inc > 1 ? static_cast<double>(inc) : 0;
    f.unit = orEmpty(arv_gc_integer_get_unit(i));
  } else if (ARV_IS_GC_FLOAT(node)) {
    auto* x = ARV_GC_FLOAT(node);
    f.type = FeatureType::kFloat;
    if (readable) f.value = formatNumber(arv_gc_float_get_value(x, error.out()));
    f.min = arv_gc_float_get_min(x, error.out());
    const bool has_min = !error;
    f.max = arv_gc_float_get_max(x, error.out());
    f.has_range = has_min && !error;
    const double inc = arv_gc_float_get_inc(x, error.out());
    f.increment = !error && std::isfinite(inc) && inc > 0 ? inc : 0;
    f.unit = orEmpty(arv_gc_float_get_unit(x));
  } else if (ARV_IS_GC_STRING(node)) {
    f.type = FeatureType::kString;
    if (readable) f.value = orEmpty(arv_gc_string_get_value(ARV_GC_STRING(node), error.out()));
  } else {
    // Register nodes and the like: shown as text, not written by name.
    f.type = FeatureType::kString;
    if (readable) f.value = orEmpty(arv_gc_feature_node_get_value_as_string(node, error.out()));
  }
  return f;
}

template <typename Visit>
void GenicamFeatures::walk(ArvGcNode* category, const Visit& visit, int depth) const {
  if (depth > kMaxCategoryDepth || category == nullptr || !ARV_IS_GC_CATEGORY(category)) return;
  ArvGc* genicam = arv_device_get_genicam(device_);
  for (const GSList* it = arv_gc_category_get_features(ARV_GC_CATEGORY(category)); it != nullptr;
       it = it->next) {
    ArvGcNode* child = arv_gc_get_node(genicam, static_cast<const char*>(it->data));
    if (child == nullptr || !ARV_IS_GC_FEATURE_NODE(child)) continue;
    if (ARV_IS_GC_CATEGORY(child)) {
      walk(child, visit, depth + 1);
      continue;
    }
    visit(ARV_GC_FEATURE_NODE(child));
  }
}

bool GenicamFeatures::listable(ArvGcFeatureNode* feature) {
  // Both may read registers: part of reading the feature, not of naming it.
  GErrorSlot error;
  return arv_gc_feature_node_is_implemented(feature, error.out()) &&
         arv_gc_feature_node_is_available(feature, error.out());
}

std::vector<Feature> GenicamFeatures::list() const {
  std::vector<Feature> out;
  walk(
      arv_gc_get_node(arv_device_get_genicam(device_), "Root"),
      [&](ArvGcFeatureNode* feature) {
        if (listable(feature)) out.push_back(describe(feature));
      },
      0);
  return out;
}

std::vector<std::string> GenicamFeatures::names() const {
  std::vector<std::string> out;
  walk(
      arv_gc_get_node(arv_device_get_genicam(device_), "Root"),
      [&](ArvGcFeatureNode* feature) {
        out.emplace_back(orEmpty(arv_gc_feature_node_get_name(feature)));
      },
      0);
  return out;
}

std::optional<Feature> GenicamFeatures::listed(const std::string& name) const {
  auto n = node(name);
  if (!n || !listable(*n)) return std::nullopt;
  return describe(*n);
}

Result<Feature> GenicamFeatures::get(const std::string& name) const {
  auto n = node(name);
  if (!n) return n.error();
  return describe(*n);
}

Result<void> GenicamFeatures::set(const std::string& name, const std::string& value) const {
  auto n = node(name);
  if (!n) return n.error();
  ArvGcFeatureNode* feature = *n;
  const Feature current = describe(feature);
  if (!current.writable) return badValue(name, "is read-only");

  GErrorSlot error;
  switch (current.type) {
    case FeatureType::kEnumeration: {
      bool known = false;
      std::string choices;
      for (const auto& c : current.choices) {
        known = known || c == value;
        choices += (choices.empty() ? "" : ", ") + c;
      }
      if (!known) return badValue(name, "'" + value + "' is not one of " + choices);
      arv_gc_enumeration_set_string_value(ARV_GC_ENUMERATION(feature), value.c_str(), error.out());
      break;
    }
    case FeatureType::kBoolean: {
      const std::string v = toUpper(value);
      const bool on = v == "TRUE" || v == "1" || v == "ON";
      if (!on && v != "FALSE" && v != "0" && v != "OFF") {
        return badValue(name, "'" + value + "' is not a boolean (true or false)");
      }
      arv_gc_boolean_set_value(ARV_GC_BOOLEAN(feature), on, error.out());
      break;
    }
    case FeatureType::kCommand:
      arv_gc_command_execute(ARV_GC_COMMAND(feature), error.out());
      break;
    case FeatureType::kInteger: {
      const auto v = parseInt(value);
      if (!v) return badValue(name, "'" + value + "' is not an integer");
      if (current.has_range && (*v < current.min || *v > current.max)) {
        return badValue(name, value + " is out of range " + rangeText(current.min, current.max));
      }
      if (current.increment > 1 && current.has_range) {
        const auto step = static_cast<long long>(current.increment);
        if ((*v - static_cast<long long>(current.min)) % step != 0) {
          return badValue(name, value + " is not " + formatNumber(current.min) +
                                    " plus a multiple of " + formatNumber(current.increment));
        }
      }
      arv_gc_integer_set_value(ARV_GC_INTEGER(feature), *v, error.out());
      break;
    }
    case FeatureType::kFloat: {
      const auto v = parseDouble(value);
      if (!v || !std::isfinite(*v)) return badValue(name, "'" + value + "' is not a number");
      if (current.has_range && (*v < current.min || *v > current.max)) {
        return badValue(name, value + " is out of range " + rangeText(current.min, current.max));
      }
      arv_gc_float_set_value(ARV_GC_FLOAT(feature), *v, error.out());
      break;
    }
    case FeatureType::kString:
      if (!ARV_IS_GC_STRING(feature)) return badValue(name, "cannot be set by name");
      arv_gc_string_set_value(ARV_GC_STRING(feature), value.c_str(), error.out());
      break;
  }
  if (error) return writeError(name, value, error);
  return {};
}

}  // namespace picksight::video
