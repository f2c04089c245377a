// Time profiles (the hand's set-point, the force operator's force): a `shape` and the keys
// that shape takes, turned into the breakpoints of a piecewise-linear function (or the sine
// parameters) that the simulator evaluates.
#include <algorithm>
#include <array>

#include "config/config_schema.h"

namespace hapticd::config::schema {
namespace {

using Shape = ProfileSpec::Shape;

const std::vector<std::string> kShapeNames{"constant", "step", "ramp", "sine", "press"};
constexpr std::array<Shape, 5> kShapes{Shape::kConstant, Shape::kStep, Shape::kRamp, Shape::kSine,
                                       Shape::kPress};

// Every key any shape takes, in the order the documentation lists them.
const std::vector<std::string> kAllKeys{"shape", "value",    "initial", "final",     "at",
                                        "start", "duration", "offset",  "amplitude", "frequency_hz",
                                        "phase", "rest",     "depth",   "ramp",      "hold"};

const std::vector<std::vector<std::string>> kShapeKeys{
    {"shape", "value"},
    {"shape", "initial", "final", "at"},
    {"shape", "initial", "final", "start", "duration"},
    {"shape", "offset", "amplitude", "frequency_hz", "phase"},
    {"shape", "rest", "depth", "start", "ramp", "hold"},
};

// Reads the numbers of one shape; each missing required key and each bad value is reported.
class ShapeReader {
 public:
  ShapeReader(MapReader& map, const std::string& shape_name)
      : map_(map), reason_("required by shape '" + shape_name + "'") {}

  double required(std::string_view key, const Range& range = Range::any()) {
    const Field f = map_.take(key);
    if (!f.present) {
      map_.missing(key, reason_);
      ok_ = false;
      return 0.0;
    }
    return value(f, range);
  }

  double optional(std::string_view key, double fallback, const Range& range = Range::any()) {
    const Field f = map_.take(key);
    return f.present ? value(f, range) : fallback;
  }

  bool ok() const { return ok_; }

 private:
  double value(const Field& f, const Range& range) {
    const auto v = read_number(map_.diag(), f, range);
    if (!v) ok_ = false;
    return v.value_or(0.0);
  }

  MapReader& map_;
  std::string reason_;
  bool ok_ = true;
};

ProfileSpec build(Shape shape, ShapeReader& r) {
  ProfileSpec p;
  p.shape = shape;
  switch (shape) {
    case Shape::kConstant:
      p.points = {{0.0, r.required("value")}};
      break;
    case Shape::kStep: {
      const double initial = r.required("initial");
      const double final_value = r.required("final");
      const double at = r.required("at", Range::at_least(0.0));
      p.points = {{at, initial}, {at, final_value}};
      break;
    }
    case Shape::kRamp: {
      const double initial = r.required("initial");
      const double final_value = r.required("final");
      const double start = r.optional("start", 0.0, Range::at_least(0.0));
      const double duration = r.required("duration", Range::greater_than(0.0));
      p.points = {{start, initial}, {start + duration, final_value}};
      break;
    }
    case Shape::kSine:
      p.offset = r.optional("offset", 0.0);
      p.amplitude = r.required("amplitude");
      p.frequency_hz = r.required("frequency_hz", Range::greater_than(0.0));
      p.phase_rad = r.optional("phase", 0.0);
      break;
    case Shape::kPress: {
      const double rest = r.required("rest");
      const double depth = r.required("depth");
      const double start = r.optional("start", 0.0, Range::at_least(0.0));
      const double ramp = r.required("ramp", Range::greater_than(0.0));
      const double hold = r.required("hold", Range::at_least(0.0));
      p.points = {{start, rest},
                  {start + ramp, depth},
                  {start + ramp + hold, depth},
                  {start + 2.0 * ramp + hold, rest}};
      break;
    }
  }
  return p;
}

}  // namespace

void read_profile(MapReader& parent, std::string_view key,
                  const std::optional<std::string>& required_by, ProfileSpec& out) {
  const Field field = parent.take(key);
  if (!field.present) {
    if (required_by) parent.missing(key, "required by " + *required_by);
    return;
  }
  MapReader map(parent.diag(), field);
  if (!map.ok()) return;

  const Field shape_field = map.take("shape");
  if (!shape_field.present) {
    map.diag().error(field.key_mark, child_path(field.path, "shape"),
                     "missing; must be one of constant, step, ramp, sine, press");
    map.skip_rest();  // which keys apply depends on the shape
    return;
  }
  const auto index = read_choice(map.diag(), shape_field, kShapeNames);
  if (!index) {
    // Without a valid shape nothing says which keys apply.
    map.skip_rest();
    return;
  }

  ShapeReader reader(map, kShapeNames[*index]);
  ProfileSpec spec = build(kShapes[*index], reader);
  const std::vector<std::string>& keys = kShapeKeys[*index];
  for (const std::string& k : kAllKeys) {
    if (std::find(keys.begin(), keys.end(), k) == keys.end()) {
      map.not_used(k, "shape '" + kShapeNames[*index] + "'");
    }
  }
  map.finish();
  if (reader.ok()) out = std::move(spec);
}

}  // namespace hapticd::config::schema
