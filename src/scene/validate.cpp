// SceneSpec -> Scene: every semantic check, unit conversion and preset resolution.
#include <openssl/evp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <tuple>

#include "frame_pattern.h"
#include "output_path.h"
#include "geometry/mesh_import.h"
#include "load.h"
#include "scene_magnetics.h"

namespace magbake::scene {
namespace {

constexpr double kPi = std::numbers::pi;

struct Ctx {
  Diagnostics& d;
  double L = 1;  // file length unit -> m
  double A = 1;  // file angle unit -> rad
  std::filesystem::path dir;
  /// Bodies and parts with the same shape share one geometry object, so its derived data (cells,
  /// demagnetization tensors, convex pieces) is computed once per distinct shape, not per body.
  std::map<std::string, std::shared_ptr<const geometry::Shape>> shapes = {};
};

template <class S, class... Args>
std::shared_ptr<const geometry::Shape> shared_shape(Ctx& c, const std::string& key, Args&&... args) {
  auto& slot = c.shapes[key];
  if (!slot) slot = std::make_shared<S>(std::forward<Args>(args)...);
  return slot;
}

std::string shape_key(const char* kind, std::initializer_list<double> values) {
  std::string key = kind;
  for (double v : values) {
    char buf[40];
    std::snprintf(buf, sizeof buf, " %a", v);  // exact: hex float
    key += buf;
  }
  return key;
}

bool positive(Ctx& c, const Val<double>& v, const std::string& path, const char* what = "length") {
  if (!v.set) return false;
  if (!(v.v > 0) || !std::isfinite(v.v)) {
    c.d.add(v.loc, path, std::string("must be a positive ") + what + ", got " + std::to_string(v.v));
    return false;
  }
  return true;
}

// Magnitude limits (SI, after unit conversion) far beyond any shot but small enough that no
// count, product or force computed from them overflows: a hostile or mistyped number (1e308 T,
// a 1e30 m box) is an error at its file:line:col, not NaN moments or a wrapped integer later.
constexpr double kMaxLength = 1e4;          // m: sizes, cell size, voxel, margin
constexpr double kMinLength = 1e-7;         // m: 0.1 um, the smallest size or cell
constexpr double kMaxCoordinate = 1e6;      // m: positions, bounds
constexpr double kMaxSpeed = 1e5;           // m/s
constexpr double kMaxSpin = 1e6;            // rad/s
constexpr double kMaxAcceleration = 1e4;    // m/s² (gravity)
constexpr double kMaxFieldTesla = 100;      // T: external field, remanence
constexpr double kMaxSusceptibility = 1e7;
constexpr double kMaxDensity = 1e6;         // kg/m³
constexpr double kMaxFrame = 1e8;           // |frame number|
constexpr double kMaxFrames = 1e6;          // frames in one shot
constexpr double kMaxStepsPerFrame = 1e6;   // physics substeps between two frames

// |v| (scaled to SI by `scale`) <= `limit`, else a diagnostic; true when within.
bool within(Ctx& c, const Val<double>& v, const std::string& path, double limit, double scale, const char* unit) {
  if (!v.set || std::abs(v.v * scale) <= limit) return true;
  char buf[96];
  std::snprintf(buf, sizeof buf, "out of range: at most %g %s in magnitude, got %g %s", limit, unit, v.v * scale, unit);
  c.d.add(v.loc, path, buf);
  return false;
}
bool within(Ctx& c, const Val<Vec>& v, const std::string& path, double limit, double scale, const char* unit) {
  if (!v.set) return true;
  for (double x : v.v) {
    if (!(std::abs(x * scale) <= limit)) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "out of range: every component at most %g %s in magnitude, got %g %s", limit, unit,
                    x * scale, unit);
      c.d.add(v.loc, path, buf);
      return false;
    }
  }
  return true;
}
// A positive length (scaled to m) between kMinLength and kMaxLength.
bool length(Ctx& c, const Val<double>& v, const std::string& path) {
  if (!positive(c, v, path)) return false;
  if (!within(c, v, path, kMaxLength, c.L, "m")) return false;
  if (v.v * c.L < kMinLength) {
    c.d.add(v.loc, path, "too small: at least " + std::to_string(kMinLength).substr(0, 8) + " m (0.1 um)");
    return false;
  }
  return true;
}

Vec3 vec3(const Val<Vec>& v, double scale = 1) { return Vec3(v.v[0], v.v[1], v.v[2]) * scale; }

std::optional<Quat> orientation(Ctx& c, const OrientationSpec& o, const std::string& path) {
  if (!o.set) return std::nullopt;
  if (o.quat.set) {
    const Eigen::Vector4d q(o.quat.v[0], o.quat.v[1], o.quat.v[2], o.quat.v[3]);
    const double n = q.norm();
    if (n == 0) {
      c.d.add(o.quat.loc, path + ".orientation.quat", "zero quaternion: give a unit quaternion [w, x, y, z]");
      return std::nullopt;
    }
    if (std::abs(n - 1) > 1e-6) {
      c.d.add(o.quat.loc, path + ".orientation.quat",
              "not a unit quaternion (norm " + std::to_string(n) + "): give [w, x, y, z] with w²+x²+y²+z² = 1");
      return std::nullopt;
    }
    return Quat(q[0], q[1], q[2], q[3]).normalized();
  }
  if (o.axis.set && o.angle.set) {
    const Vec3 axis = vec3(o.axis);
    if (axis.norm() == 0) {
      c.d.add(o.axis.loc, path + ".orientation.axis", "zero rotation axis");
      return std::nullopt;
    }
    return Quat(Eigen::AngleAxisd(o.angle.v * c.A, axis.normalized()));
  }
  return std::nullopt;
}

std::optional<Vec3> direction(Ctx& c, const Val<Vec>& v, const std::string& path) {
  if (!v.set) return std::nullopt;
  const Vec3 x = vec3(v);
  if (x.norm() == 0) {
    c.d.add(v.loc, path, "zero vector: give a direction");
    return std::nullopt;
  }
  return x.normalized();
}

ShapeDesc shape(Ctx& c, const ShapeSpec& s, const std::string& path) {
  ShapeDesc out;
  const std::string kp = path + "." + s.kind;
  if (s.kind == "box") {
    out.kind = geometry::ShapeKind::kBox;
    if (!s.size.set) return out;
    for (double x : s.size.v) {
      if (!(x > 0)) {
        c.d.add(s.size.loc, kp, "box edges must be positive lengths");
        return out;
      }
      if (!(x * c.L <= kMaxLength && x * c.L >= kMinLength)) {
        c.d.add(s.size.loc, kp, "box edges must be between 1e-07 and 10000 m");
        return out;
      }
    }
    out.size = vec3(s.size, c.L);
    out.shape = shared_shape<geometry::BoxShape>(c, shape_key("box", {out.size[0], out.size[1], out.size[2]}), out.size);
  } else if (s.kind == "sphere") {
    out.kind = geometry::ShapeKind::kSphere;
    if (!length(c, s.radius, kp + ".radius")) return out;
    out.radius = s.radius.v * c.L;
    out.shape = shared_shape<geometry::SphereShape>(c, shape_key("sphere", {out.radius}), out.radius);
  } else if (s.kind == "cylinder") {
    out.kind = geometry::ShapeKind::kCylinder;
    const bool ok = length(c, s.radius, kp + ".radius") & length(c, s.height, kp + ".height");
    if (!ok) return out;
    out.radius = s.radius.v * c.L, out.height = s.height.v * c.L;
    out.shape = shared_shape<geometry::CylinderShape>(c, shape_key("cylinder", {out.radius, out.height}), out.radius, out.height);
  } else if (s.kind == "torus") {
    out.kind = geometry::ShapeKind::kTorus;
    const bool ok = length(c, s.major, kp + ".major") & length(c, s.minor, kp + ".minor");
    if (!ok) return out;
    if (s.minor.v >= s.major.v) {
      c.d.add(s.minor.loc, kp + ".minor", "the tube radius (minor) must be smaller than the major radius");
      return out;
    }
    out.major = s.major.v * c.L, out.minor = s.minor.v * c.L;
    out.shape = shared_shape<geometry::TorusShape>(c, shape_key("torus", {out.major, out.minor}), out.major, out.minor);
  } else if (s.kind == "mesh") {
    out.kind = geometry::ShapeKind::kMesh;
    if (!s.file.set) return out;
    double scale = 1;
    if (s.scale.set) {
      if (!positive(c, s.scale, kp + ".scale", "number") || !within(c, s.scale, kp + ".scale", 1e6, 1, "")) return out;
      scale = s.scale.v;
    }
    const std::filesystem::path file =
        std::filesystem::path(s.file.v).is_absolute() ? std::filesystem::path(s.file.v) : c.dir / s.file.v;
    out.mesh_file = file.lexically_normal().string();
    out.mesh_scale = scale;
    try {
      const std::string key = shape_key(("mesh " + out.mesh_file).c_str(), {scale * c.L});
      if (auto it = c.shapes.find(key); it != c.shapes.end()) {
        out.shape = it->second;
      } else {
        geometry::TriangleSoup soup = geometry::load_triangles(out.mesh_file, scale * c.L);
        out.shape = shared_shape<geometry::MeshShape>(c, key, std::move(soup.vertices), std::move(soup.triangles));
      }
    } catch (const std::exception& e) {
      c.d.add(s.file.loc, kp + ".file", e.what());
    }
  }
  return out;
}

// outputs.field and outputs.preview in SI units (shared with outputs_of_text: farm nodes read
// them from a cache's scene text without loading its meshes).
void read_outputs(const SceneSpec& s, double L, double A, Diagnostics& d, std::optional<FieldOutput>& field,
                  std::optional<PreviewOutput>& preview) {
  Ctx c{d, L, A, {}};
  if (s.field_set) {
    FieldOutput f;
    f.path = s.field_path.v;
    if (s.field_path.set) {
      if (const auto e = frame_pattern_error(f.path)) d.add(s.field_path.loc, "outputs.field.path", *e);
      else if (const auto e2 = output_path_error(f.path, true)) d.add(s.field_path.loc, "outputs.field.path", *e2);
    }
    if (s.field_voxel.set && length(c, s.field_voxel, "outputs.field.voxel")) f.voxel = s.field_voxel.v * L;
    if (s.field_margin.set) {
      if (!(s.field_margin.v >= 0)) d.add(s.field_margin.loc, "outputs.field.margin", "must be >= 0");
      else if (within(c, s.field_margin, "outputs.field.margin", kMaxLength, L, "m")) f.margin = s.field_margin.v * L;
    }
    if (s.field_threshold.set) {
      if (!(s.field_threshold.v >= 0 && s.field_threshold.v <= 100)) {
        d.add(s.field_threshold.loc, "outputs.field.threshold", "must be 'auto' or from 0 to 100 (tesla)");
      } else {
        f.threshold = s.field_threshold.v;
      }
    }
    if (s.field_every.set) {
      if (!(s.field_every.v >= 1 && s.field_every.v <= kMaxFrames) || s.field_every.v != std::floor(s.field_every.v)) {
        d.add(s.field_every.loc, "outputs.field.every", "must be a whole number from 1 to 1000000");
      } else {
        f.every = int(s.field_every.v);
      }
    }
    if (s.field_bounds_auto.set && s.field_bounds_auto.v != "auto") {
      d.add(s.field_bounds_auto.loc, "outputs.field.bounds", "expected 'auto' or [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
    }
    if (s.field_bounds.set) {
      for (const auto& corner : s.field_bounds.v) {
        for (double x : corner) {
          if (!(std::abs(x * L) <= kMaxCoordinate)) d.add(s.field_bounds.loc, "outputs.field.bounds", "out of range: at most 1e6 m");
        }
      }
      f.auto_bounds = false;
      f.bounds_min = Vec3(s.field_bounds.v[0][0], s.field_bounds.v[0][1], s.field_bounds.v[0][2]) * L;
      f.bounds_max = Vec3(s.field_bounds.v[1][0], s.field_bounds.v[1][1], s.field_bounds.v[1][2]) * L;
      if (!(f.bounds_min.array() < f.bounds_max.array()).all()) {
        d.add(s.field_bounds.loc, "outputs.field.bounds", "every minimum must be below its maximum");
      }
    }
    field = f;
  }
  if (s.preview_set) {
    PreviewOutput p;
    p.path = s.preview_path.v;
    if (s.preview_path.set) {
      if (const auto e = frame_pattern_error(p.path)) d.add(s.preview_path.loc, "outputs.preview.path", *e);
      else if (const auto e2 = output_path_error(p.path, true)) d.add(s.preview_path.loc, "outputs.preview.path", *e2);
    }
    if (s.preview_size.set) {
      const double w = s.preview_size.v[0], h = s.preview_size.v[1];
      if (!(w >= 16 && h >= 16 && w <= 16384 && h <= 16384) || w != std::floor(w) || h != std::floor(h)) {
        d.add(s.preview_size.loc, "outputs.preview.size", "expected [width, height] in pixels, 16 to 16384");
      } else {
        p.width = int(w), p.height = int(h);
      }
    }
    if (s.field_lines.set) p.field_lines = s.field_lines.v;
    within(c, s.camera.position, "outputs.preview.camera.position", kMaxCoordinate, L, "m");
    within(c, s.camera.look_at, "outputs.preview.camera.look_at", kMaxCoordinate, L, "m");
    if (s.camera.set && s.camera.position.set && s.camera.look_at.set) {
      Camera cam;
      cam.position = vec3(s.camera.position, L);
      cam.look_at = vec3(s.camera.look_at, L);
      if (s.camera.fov.set) {
        const double fov = s.camera.fov.v * A;
        if (!(fov > 0 && fov < kPi)) d.add(s.camera.fov.loc, "outputs.preview.camera.fov", "must be between 0 and 180 degrees");
        else cam.fov = fov;
      }
      if ((cam.position - cam.look_at).norm() == 0) {
        d.add(s.camera.loc, "outputs.preview.camera", "position and look_at must differ");
      }
      p.camera = cam;
    }
    preview = p;
  }
}

}  // namespace

std::string ShapeDesc::describe() const {
  char buf[256];
  switch (kind) {
    case geometry::ShapeKind::kBox:
      std::snprintf(buf, sizeof buf, "box %g x %g x %g mm", size[0] * 1e3, size[1] * 1e3, size[2] * 1e3);
      break;
    case geometry::ShapeKind::kSphere: std::snprintf(buf, sizeof buf, "sphere r=%g mm", radius * 1e3); break;
    case geometry::ShapeKind::kCylinder:
      std::snprintf(buf, sizeof buf, "cylinder r=%g mm h=%g mm", radius * 1e3, height * 1e3);
      break;
    case geometry::ShapeKind::kTorus:
      std::snprintf(buf, sizeof buf, "torus R=%g mm r=%g mm", major * 1e3, minor * 1e3);
      break;
    case geometry::ShapeKind::kMesh:
      std::snprintf(buf, sizeof buf, "mesh %s (%zu triangles)", std::filesystem::path(mesh_file).filename().c_str(),
                    shape ? static_cast<const geometry::MeshShape&>(*shape).triangles().size() : 0);
      break;
  }
  return buf;
}

namespace {
// Interpolates the keys that set a quantity (linear / slerp), holding it outside them.
template <class T, class Has, class Get, class Mix>
void interpolate(const std::vector<Key>& keys, double t, Has has, Get get, Mix mix, T& out) {
  const Key* prev = nullptr;
  for (const Key& k : keys) {
    if (!has(k)) continue;
    if (k.t >= t) {  // the first key at or after t
      out = prev ? mix(get(*prev), get(k), (t - prev->t) / (k.t - prev->t)) : get(k);
      return;
    }
    prev = &k;
  }
  if (prev) out = get(*prev);
}
}  // namespace

Pose Body::pose_at(double t) const {
  if (motion != Motion::kKinematic || keys.empty()) return pose;
  Pose p = pose;
  interpolate(keys, t, [](const Key& k) { return k.position.has_value(); }, [](const Key& k) { return *k.position; },
              [](const Vec3& a, const Vec3& b, double s) { return Vec3((1 - s) * a + s * b); }, p.position);
  interpolate(keys, t, [](const Key& k) { return k.orientation.has_value(); },
              [](const Key& k) { return *k.orientation; },
              [](const Quat& a, const Quat& b, double s) { return a.slerp(s, b); }, p.rotation);
  return p;
}

bool Body::magnetic(const std::vector<Material>& m) const {
  if (material >= 0 && m[material].kind != magnetics::MaterialKind::kNone) return true;
  for (const Part& p : parts) {
    if (p.material >= 0 && m[p.material].kind != magnetics::MaterialKind::kNone) return true;
  }
  return false;
}

Vec3 Scene::applied_field(double t) const {
  const MagneticsSettings& m = magnetics;
  if (m.rotating_field) {
    const auto& r = *m.rotating_field;
    const double a = 2 * kPi * r.frequency * t;
    return r.magnitude * (std::cos(a) * r.from + std::sin(a) * r.axis.cross(r.from));
  }
  const auto& k = m.external_field_keys;
  if (k.empty()) return m.external_field;
  if (t <= k.front().first) return k.front().second;
  if (t >= k.back().first) return k.back().second;
  const auto it = std::upper_bound(k.begin(), k.end(), t, [](double x, const auto& key) { return x < key.first; });
  const auto& [t1, b1] = *it;
  const auto& [t0, b0] = *(it - 1);
  const double s = (t - t0) / (t1 - t0);
  return (1 - s) * b0 + s * b1;
}

int Scene::body_index(const std::string& n) const {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_Digest(bytes.data(), bytes.size(), md, &len, EVP_sha256(), nullptr);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < len; ++i) out += hex[md[i] >> 4], out += hex[md[i] & 15];
  return out;
}

Scene validate_scene(const SceneSpec& s, Diagnostics& d) {
  Scene sc;
  sc.file = s.file;
  sc.text = s.text;
  sc.hash = sha256_hex(s.text);
  Ctx c{d, 1, 1, std::filesystem::path(s.file).parent_path()};

  // Version and units first: everything else depends on them.
  if (s.version.set && s.version.v != 1 && s.version.v != 1.1) {
    d.add(s.version.loc, "magbake",
          "unsupported scene format version " + std::to_string(s.version.v).substr(0, 6) +
              "; this magbake reads versions 1 and 1.1");
  }
  if (s.length_unit.set) {
    sc.length_unit = s.length_unit.v;
    if (s.length_unit.v == "m") c.L = 1;
    else if (s.length_unit.v == "cm") c.L = 0.01;
    else if (s.length_unit.v == "mm") c.L = 0.001;
    else d.add(s.length_unit.loc, "units.length", "expected m, cm or mm, got '" + s.length_unit.v + "'");
  }
  if (s.angle_unit.set) {
    sc.angle_unit = s.angle_unit.v;
    if (s.angle_unit.v == "deg") c.A = kPi / 180;
    else if (s.angle_unit.v == "rad") c.A = 1;
    else d.add(s.angle_unit.loc, "units.angle", "expected deg or rad, got '" + s.angle_unit.v + "'");
  }
  sc.name = s.name.set ? s.name.v : std::filesystem::path(s.file).stem().string();
  if (s.name.set) {
    if (const auto e = scene_name_error(s.name.v)) d.add(s.name.loc, "name", *e);
  }

  // Time.
  if (s.fps.set && positive(c, s.fps, "time.fps", "frame rate")) {
    if (!(s.fps.v >= 1e-3 && s.fps.v <= 1e5)) d.add(s.fps.loc, "time.fps", "out of range: from 0.001 to 100000 frames per second");
    else sc.fps = s.fps.v;
  }
  if (s.frames.set) {
    const double a = s.frames.v[0], b = s.frames.v[1];
    if (a != std::floor(a) || b != std::floor(b)) {
      d.add(s.frames.loc, "time.frames", "frame numbers must be integers");
    } else if (!(std::abs(a) <= kMaxFrame && std::abs(b) <= kMaxFrame)) {
      d.add(s.frames.loc, "time.frames", "frame numbers must be within +-100000000");
    } else if (b - a + 1 > kMaxFrames) {
      d.add(s.frames.loc, "time.frames", "more than 1000000 frames in one shot; split it into several bakes");
    } else if (b < a) {
      d.add(s.frames.loc, "time.frames",
            "frame range reversed: [" + std::to_string(int(a)) + ", " + std::to_string(int(b)) + "]; give [first, last]");
    } else {
      sc.first_frame = int(a), sc.last_frame = int(b);
    }
  }
  sc.dt = std::min(1.0 / 600.0, 1.0 / sc.fps);
  if (s.dt.set) {
    if (!(s.dt.v > 0)) {
      d.add(s.dt.loc, "time.dt", "the physics substep must be positive, got " + std::to_string(s.dt.v));
    } else if (s.dt.v > 1.0 / sc.fps + 1e-15) {
      d.add(s.dt.loc, "time.dt", "the physics substep must not exceed the frame interval 1/fps");
    } else if (1.0 / (sc.fps * s.dt.v) > kMaxStepsPerFrame) {
      d.add(s.dt.loc, "time.dt", "more than 1000000 physics substeps per frame: dt must be at least 1e-6 / fps");
    } else {
      sc.dt = s.dt.v;
    }
  }
  if (s.sleep.set) {
    if (!(s.sleep.v >= 0 && s.sleep.v <= 1e6)) {
      d.add(s.sleep.loc, "time.sleep", "seconds at rest before a body sleeps: from 0 (never) to 1000000");
    } else {
      sc.sleep_time = s.sleep.v;
    }
  }
  if (s.gravity.set && within(c, s.gravity, "gravity", kMaxAcceleration, c.L, "m/s²")) sc.gravity = vec3(s.gravity, c.L);

  // Magnetics settings and presets.
  auto& mg = sc.magnetics;
  if (s.quality.set) {
    if (!apply_quality_preset(s.quality.v, mg)) {
      d.add(s.quality.loc, "magnetics.quality", "expected draft, default or high, got '" + s.quality.v + "'");
    }
  }
  if (s.cell_size.set && length(c, s.cell_size, "magnetics.cell_size")) mg.cell_size = s.cell_size.v * c.L;
  if (s.theta.set) {
    if (!(s.theta.v >= 0 && s.theta.v <= 1)) d.add(s.theta.loc, "magnetics.theta", "must be in [0, 1]");
    else mg.theta = s.theta.v;
  }
  if (s.induction.set) {
    if (s.induction.v != "coupled" && s.induction.v != "paper" && s.induction.v != "off") {
      d.add(s.induction.loc, "magnetics.induction", "expected coupled, paper or off, got '" + s.induction.v + "'");
    } else {
      mg.induction = s.induction.v;
    }
  }
  if (s.induction_tolerance.set) {
    if (!(s.induction_tolerance.v >= 1e-12 && s.induction_tolerance.v <= 0.1)) {
      d.add(s.induction_tolerance.loc, "magnetics.induction_tolerance", "must be in [1e-12, 0.1]");
    } else {
      mg.induction_tolerance = s.induction_tolerance.v;
    }
  }
  if (s.surface_tolerance.set) {
    // 0 turns surfaces off; otherwise a length from 0.1 um to 1 mm (coarser is no surface at all).
    if (s.surface_tolerance.v == 0) {
      mg.surface_tolerance = 0;
    } else if (!(s.surface_tolerance.v * c.L >= 1e-7 && s.surface_tolerance.v * c.L <= 1e-3)) {
      d.add(s.surface_tolerance.loc, "magnetics.surface_tolerance", "must be 0 (off) or from 1e-7 to 1e-3 m");
    } else {
      mg.surface_tolerance = s.surface_tolerance.v * c.L;
    }
  }
  if (s.grading.set) {
    if (!(s.grading.v == 0 || s.grading.v == 1 || s.grading.v == 2 || s.grading.v == 3)) {
      d.add(s.grading.loc, "magnetics.grading", "must be 0 (uniform cells), 1, 2 or 3 (levels of finer cells at soft surfaces)");
    } else {
      mg.grading = static_cast<int>(s.grading.v);
    }
  }
  if (s.soft_cells_across.set) {
    const double v = s.soft_cells_across.v;
    if (!(v >= 1 && v <= 64 && v == std::floor(v))) {
      d.add(s.soft_cells_across.loc, "magnetics.soft_cells_across", "must be a whole number from 1 to 64 (cells across a soft part's smallest extent)");
    } else {
      mg.soft_cells_per_extent = static_cast<int>(v);
    }
  }
  if (s.external_field.set && within(c, s.external_field, "magnetics.external_field", kMaxFieldTesla, 1, "T")) {
    mg.external_field = vec3(s.external_field);
  }
  {
    double last_t = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < s.external_field_keys.size(); ++k) {
      const auto& ks = s.external_field_keys[k];
      const std::string kp = "magnetics.external_field[" + std::to_string(k) + "]";
      if (!ks.t.set || !ks.B.set) continue;
      if (!within(c, ks.t, kp + ".t", 1e9, 1, "s") || !within(c, ks.B, kp + ".B", kMaxFieldTesla, 1, "T")) continue;
      if (!(ks.t.v > last_t)) {
        d.add(ks.t.loc, kp + ".t", "keys out of time order: t = " + std::to_string(ks.t.v) +
                                       " does not come after the previous key's t = " + std::to_string(last_t));
      }
      last_t = ks.t.v;
      mg.external_field_keys.emplace_back(ks.t.v, vec3(ks.B));
    }
    if (!mg.external_field_keys.empty()) mg.external_field = mg.external_field_keys.front().second;
  }
  if (s.rotating_set && s.rotating_magnitude.set && s.rotating_frequency.set) {
    const std::string rp = "magnetics.external_field.rotating";
    MagneticsSettings::RotatingField rot;
    bool ok = within(c, s.rotating_magnitude, rp + ".magnitude", kMaxFieldTesla, 1, "T") &&
              within(c, s.rotating_frequency, rp + ".frequency", 1e6, 1, "Hz");
    if (ok && !(s.rotating_magnitude.v >= 0)) {
      d.add(s.rotating_magnitude.loc, rp + ".magnitude", "must be >= 0 (tesla)");
      ok = false;
    }
    rot.magnitude = s.rotating_magnitude.v, rot.frequency = s.rotating_frequency.v;
    if (s.rotating_axis.set) {
      if (auto a = direction(c, s.rotating_axis, rp + ".axis")) rot.axis = *a;
      else ok = false;
    }
    // `from`: its part normal to the axis; default x (or y if the axis is along x).
    const Vec3 from = s.rotating_from.set ? vec3(s.rotating_from) : (std::abs(rot.axis.x()) > 0.9 ? Vec3::UnitY() : Vec3::UnitX());
    const Vec3 normal = from - from.dot(rot.axis) * rot.axis;
    if (normal.norm() < 1e-9 * std::max(1.0, from.norm())) {
      d.add(s.rotating_from.set ? s.rotating_from.loc : s.rotating_loc, rp + ".from",
            "must not be along the axis: it is where the field points at t = 0, normal to the axis");
      ok = false;
    } else {
      rot.from = normal.normalized();
    }
    if (ok) {
      mg.rotating_field = rot;
      mg.external_field = rot.magnitude * rot.from;
    }
  }

  // Format 1.1 surface and look keys, shared by materials and bodies.
  auto friction = [&](const Val<double>& v, const std::string& path) -> std::optional<double> {
    if (v.v >= 0 && v.v <= 100) return v.v;
    d.add(v.loc, path, "must be in [0, 100]");
    return std::nullopt;
  };
  auto restitution = [&](const Val<double>& v, const std::string& path) -> std::optional<double> {
    if (v.v >= 0 && v.v <= 1) return v.v;
    d.add(v.loc, path, "must be in [0, 1]");
    return std::nullopt;
  };
  auto damping = [&](const DampingSpec& ds, const std::string& path, std::optional<double>& linear,
                     std::optional<double>& angular) {
    if (!ds.set) return;
    for (auto [v, out, name] : {std::tuple{&ds.linear, &linear, "linear"}, std::tuple{&ds.angular, &angular, "angular"}}) {
      if (!v->set) continue;
      if (v->v >= 0 && v->v < 1) *out = v->v;
      else d.add(v->loc, path + ".damping." + name, "must be in [0, 1): the share of the velocity lost per second");
    }
  };
  auto color = [&](const Val<Vec>& v, const std::string& path) -> std::optional<Vec3> {
    if (v.v.size() != 3) return std::nullopt;  // the parser reported it
    for (double x : v.v) {
      if (!(x >= 0 && x <= 1)) {
        d.add(v.loc, path, "expected [r, g, b] with each in [0, 1]");
        return std::nullopt;
      }
    }
    return Vec3(v.v[0], v.v[1], v.v[2]);
  };

  // Materials.
  std::vector<std::string> material_names;
  for (const MaterialSpecS& ms : s.materials) {
    if (std::find(material_names.begin(), material_names.end(), ms.name) != material_names.end()) continue;
    Material m;
    m.name = ms.name;
    const std::string mp = "materials." + ms.name;
    if (ms.kind.set) {
      m.kind_name = ms.kind.v;
      if (ms.kind.v == "permanent") {
        m.kind = magnetics::MaterialKind::kPermanent;
        if (!ms.remanence.set) d.add(ms.loc, mp, "a permanent material needs its remanence (tesla)");
        else if (positive(c, ms.remanence, mp + ".remanence", "remanence in tesla") &&
                 within(c, ms.remanence, mp + ".remanence", kMaxFieldTesla, 1, "T")) {
          m.remanence = ms.remanence.v;
        }
      } else if (ms.kind.v == "soft" || ms.kind.v == "linear") {
        m.kind = magnetics::MaterialKind::kLinear;
        if (!ms.chi.set) {
          d.add(ms.loc, mp, "a " + ms.kind.v + " material needs its susceptibility chi");
        } else if (!(ms.chi.v > -1)) {
          d.add(ms.chi.loc, mp + ".chi", "chi must be greater than -1 (use kind: superconductor for chi = -1)");
        } else if (within(c, ms.chi, mp + ".chi", kMaxSusceptibility, 1, "")) {
          m.chi = ms.chi.v;
        }
      } else if (ms.kind.v == "superconductor") {
        m.kind = magnetics::MaterialKind::kSuperconductor;
        m.chi = -1;
      } else if (ms.kind.v == "none") {
        m.kind = magnetics::MaterialKind::kNone;
      } else {
        const std::string guess = did_you_mean(ms.kind.v, {"permanent", "soft", "linear", "superconductor", "none"});
        d.add(ms.kind.loc, mp + ".kind",
              "unknown material kind '" + ms.kind.v + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)"));
      }
      if (ms.remanence.set && m.kind != magnetics::MaterialKind::kPermanent) {
        d.add(ms.remanence.loc, mp + ".remanence", "only permanent materials have a remanence");
      }
      if (ms.chi.set && m.kind != magnetics::MaterialKind::kLinear) {
        d.add(ms.chi.loc, mp + ".chi", "only soft and linear materials have a susceptibility");
      }
      if (ms.saturation.set) {
        if (m.kind != magnetics::MaterialKind::kLinear) {
          d.add(ms.saturation.loc, mp + ".saturation", "only soft and linear materials saturate");
        } else if (ms.chi.set && !(ms.chi.v > 0)) {
          d.add(ms.saturation.loc, mp + ".saturation", "only a material with chi > 0 saturates");
        } else if (sc.magnetics.induction == "paper") {
          d.add(ms.saturation.loc, mp + ".saturation",
                "saturation needs magnetics.induction: coupled (the paper's one-pass induction is linear)");
        } else if (positive(c, ms.saturation, mp + ".saturation", "saturation polarization in tesla") &&
                   within(c, ms.saturation, mp + ".saturation", kMaxFieldTesla, 1, "T")) {
          m.saturation = ms.saturation.v;
        }
      }
    }
    if (ms.density.set && positive(c, ms.density, mp + ".density", "density in kg/m³") &&
        within(c, ms.density, mp + ".density", kMaxDensity, 1, "kg/m³")) {
      m.density = ms.density.v;
    }
    if (ms.friction.set) m.friction = friction(ms.friction, mp + ".friction");
    if (ms.restitution.set) m.restitution = restitution(ms.restitution, mp + ".restitution");
    damping(ms.damping, mp, m.linear_damping, m.angular_damping);
    if (ms.color.set) m.color = color(ms.color, mp + ".color");
    material_names.push_back(m.name);
    sc.materials.push_back(m);
  }
  auto find_material = [&](const Val<std::string>& v, const std::string& path) {
    if (!v.set) return -1;
    for (std::size_t i = 0; i < sc.materials.size(); ++i) {
      if (sc.materials[i].name == v.v) return static_cast<int>(i);
    }
    const std::string guess = did_you_mean(v.v, material_names);
    d.add(v.loc, path, "unknown material '" + v.v + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)"));
    return -1;
  };
  auto check_magnetization = [&](int mat, const Val<Vec>& v, Loc where, const std::string& path, Vec3& out) {
    if (mat < 0) return;
    const bool permanent = sc.materials[mat].kind == magnetics::MaterialKind::kPermanent;
    if (permanent && !v.set) {
      d.add(where, path, "permanent material '" + sc.materials[mat].name +
                             "' needs a magnetization direction: add magnetization: [x, y, z] (body frame)");
    } else if (!permanent && v.set) {
      d.add(v.loc, path + ".magnetization", "only permanent materials have a magnetization direction");
    } else if (permanent) {
      if (auto dir = direction(c, v, path + ".magnetization")) out = *dir;
    }
  };

  // Bodies.
  std::set<std::string> names;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const BodySpecS& bs = s.bodies[i];
    const std::string bp = "bodies[" + std::to_string(i) + "]";
    Body b;
    if (bs.name.set) {
      b.name = bs.name.v;
      if (!names.insert(b.name).second) d.add(bs.name.loc, bp + ".name", "two bodies are named '" + b.name + "'");
    }
    if (!bs.shape.kind.empty()) b.shape = shape(c, bs.shape, bp + ".shape");
    b.material = find_material(bs.material, bp + ".material");
    check_magnetization(b.material, bs.magnetization, bs.loc, bp, b.magnetization);
    if (bs.position.set && within(c, bs.position, bp + ".position", kMaxCoordinate, c.L, "m")) {
      b.pose.position = vec3(bs.position, c.L);
    }
    if (auto q = orientation(c, bs.orientation, bp)) b.pose.rotation = *q;
    if (bs.motion.set) {
      if (bs.motion.v == "dynamic") b.motion = Motion::kDynamic;
      else if (bs.motion.v == "static") b.motion = Motion::kStatic;
      else if (bs.motion.v == "kinematic") b.motion = Motion::kKinematic;
      else d.add(bs.motion.loc, bp + ".motion", "expected dynamic, static or kinematic, got '" + bs.motion.v + "'");
    }
    // Surface, damping and colour: the body's key, else its material's, else the defaults.
    {
      const Material* m = b.material >= 0 ? &sc.materials[b.material] : nullptr;
      if (bs.friction.set) b.friction = friction(bs.friction, bp + ".friction").value_or(b.friction);
      else if (m && m->friction) b.friction = *m->friction;
      if (bs.restitution.set) b.restitution = restitution(bs.restitution, bp + ".restitution").value_or(b.restitution);
      else if (m && m->restitution) b.restitution = *m->restitution;
      std::optional<double> linear, angular;
      damping(bs.damping, bp, linear, angular);
      b.linear_damping = linear.value_or(m && m->linear_damping ? *m->linear_damping : 0.0);
      b.angular_damping = angular.value_or(m && m->angular_damping ? *m->angular_damping : 0.0);
      if (bs.color.set) b.color = color(bs.color, bp + ".color");
      else if (m) b.color = m->color;
    }
    if (bs.velocity.set && within(c, bs.velocity, bp + ".velocity", kMaxSpeed, c.L, "m/s")) {
      b.velocity = vec3(bs.velocity, c.L);
    }
    if (bs.angular_velocity.set && within(c, bs.angular_velocity, bp + ".angular_velocity", kMaxSpin, c.A, "rad/s")) {
      b.angular_velocity = vec3(bs.angular_velocity, c.A);
    }
    // Keys.
    if (!bs.keys.empty() && b.motion != Motion::kKinematic) {
      d.add(bs.keys_loc, bp + ".keys", "only kinematic bodies have keys (add motion: kinematic)");
    }
    double last_t = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < bs.keys.size(); ++k) {
      const KeySpec& ks = bs.keys[k];
      const std::string kp = bp + ".keys[" + std::to_string(k) + "]";
      if (!ks.t.set) continue;
      if (!within(c, ks.t, kp + ".t", 1e9, 1, "s")) continue;
      within(c, ks.position, kp + ".position", kMaxCoordinate, c.L, "m");
      if (!(ks.t.v > last_t)) {
        d.add(ks.t.loc, kp + ".t", "keys out of time order: t = " + std::to_string(ks.t.v) +
                                       " does not come after the previous key's t = " + std::to_string(last_t));
      }
      last_t = ks.t.v;
      Key key;
      key.t = ks.t.v;
      if (ks.position.set) key.position = vec3(ks.position, c.L);
      key.orientation = orientation(c, ks.orientation, kp);
      b.keys.push_back(key);
    }
    // Parts.
    for (std::size_t j = 0; j < bs.parts.size(); ++j) {
      const PartSpecS& ps = bs.parts[j];
      const std::string pp = bp + ".parts[" + std::to_string(j) + "]";
      Part p;
      if (!ps.shape.kind.empty()) p.shape = shape(c, ps.shape, pp + ".shape");
      if (ps.position.set && within(c, ps.position, pp + ".position", kMaxLength, c.L, "m")) {
        p.pose.position = vec3(ps.position, c.L);
      }
      if (auto q = orientation(c, ps.orientation, pp)) p.pose.rotation = *q;
      p.material = find_material(ps.material, pp + ".material");
      check_magnetization(p.material, ps.magnetization, ps.loc, pp, p.magnetization);
      b.parts.push_back(std::move(p));
    }
    // Mass: the body's own shape with the body's mass or density, else the material's density.
    if (bs.density.set && bs.mass.set) d.add(bs.mass.loc, bp, "give density or mass, not both");
    if (b.shape.shape) {
      const geometry::MassProperties mp = b.shape.shape->mass_properties();
      std::optional<double> density;
      if (bs.density.set && positive(c, bs.density, bp + ".density", "density in kg/m³") &&
          within(c, bs.density, bp + ".density", kMaxDensity, 1, "kg/m³")) {
        density = bs.density.v;
      }
      if (bs.mass.set && positive(c, bs.mass, bp + ".mass", "mass in kg") && within(c, bs.mass, bp + ".mass", 1e12, 1, "kg")) {
        density = bs.mass.v / mp.volume;
      }
      if (!density && b.material >= 0) density = sc.materials[b.material].density;
      if (density) {
        b.mass = *density * mp.volume;
        b.inertia = *density * mp.inertia;
      } else if (b.motion == Motion::kDynamic) {
        d.add(bs.loc, bp, "a dynamic body needs a mass: give mass, density, or a density for its material");
      }
      b.com = mp.centroid;
    }
    sc.bodies.push_back(std::move(b));
  }

  // Joints (format 1.1): frames from the initial poses.
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    const JointSpec& js = s.joints[i];
    const std::string jp = "joints[" + std::to_string(i) + "]";
    Joint j;
    j.name = js.name.set ? js.name.v : "joint " + std::to_string(i);
    bool ok = true;
    if (js.type.set) {
      j.type_name = js.type.v;
      if (js.type.v == "hinge") j.type = JointType::kHinge;
      else if (js.type.v == "ball") j.type = JointType::kBall;
      else if (js.type.v == "fixed") j.type = JointType::kFixed;
      else if (js.type.v == "slider") j.type = JointType::kSlider;
      else {
        const std::string guess = did_you_mean(js.type.v, {"hinge", "ball", "fixed", "slider"});
        d.add(js.type.loc, jp + ".type",
              "unknown joint type '" + js.type.v + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)") +
                  "; expected hinge, ball, fixed or slider");
        ok = false;
      }
    }
    int ends[2] = {-1, -1};
    if (js.bodies.set) {
      for (std::size_t k = 0; k < js.bodies.v.size(); ++k) {
        const std::string& name = js.bodies.v[k];
        if (k == 1 && name == "world") continue;
        const int idx = sc.body_index(name);
        if (idx < 0) {
          std::vector<std::string> all;
          for (const Body& b : sc.bodies) all.push_back(b.name);
          const std::string guess = did_you_mean(name, all);
          d.add(js.bodies.loc, jp + ".bodies",
                "unknown body '" + name + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)"));
          ok = false;
        }
        ends[k] = idx;
      }
      if (ok && ends[0] == ends[1]) {
        d.add(js.bodies.loc, jp + ".bodies", "a joint needs two different bodies (or one and the world)");
        ok = false;
      }
      if (ok) {
        const bool dyn0 = sc.bodies[ends[0]].motion == Motion::kDynamic;
        const bool dyn1 = ends[1] >= 0 && sc.bodies[ends[1]].motion == Motion::kDynamic;
        if (!dyn0 && !dyn1) {
          d.add(js.bodies.loc, jp + ".bodies", "a joint holds a dynamic body; these are static or kinematic");
          ok = false;
        }
      }
    }
    const bool axial = j.type == JointType::kHinge || j.type == JointType::kSlider;
    if (js.type.set && ok && axial && !js.axis.set) d.add(js.loc, jp, "a " + j.type_name + " joint needs its axis: [x, y, z] (world)");
    if (js.axis.set && !axial && js.type.set) d.add(js.axis.loc, jp + ".axis", "only hinge and slider joints have an axis");
    if (js.type.set && (j.type == JointType::kHinge || j.type == JointType::kBall) && !js.pivot.set) {
      d.add(js.loc, jp, "a " + j.type_name + " joint needs its pivot: [x, y, z] (world, at the start)");
    }
    if (js.limits.set) {
      const double scale = j.type == JointType::kHinge ? c.A : c.L;
      if (!axial) {
        d.add(js.limits.loc, jp + ".limits", "only hinge (angles) and slider (lengths) joints have limits");
      } else if (!within(c, js.limits, jp + ".limits", 1e6, 1, "")) {
      } else if (!(js.limits.v[0] <= 0 && js.limits.v[1] >= 0)) {
        d.add(js.limits.loc, jp + ".limits",
              "expected [lower, upper] with lower <= 0 <= upper: limits count from where the bodies start");
      } else if (j.type == JointType::kHinge && (js.limits.v[0] * c.A < -kPi || js.limits.v[1] * c.A > kPi)) {
        d.add(js.limits.loc, jp + ".limits", "a hinge's limits lie within [-180, 180] degrees");
      } else {
        j.limits = std::pair{js.limits.v[0] * scale, js.limits.v[1] * scale};
      }
    }
    std::optional<Vec3> pivot, axis;
    if (js.pivot.set && within(c, js.pivot, jp + ".pivot", kMaxCoordinate, c.L, "m")) pivot = vec3(js.pivot, c.L);
    if (js.axis.set) axis = direction(c, js.axis, jp + ".axis");
    if (!ok || !js.type.set || !js.bodies.set) continue;
    // The joint frame in the world at t = 0: origin at the pivot (body a's origin if none is
    // given), z along the axis (any frame for a ball or fixed joint).
    const Pose pa = sc.bodies[ends[0]].pose_at(0.0);
    Pose world{Quat::Identity(), pivot.value_or(pa.position)};
    if (axis) world.rotation = Quat::FromTwoVectors(Vec3::UnitZ(), *axis);
    auto in_body = [&](int b) {
      if (b < 0) return world;
      const Pose p = sc.bodies[b].pose_at(0.0);
      const Quat inv = p.rotation.conjugate();
      return Pose{(inv * world.rotation).normalized(), inv * (world.position - p.position)};
    };
    j.a = ends[0], j.b = ends[1];
    j.frame_a = in_body(j.a);
    j.frame_b = in_body(j.b);
    sc.joints.push_back(j);
  }

  // Outputs.
  if (s.cache.set) {
    // Absolute paths pass here; the command refuses them unless --allow-absolute-outputs.
    if (const auto e = output_path_error(s.cache.v, true)) d.add(s.cache.loc, "outputs.cache", *e);
    else sc.cache = s.cache.v;
  }
  if (s.usd.set) {
    if (const auto e = output_path_error(s.usd.v, true)) {
      d.add(s.usd.loc, "outputs.usd", *e);
    } else if (const std::string ext = std::filesystem::path(s.usd.v).extension().string();
               ext != ".usda" && ext != ".usdc" && ext != ".usd") {
      d.add(s.usd.loc, "outputs.usd", "expected a .usda (text), .usdc or .usd (binary) file, got '" + s.usd.v + "'");
    } else {
      sc.usd = s.usd.v;
    }
  }
  read_outputs(s, c.L, c.A, d, sc.field, sc.preview);
  return sc;
}

std::string outputs_of_text(const std::string& text, std::optional<FieldOutput>& field,
                            std::optional<PreviewOutput>& preview) {
  Diagnostics d("scene");
  const SceneSpec s = parse_scene_text(text, "scene", d);
  double L = 1, A = 1;
  if (s.length_unit.v == "cm") L = 0.01;
  if (s.length_unit.v == "mm") L = 0.001;
  if (s.angle_unit.v == "deg") A = kPi / 180;
  Diagnostics outputs("scene");
  read_outputs(s, L, A, outputs, field, preview);
  if (outputs.empty()) return "";
  // A stored pattern or path that would not validate today is never used.
  field.reset(), preview.reset();
  return outputs.format();
}

Scene load_scene_text(const std::string& text, const std::string& file) {
  Diagnostics d(file);
  const SceneSpec spec = parse_scene_text(text, file, d);
  if (!d.empty()) throw SceneError(d);
  Scene s = validate_scene(spec, d);
  if (!d.empty()) throw SceneError(d);
  return s;
}

Scene load_scene(const std::string& path) {
  Diagnostics d(path);
  const SceneSpec spec = parse_scene_file(path, d);
  if (!d.empty()) throw SceneError(d);
  Scene s = validate_scene(spec, d);
  if (!d.empty()) throw SceneError(d);
  return s;
}

}  // namespace magbake::scene
