// SceneSpec: a scene file as written (file units, names unresolved), every value with the place
// it came from. Produced by parse_scene(); turned into a Scene by validate_scene().
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics.h"

namespace magbake::scene {

/// A value read from the file, with its position; `set` is false when the key was absent.
template <class T>
struct Val {
  T v{};
  Loc loc;
  bool set = false;
};

using Vec = std::vector<double>;

struct ShapeSpec {
  Loc loc;           ///< the `shape` mapping
  std::string kind;  ///< box | sphere | cylinder | torus | mesh ("" if missing or bad)
  Loc kind_loc;
  Val<Vec> size;     ///< box: full edges
  Val<double> radius, height, major, minor, scale;
  Val<std::string> file;
};

struct OrientationSpec {
  bool set = false;
  Loc loc;
  Val<Vec> axis;
  Val<double> angle;
  Val<Vec> quat;  ///< w, x, y, z
};

struct PartSpecS {
  Loc loc;
  ShapeSpec shape;
  Val<Vec> position;
  OrientationSpec orientation;
  Val<std::string> material;
  Val<Vec> magnetization;
};

struct KeySpec {
  Loc loc;
  Val<double> t;
  Val<Vec> position;
  OrientationSpec orientation;
};

/// `damping: {linear, angular}` (format 1.1), on a body or a material.
struct DampingSpec {
  bool set = false;
  Loc loc;
  Val<double> linear, angular;
};

struct BodySpecS {
  Loc loc;
  Val<std::string> name;
  ShapeSpec shape;
  Val<std::string> material;
  Val<Vec> magnetization;
  std::vector<PartSpecS> parts;
  Val<Vec> position;
  OrientationSpec orientation;
  Val<double> density, mass;
  Val<std::string> motion;
  std::vector<KeySpec> keys;
  Loc keys_loc;
  Val<double> friction, restitution;
  Val<Vec> velocity, angular_velocity;
  DampingSpec damping;
  Val<Vec> color;
};

struct MaterialSpecS {
  Loc loc;
  std::string name;
  Val<std::string> kind;
  Val<double> remanence, chi, saturation, density;
  Val<double> friction, restitution;
  DampingSpec damping;
  Val<Vec> color;
};

struct JointSpec {
  Loc loc;
  Val<std::string> name, type;
  Val<std::vector<std::string>> bodies;
  Val<Vec> pivot, axis, limits;
};

struct CameraSpec {
  bool set = false;
  Loc loc;
  Val<Vec> position, look_at;
  Val<double> fov;
};

struct SceneSpec {
  std::string file;       ///< path as given
  std::string text;       ///< the file's bytes
  Loc root;
  Val<double> version;    ///< `magbake:`
  Val<std::string> name;
  Loc units_loc;
  Val<std::string> length_unit, angle_unit;
  Loc time_loc;
  Val<double> fps, dt, sleep;
  Val<Vec> frames;
  Val<Vec> gravity;
  Loc magnetics_loc;
  Val<std::string> quality, induction;
  Val<double> cell_size, theta, induction_tolerance, surface_tolerance, grading, soft_cells_across;
  Val<Vec> external_field;  ///< the constant form [bx, by, bz]
  /// Format 1.1: keys [{t, B}, ...] (loc of the list in external_field_keys_loc).
  struct FieldKeySpec {
    Loc loc;
    Val<double> t;
    Val<Vec> B;
  };
  std::vector<FieldKeySpec> external_field_keys;
  Loc external_field_keys_loc;
  /// Format 1.1: {rotating: {magnitude, axis, frequency, from}}.
  bool rotating_set = false;
  Loc rotating_loc;
  Val<double> rotating_magnitude, rotating_frequency;
  Val<Vec> rotating_axis, rotating_from;
  std::vector<MaterialSpecS> materials;
  std::vector<BodySpecS> bodies;
  std::vector<JointSpec> joints;
  // outputs
  Val<std::string> cache, usd;
  bool field_set = false;
  Loc field_loc;
  Val<std::string> field_path, field_bounds_auto;
  Val<std::vector<Vec>> field_bounds;
  Val<double> field_voxel, field_margin, field_every, field_threshold;
  Val<std::string> field_margin_auto, field_threshold_auto;  ///< "auto" given for margin / threshold
  bool preview_set = false;
  Loc preview_loc;
  Val<std::string> preview_path;
  Val<Vec> preview_size;
  CameraSpec camera;
  Val<bool> field_lines;
};

/// Reads a scene file (YAML) into a SceneSpec. Syntax errors, unknown or duplicate keys,
/// missing required keys and wrong value types are added to `diag` with their positions.
SceneSpec parse_scene_text(const std::string& text, const std::string& file, Diagnostics& diag);

/// Same, reading the file first (an unreadable file is a diagnostic).
SceneSpec parse_scene_file(const std::string& path, Diagnostics& diag);

}  // namespace magbake::scene
