// YAML -> SceneSpec. Reads through const nodes only (yaml-cpp's non-const operator[] inserts
// missing keys), reports 1-based positions (yaml-cpp's are 0-based) and detects duplicate keys
// (yaml-cpp accepts them silently).
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "spec.h"

namespace magbake::scene {
namespace {

Loc loc_of(const YAML::Node& n) {
  if (!n.IsDefined()) return {};
  const YAML::Mark m = n.Mark();
  if (m.line < 0) return {};
  return {m.line + 1, m.column + 1};
}

std::string show(const YAML::Node& n) {
  if (!n.IsDefined()) return "nothing";
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a mapping";
  return "nothing";
}

class Reader {
 public:
  explicit Reader(Diagnostics& d) : d_(d) {}

  // Checks that `n` is a mapping whose keys are all in `allowed` (no duplicates) and that every
  // key in `required` is present. Returns false if `n` is not a mapping.
  bool mapping(const YAML::Node& n, const std::string& path, const std::vector<std::string>& allowed,
               const std::vector<std::string>& required, Loc parent) {
    if (!n.IsDefined() || !n.IsMap()) {
      d_.add(n.IsDefined() ? loc_of(n) : parent, path, "expected a mapping, got " + show(n));
      return false;
    }
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      const std::string kp = path.empty() ? key : path + "." + key;
      if (!seen.insert(key).second) {
        d_.add(loc_of(kv.first), kp, "duplicate key '" + key + "'");
        continue;
      }
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        const std::string guess = did_you_mean(key, allowed);
        d_.add(loc_of(kv.first), kp,
               "unknown key '" + key + "'" + (guess.empty() ? "" : " (did you mean '" + guess + "'?)"));
      }
    }
    for (const std::string& r : required) {
      if (!seen.count(r)) d_.add(loc_of(n), path, "missing required key '" + r + "'");
    }
    return true;
  }

  // Checks that `n` is a mapping of free names (no duplicates).
  bool names(const YAML::Node& n, const std::string& path, Loc parent) {
    if (!n.IsDefined() || !n.IsMap()) {
      d_.add(n.IsDefined() ? loc_of(n) : parent, path, "expected a mapping of names, got " + show(n));
      return false;
    }
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      if (!seen.insert(key).second) d_.add(loc_of(kv.first), path + "." + key, "duplicate key '" + key + "'");
    }
    return true;
  }

  Val<double> number(const YAML::Node& map, const char* key, const std::string& path) {
    Val<double> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined()) return out;
    out.loc = loc_of(n);
    const std::string kp = join(path, key);
    if (!n.IsScalar() || !as_double(n, out.v)) {
      d_.add(out.loc, kp, "expected a number, got " + show(n));
      return out;
    }
    out.set = true;
    return out;
  }

  Val<std::string> text(const YAML::Node& map, const char* key, const std::string& path) {
    Val<std::string> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined()) return out;
    out.loc = loc_of(n);
    if (!n.IsScalar()) {
      d_.add(out.loc, join(path, key), "expected a string, got " + show(n));
      return out;
    }
    out.v = n.Scalar();
    out.set = true;
    return out;
  }

  Val<bool> boolean(const YAML::Node& map, const char* key, const std::string& path) {
    Val<bool> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined()) return out;
    out.loc = loc_of(n);
    bool b = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, b)) {
      d_.add(out.loc, join(path, key), "expected true or false, got " + show(n));
      return out;
    }
    out.v = b;
    out.set = true;
    return out;
  }

  // A list of `count` numbers (count 0: any length).
  Val<Vec> vector(const YAML::Node& map, const char* key, const std::string& path, std::size_t count) {
    Val<Vec> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined()) return out;
    out.loc = loc_of(n);
    read_vector(n, join(path, key), count, out);
    return out;
  }

  void read_vector(const YAML::Node& n, const std::string& kp, std::size_t count, Val<Vec>& out) {
    const std::string want = count ? "a list of " + std::to_string(count) + " numbers" : "a list of numbers";
    if (!n.IsSequence()) {
      d_.add(loc_of(n), kp, "expected " + want + ", got " + show(n));
      return;
    }
    for (const auto& e : n) {
      double x;
      if (!e.IsScalar() || !as_double(e, x)) {
        d_.add(loc_of(e), kp, "expected " + want + ", got " + show(e) + " in it");
        return;
      }
      out.v.push_back(x);
    }
    if (count && out.v.size() != count) {
      d_.add(loc_of(n), kp, "expected " + want + ", got " + std::to_string(out.v.size()));
      out.v.clear();
      return;
    }
    out.set = true;
  }

  // A list of 1 to `most` strings.
  Val<std::vector<std::string>> strings(const YAML::Node& map, const char* key, const std::string& path, std::size_t most) {
    Val<std::vector<std::string>> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined()) return out;
    out.loc = loc_of(n);
    const std::string kp = join(path, key);
    const std::string want = "a list of 1 to " + std::to_string(most) + " names";
    if (!n.IsSequence() || n.size() == 0 || n.size() > most) {
      d_.add(out.loc, kp, "expected " + want + ", got " + show(n));
      return out;
    }
    for (const auto& e : n) {
      if (!e.IsScalar()) {
        d_.add(loc_of(e), kp, "expected " + want + ", got " + show(e) + " in it");
        return out;
      }
      out.v.push_back(e.Scalar());
    }
    out.set = true;
    return out;
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

  Diagnostics& diag() { return d_; }

 private:
  static bool as_double(const YAML::Node& n, double& x) {
    // YAML 1.2 core numbers; booleans and strings are not numbers.
    const std::string& s = n.Scalar();
    if (s.empty()) return false;
    std::istringstream is(s);
    is.imbue(std::locale::classic());
    is >> x;
    return !is.fail() && is.eof();
  }
  Diagnostics& d_;
};

void read_shape(Reader& r, const YAML::Node& n, const std::string& path, Loc parent, ShapeSpec& s) {
  s.loc = n.IsDefined() ? loc_of(n) : parent;
  static const std::vector<std::string> kinds{"box", "sphere", "cylinder", "torus", "mesh"};
  if (!r.mapping(n, path, kinds, {}, parent)) return;
  if (n.size() != 1) {
    r.diag().add(s.loc, path, "expected exactly one of box, sphere, cylinder, torus, mesh");
    return;
  }
  const auto kv = *n.begin();
  s.kind = kv.first.Scalar();
  s.kind_loc = loc_of(kv.first);
  const YAML::Node& v = kv.second;
  const std::string kp = path + "." + s.kind;
  if (s.kind == "box") {
    s.size.loc = loc_of(v);
    r.read_vector(v, kp, 3, s.size);
  } else if (s.kind == "sphere") {
    if (r.mapping(v, kp, {"radius"}, {"radius"}, s.kind_loc)) s.radius = r.number(v, "radius", kp);
  } else if (s.kind == "cylinder") {
    if (r.mapping(v, kp, {"radius", "height"}, {"radius", "height"}, s.kind_loc)) {
      s.radius = r.number(v, "radius", kp);
      s.height = r.number(v, "height", kp);
    }
  } else if (s.kind == "torus") {
    if (r.mapping(v, kp, {"major", "minor"}, {"major", "minor"}, s.kind_loc)) {
      s.major = r.number(v, "major", kp);
      s.minor = r.number(v, "minor", kp);
    }
  } else if (s.kind == "mesh") {
    if (r.mapping(v, kp, {"file", "scale"}, {"file"}, s.kind_loc)) {
      s.file = r.text(v, "file", kp);
      s.scale = r.number(v, "scale", kp);
    }
  } else {
    s.kind.clear();  // reported as an unknown key by mapping()
  }
}

void read_orientation(Reader& r, const YAML::Node& map, const std::string& path, OrientationSpec& o) {
  const YAML::Node n = map["orientation"];
  if (!n.IsDefined()) return;
  const std::string kp = Reader::join(path, "orientation");
  o.set = true;
  o.loc = loc_of(n);
  if (!r.mapping(n, kp, {"axis", "angle", "quat"}, {}, o.loc)) return;
  o.axis = r.vector(n, "axis", kp, 3);
  o.angle = r.number(n, "angle", kp);
  o.quat = r.vector(n, "quat", kp, 4);
  const bool aa = n["axis"].IsDefined() || n["angle"].IsDefined();
  if (aa && n["quat"].IsDefined()) {
    r.diag().add(o.loc, kp, "give either {axis, angle} or {quat}, not both");
  } else if (!aa && !n["quat"].IsDefined()) {
    r.diag().add(o.loc, kp, "expected {axis: [x, y, z], angle: a} or {quat: [w, x, y, z]}");
  } else if (aa && !(n["axis"].IsDefined() && n["angle"].IsDefined())) {
    r.diag().add(o.loc, kp, std::string("missing required key '") + (n["axis"].IsDefined() ? "angle" : "axis") + "'");
  }
}

// `damping: {linear: d, angular: d}` on a body or material (format 1.1).
void read_damping(Reader& r, const YAML::Node& map, const std::string& path, DampingSpec& out) {
  const YAML::Node n = map["damping"];
  if (!n.IsDefined()) return;
  const std::string kp = Reader::join(path, "damping");
  out.set = true;
  out.loc = loc_of(n);
  if (!r.mapping(n, kp, {"linear", "angular"}, {}, out.loc)) return;
  out.linear = r.number(n, "linear", kp);
  out.angular = r.number(n, "angular", kp);
}

}  // namespace

SceneSpec parse_scene_text(const std::string& text, const std::string& file, Diagnostics& d) {
  SceneSpec s;
  s.file = file;
  s.text = text;
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    d.add({e.mark.line + 1, e.mark.column + 1}, "", "YAML syntax error: " + e.msg);
    return s;
  }
  Reader r(d);
  const YAML::Node& c = root;
  s.root = {1, 1};
  if (!r.mapping(c, "", {"magbake", "name", "units", "time", "gravity", "magnetics", "materials", "bodies", "joints", "outputs"},
                 {"magbake", "units"}, s.root)) {
    return s;
  }
  s.version = r.number(c, "magbake", "");
  s.name = r.text(c, "name", "");

  if (const YAML::Node u = c["units"]; u.IsDefined()) {
    s.units_loc = loc_of(u);
    if (r.mapping(u, "units", {"length", "angle"}, {"length", "angle"}, s.units_loc)) {
      s.length_unit = r.text(u, "length", "units");
      s.angle_unit = r.text(u, "angle", "units");
    }
  }
  if (const YAML::Node t = c["time"]; t.IsDefined()) {
    s.time_loc = loc_of(t);
    if (r.mapping(t, "time", {"fps", "frames", "dt", "sleep"}, {}, s.time_loc)) {
      s.fps = r.number(t, "fps", "time");
      s.frames = r.vector(t, "frames", "time", 2);
      s.dt = r.number(t, "dt", "time");
      s.sleep = r.number(t, "sleep", "time");
    }
  }
  s.gravity = r.vector(c, "gravity", "", 3);
  if (const YAML::Node m = c["magnetics"]; m.IsDefined()) {
    s.magnetics_loc = loc_of(m);
    if (r.mapping(m, "magnetics", {"quality", "cell_size", "theta", "induction", "induction_tolerance", "surface_tolerance", "grading", "soft_cells_across", "external_field"}, {}, s.magnetics_loc)) {
      s.quality = r.text(m, "quality", "magnetics");
      s.cell_size = r.number(m, "cell_size", "magnetics");
      s.theta = r.number(m, "theta", "magnetics");
      s.induction = r.text(m, "induction", "magnetics");
      s.induction_tolerance = r.number(m, "induction_tolerance", "magnetics");
      s.surface_tolerance = r.number(m, "surface_tolerance", "magnetics");
      s.grading = r.number(m, "grading", "magnetics");
      s.soft_cells_across = r.number(m, "soft_cells_across", "magnetics");
      // external_field: [bx, by, bz], keys [{t, B}, ...] (1.1) or {rotating: {...}} (1.1).
      const YAML::Node ef = m["external_field"];
      if (ef.IsDefined() && ef.IsSequence() && ef.size() > 0 && ef[0].IsMap()) {
        s.external_field_keys_loc = loc_of(ef);
        int k = 0;
        for (const auto& kn : ef) {
          SceneSpec::FieldKeySpec key;
          key.loc = loc_of(kn);
          const std::string kp = "magnetics.external_field[" + std::to_string(k++) + "]";
          if (!r.mapping(kn, kp, {"t", "B"}, {"t", "B"}, key.loc)) continue;
          key.t = r.number(kn, "t", kp);
          key.B = r.vector(kn, "B", kp, 3);
          s.external_field_keys.push_back(key);
        }
      } else if (ef.IsDefined() && ef.IsMap()) {
        const std::string kp = "magnetics.external_field";
        if (r.mapping(ef, kp, {"rotating"}, {"rotating"}, loc_of(ef))) {
          const YAML::Node rn = ef["rotating"];
          s.rotating_set = true;
          s.rotating_loc = loc_of(rn);
          const std::string rp = kp + ".rotating";
          if (r.mapping(rn, rp, {"magnitude", "axis", "frequency", "from"}, {"magnitude", "frequency"}, s.rotating_loc)) {
            s.rotating_magnitude = r.number(rn, "magnitude", rp);
            s.rotating_frequency = r.number(rn, "frequency", rp);
            s.rotating_axis = r.vector(rn, "axis", rp, 3);
            s.rotating_from = r.vector(rn, "from", rp, 3);
          }
        }
      } else {
        s.external_field = r.vector(m, "external_field", "magnetics", 3);
      }
    }
  }
  // Materials: a mapping of free names -> properties.
  if (const YAML::Node mats = c["materials"]; mats.IsDefined()) r.names(mats, "materials", s.root);
  if (const YAML::Node mats = c["materials"]; mats.IsDefined() && mats.IsMap()) {
    for (const auto& kv : mats) {
      MaterialSpecS m;
      m.name = kv.first.Scalar();
      m.loc = loc_of(kv.first);
      const std::string kp = "materials." + m.name;
      const YAML::Node& v = kv.second;
      if (!r.mapping(v, kp, {"kind", "remanence", "chi", "saturation", "density", "friction", "restitution", "damping", "color"},
                     {"kind"}, m.loc)) {
        continue;
      }
      m.kind = r.text(v, "kind", kp);
      m.remanence = r.number(v, "remanence", kp);
      m.chi = r.number(v, "chi", kp);
      m.saturation = r.number(v, "saturation", kp);
      m.density = r.number(v, "density", kp);
      m.friction = r.number(v, "friction", kp);
      m.restitution = r.number(v, "restitution", kp);
      read_damping(r, v, kp, m.damping);
      m.color = r.vector(v, "color", kp, 3);
      s.materials.push_back(m);
    }
  }
  if (const YAML::Node bodies = c["bodies"]; bodies.IsDefined()) {
    if (!bodies.IsSequence()) {
      d.add(loc_of(bodies), "bodies", "expected a list of bodies, got " + show(bodies));
    } else {
      int i = 0;
      for (const auto& bn : bodies) {
        BodySpecS b;
        b.loc = loc_of(bn);
        const std::string bp = "bodies[" + std::to_string(i++) + "]";
        if (!r.mapping(bn, bp,
                       {"name", "shape", "material", "magnetization", "parts", "position", "orientation", "density",
                        "mass", "motion", "keys", "friction", "restitution", "velocity", "angular_velocity",
                        "damping", "color"},
                       {"name", "shape", "material"}, b.loc)) {
          continue;
        }
        b.name = r.text(bn, "name", bp);
        if (bn["shape"].IsDefined()) read_shape(r, bn["shape"], bp + ".shape", b.loc, b.shape);
        b.material = r.text(bn, "material", bp);
        b.magnetization = r.vector(bn, "magnetization", bp, 3);
        b.position = r.vector(bn, "position", bp, 3);
        read_orientation(r, bn, bp, b.orientation);
        b.density = r.number(bn, "density", bp);
        b.mass = r.number(bn, "mass", bp);
        b.motion = r.text(bn, "motion", bp);
        b.friction = r.number(bn, "friction", bp);
        b.restitution = r.number(bn, "restitution", bp);
        b.velocity = r.vector(bn, "velocity", bp, 3);
        b.angular_velocity = r.vector(bn, "angular_velocity", bp, 3);
        read_damping(r, bn, bp, b.damping);
        b.color = r.vector(bn, "color", bp, 3);
        if (const YAML::Node parts = bn["parts"]; parts.IsDefined()) {
          if (!parts.IsSequence()) {
            d.add(loc_of(parts), bp + ".parts", "expected a list of parts, got " + show(parts));
          } else {
            int j = 0;
            for (const auto& pn : parts) {
              PartSpecS p;
              p.loc = loc_of(pn);
              const std::string pp = bp + ".parts[" + std::to_string(j++) + "]";
              if (!r.mapping(pn, pp, {"shape", "position", "orientation", "material", "magnetization"},
                             {"shape", "material"}, p.loc)) {
                continue;
              }
              if (pn["shape"].IsDefined()) read_shape(r, pn["shape"], pp + ".shape", p.loc, p.shape);
              p.position = r.vector(pn, "position", pp, 3);
              read_orientation(r, pn, pp, p.orientation);
              p.material = r.text(pn, "material", pp);
              p.magnetization = r.vector(pn, "magnetization", pp, 3);
              b.parts.push_back(p);
            }
          }
        }
        if (const YAML::Node keys = bn["keys"]; keys.IsDefined()) {
          b.keys_loc = loc_of(keys);
          if (!keys.IsSequence()) {
            d.add(b.keys_loc, bp + ".keys", "expected a list of keys, got " + show(keys));
          } else {
            int j = 0;
            for (const auto& kn : keys) {
              KeySpec k;
              k.loc = loc_of(kn);
              const std::string kp = bp + ".keys[" + std::to_string(j++) + "]";
              if (!r.mapping(kn, kp, {"t", "position", "orientation"}, {"t"}, k.loc)) continue;
              k.t = r.number(kn, "t", kp);
              k.position = r.vector(kn, "position", kp, 3);
              read_orientation(r, kn, kp, k.orientation);
              b.keys.push_back(k);
            }
          }
        }
        s.bodies.push_back(std::move(b));
      }
    }
  }
  if (const YAML::Node joints = c["joints"]; joints.IsDefined()) {
    if (!joints.IsSequence()) {
      d.add(loc_of(joints), "joints", "expected a list of joints, got " + show(joints));
    } else {
      int i = 0;
      for (const auto& jn : joints) {
        JointSpec j;
        j.loc = loc_of(jn);
        const std::string jp = "joints[" + std::to_string(i++) + "]";
        if (!r.mapping(jn, jp, {"name", "type", "bodies", "pivot", "axis", "limits"}, {"type", "bodies"}, j.loc)) continue;
        j.name = r.text(jn, "name", jp);
        j.type = r.text(jn, "type", jp);
        j.bodies = r.strings(jn, "bodies", jp, 2);
        j.pivot = r.vector(jn, "pivot", jp, 3);
        j.axis = r.vector(jn, "axis", jp, 3);
        j.limits = r.vector(jn, "limits", jp, 2);
        s.joints.push_back(j);
      }
    }
  }
  if (const YAML::Node o = c["outputs"]; o.IsDefined()) {
    if (r.mapping(o, "outputs", {"cache", "field", "preview", "usd"}, {}, loc_of(o))) {
      s.cache = r.text(o, "cache", "outputs");
      s.usd = r.text(o, "usd", "outputs");
      if (const YAML::Node f = o["field"]; f.IsDefined()) {
        s.field_set = true;
        s.field_loc = loc_of(f);
        if (r.mapping(f, "outputs.field", {"path", "voxel", "bounds", "margin", "every", "threshold"}, {"path"}, s.field_loc)) {
          // A number, or the word auto (kept as text); any other word is refused as not a number.
          auto number_or_auto = [&](const char* key, Val<double>& number, Val<std::string>& word) {
            const YAML::Node n = f[key];
            if (n.IsDefined() && n.IsScalar() && n.Scalar() == "auto") word = r.text(f, key, "outputs.field");
            else number = r.number(f, key, "outputs.field");
          };
          s.field_path = r.text(f, "path", "outputs.field");
          s.field_voxel = r.number(f, "voxel", "outputs.field");
          number_or_auto("margin", s.field_margin, s.field_margin_auto);
          number_or_auto("threshold", s.field_threshold, s.field_threshold_auto);
          s.field_every = r.number(f, "every", "outputs.field");
          if (const YAML::Node bn = f["bounds"]; bn.IsDefined()) {
            if (bn.IsScalar()) {
              s.field_bounds_auto = r.text(f, "bounds", "outputs.field");
            } else if (bn.IsSequence() && bn.size() == 2) {
              s.field_bounds.loc = loc_of(bn);
              s.field_bounds.set = true;
              for (const auto& corner : bn) {
                Val<Vec> v;
                r.read_vector(corner, "outputs.field.bounds", 3, v);
                if (!v.set) s.field_bounds.set = false;
                s.field_bounds.v.push_back(v.v);
              }
            } else {
              d.add(loc_of(bn), "outputs.field.bounds",
                    "expected 'auto' or [[xmin, ymin, zmin], [xmax, ymax, zmax]], got " + show(bn));
            }
          }
        }
      }
      if (const YAML::Node p = o["preview"]; p.IsDefined()) {
        s.preview_set = true;
        s.preview_loc = loc_of(p);
        if (r.mapping(p, "outputs.preview", {"path", "size", "camera", "field_lines"}, {"path"}, s.preview_loc)) {
          s.preview_path = r.text(p, "path", "outputs.preview");
          s.preview_size = r.vector(p, "size", "outputs.preview", 2);
          s.field_lines = r.boolean(p, "field_lines", "outputs.preview");
          if (const YAML::Node cam = p["camera"]; cam.IsDefined()) {
            s.camera.set = true;
            s.camera.loc = loc_of(cam);
            if (r.mapping(cam, "outputs.preview.camera", {"position", "look_at", "fov"}, {"position", "look_at"},
                          s.camera.loc)) {
              s.camera.position = r.vector(cam, "position", "outputs.preview.camera", 3);
              s.camera.look_at = r.vector(cam, "look_at", "outputs.preview.camera", 3);
              s.camera.fov = r.number(cam, "fov", "outputs.preview.camera");
            }
          }
        }
      }
    }
  }
  return s;
}

SceneSpec parse_scene_file(const std::string& path, Diagnostics& d) {
  // A FIFO or device would block or never end; a scene is a small regular file.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) &&
      (!std::filesystem::is_regular_file(status) || std::filesystem::file_size(path, ec) > (64u << 20))) {
    d.add({}, "", std::filesystem::is_regular_file(status) ? "the scene file is larger than 64 MiB"
                                                           : "the scene file is not a regular file");
    SceneSpec s;
    s.file = path;
    return s;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    d.add({}, "", "cannot read the scene file");
    SceneSpec s;
    s.file = path;
    return s;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_scene_text(ss.str(), path, d);
}

}  // namespace magbake::scene
