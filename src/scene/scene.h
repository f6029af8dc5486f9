// Scene: a validated scene, immutable, in SI units (m, kg, s, rad, T). Built once by
// load_scene(); everything that changes during a bake lives elsewhere (sim::SimState).
#pragma once

#include <cmath>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geometry/shapes.h"
#include "magnetics/material.h"
#include "magnetics/types.h"

namespace magbake::scene {

using magnetics::Mat3;
using magnetics::Pose;
using magnetics::Quat;
using magnetics::Vec3;

/// A named material (scene `materials:`).
struct Material {
  std::string name;
  magnetics::MaterialKind kind = magnetics::MaterialKind::kNone;
  std::string kind_name;          ///< as written: permanent | soft | linear | superconductor | none
  double remanence = 0;           ///< T (permanent)
  double chi = 0;                 ///< susceptibility (soft, linear; -1 for superconductor)
  /// Saturation polarization J_s, T (format 1.1; soft and linear with chi > 0): M(H) follows the
  /// Fröhlich–Kennelly law (physics.md §13). 0 = linear at any field.
  double saturation = 0;
  std::optional<double> density;  ///< kg/m³
  /// Format 1.1 defaults for the bodies made of this material (a body's own key wins).
  std::optional<double> friction, restitution;
  std::optional<double> linear_damping, angular_damping;  ///< see Body
  std::optional<Vec3> color;      ///< see Body
};

/// A solid shape as the scene describes it, with the built geometry.
struct ShapeDesc {
  geometry::ShapeKind kind = geometry::ShapeKind::kBox;
  Vec3 size = Vec3::Zero();       ///< box full edges, m
  double radius = 0, height = 0;  ///< sphere, cylinder, m
  double major = 0, minor = 0;    ///< torus, m
  std::string mesh_file;          ///< mesh: resolved path
  double mesh_scale = 1;          ///< mesh: file coordinates x scale x length unit -> m
  std::shared_ptr<const geometry::Shape> shape;  ///< centred as the file describes it
  std::string describe() const;   ///< e.g. "cylinder r=5 mm h=40 mm"
};

/// A magnetic insert of a body, in the body frame.
struct Part {
  ShapeDesc shape;
  Pose pose;                       ///< part frame -> body frame (body origin as written)
  int material = -1;               ///< index into Scene::materials
  Vec3 magnetization = Vec3::Zero();  ///< unit direction, body frame (permanent only)
};

/// A keyframe of a kinematic body.
struct Key {
  double t = 0;                    ///< s
  std::optional<Vec3> position;    ///< body origin, world, m
  std::optional<Quat> orientation; ///< body -> world
};

enum class Motion { kDynamic, kStatic, kKinematic };

/// A rigid body.
struct Body {
  std::string name;
  ShapeDesc shape;
  int material = -1;                  ///< index into Scene::materials
  Vec3 magnetization = Vec3::Zero();  ///< unit, body frame (permanent material only)
  std::vector<Part> parts;
  Pose pose;                          ///< initial pose of the body origin (as written), world
  Motion motion = Motion::kDynamic;
  std::vector<Key> keys;              ///< kinematic only, increasing t
  double mass = 0;                    ///< kg (0 for static/kinematic without density)
  Vec3 com = Vec3::Zero();            ///< centre of mass in the body frame, m
  Mat3 inertia = Mat3::Zero();        ///< about the centre of mass, body axes, kg·m²
  double friction = 0.5, restitution = 0.1;  ///< the body's, else its material's, else these
  /// Share of the linear / angular velocity lost per second of free motion, in [0, 1): Bullet's
  /// (and Blender's) damping, v <- v (1 - d)^dt each step; a rate of -ln(1 - d) per second.
  /// The body's `damping`, else its material's, else 0 (docs/scene-format.md).
  double linear_damping = 0, angular_damping = 0;
  /// Display colour, RGB in [0, 1] as a colour picker shows it (sRGB); unset = by material kind
  /// (previews and USD, docs/previews.md).
  std::optional<Vec3> color;
  Vec3 velocity = Vec3::Zero();       ///< initial linear velocity of the centre of mass, m/s
  Vec3 angular_velocity = Vec3::Zero();  ///< initial, world, rad/s

  /// Pose of the body origin at time t: keyed for kinematic bodies (linear position, slerp
  /// orientation, held before the first and after the last key), the initial pose otherwise.
  Pose pose_at(double t) const;
  /// Pose of the centre-of-mass frame (body axes, origin at the centre of mass).
  Pose com_pose(const Pose& origin_pose) const {
    return Pose{origin_pose.rotation, origin_pose.position + origin_pose.rotation * com};
  }
  bool magnetic(const std::vector<Material>& materials) const;
};

/// A joint (scene format 1.1): a Bullet constraint between two bodies or a body and the world,
/// made from the initial poses (docs/scene-format.md, "joints").
enum class JointType { kHinge, kBall, kFixed, kSlider };

struct Joint {
  std::string name;        ///< as written, or "joint <index>"
  JointType type = JointType::kHinge;
  std::string type_name;   ///< hinge | ball | fixed | slider
  int a = -1;              ///< body index
  int b = -1;              ///< body index, or -1 for the world
  /// The joint frame in body a's frame and in body b's (the world's if b < 0), m: both are the
  /// same world frame at t = 0 (origin at the pivot; z along the hinge's or slider's axis), so
  /// the initial configuration is the joint's zero (angle 0, slide 0).
  Pose frame_a, frame_b;
  /// Hinge: the angle about z (rad), slider: the slide along z (m), from the initial
  /// configuration; unset = free.
  std::optional<std::pair<double, double>> limits;
};

/// Magnetics settings after presets are resolved.
struct MagneticsSettings {
  std::string quality = "default";   ///< draft | default | high
  std::optional<double> cell_size;   ///< m; when unset each part uses its extent / cells_per_extent
  int cells_per_extent = 4;          ///< preset: cells across the smallest extent of each part
  /// Preset or `soft_cells_across`: the same for soft parts (induced, chi >= kSoftPartChi), whose
  /// magnetization gathers at edges and contact points and needs finer cells than a magnet's
  /// uniform one (physics.md §7).
  int soft_cells_per_extent = 8;
  double theta = 0.5;
  std::string induction = "coupled";  ///< coupled | paper | off
  /// Coupled induction: GMRES stops when the residual is below this fraction of the right-hand
  /// side (preset; physics.md §7 for what it changes in the forces).
  double induction_tolerance = 1e-4;
  /// Uniform applied field, T: the constant one, or its value at t = 0 when it is animated
  /// (Scene::applied_field gives it at any time).
  Vec3 external_field = Vec3::Zero();
  /// Format 1.1 `external_field: [{t, B}, ...]`: keys (t in s, increasing; B in T), linearly
  /// interpolated, held before the first and after the last. Empty when constant or rotating.
  std::vector<std::pair<double, Vec3>> external_field_keys;
  /// Format 1.1 `external_field: {rotating: ...}`: a field of `magnitude` T turning about the unit
  /// `axis` at `frequency` turns per second (right-handed; negative turns back), pointing along
  /// the unit `from` (normal to the axis) at t = 0: B(t) = |B| (cos 2πft from + sin 2πft axis × from).
  struct RotatingField {
    double magnitude = 0, frequency = 0;
    Vec3 axis = Vec3::UnitZ(), from = Vec3::UnitX();
  };
  std::optional<RotatingField> rotating_field;
  double near_field = 2.5;           ///< cell sizes (exact cuboid interactions within)
  int near_field_order = 4;
  /// Preset: curved permanent magnets keep their surface, tessellated within this distance (m),
  /// for the exact field near them (physics.md §12).
  double surface_tolerance = 1e-5;
  /// Preset: soft parts' surface cells are split in 8 this many times (BuildSettings::grading).
  int grading = 0;
};

struct FieldOutput {
  std::string path;                  ///< pattern with #### or printf %04d
  std::optional<double> voxel;       ///< m; default: automatic from the bounds
  bool auto_bounds = true;
  Vec3 bounds_min = Vec3::Zero(), bounds_max = Vec3::Zero();  ///< m, world
  std::optional<double> margin;      ///< m, added around the magnetic bodies (auto bounds); unset = auto (docs/field-volumes.md)
  std::optional<double> threshold;   ///< T, voxels where the bodies' |B| is below stay inactive; unset = auto (io::kAutoThresholdFraction of the strongest remanence or applied field)
  int every = 1;                     ///< write every n-th frame
};

struct Camera {
  Vec3 position, look_at;            ///< m, world
  double fov = 0.6981317007977318;   ///< vertical field of view, rad (40 degrees)
};

struct PreviewOutput {
  std::string path;
  int width = 960, height = 540;
  std::optional<Camera> camera;
  bool field_lines = false;
};

struct Scene {
  std::string file;        ///< the scene file path
  std::string text;        ///< its exact bytes (stored in caches)
  std::string hash;        ///< SHA-256 of text, hex
  std::string name;
  std::string length_unit, angle_unit;
  double fps = 30;
  int first_frame = 1, last_frame = 120;
  double dt = 1.0 / 600.0;  ///< physics substep, s
  /// Seconds a dynamic body must stay at rest (with its island of touching bodies) before it
  /// sleeps: it is no longer stepped, and its magnetic forces come from cached pairs until a
  /// contact or a change of its magnetic force wakes it (sim::Simulator). 0 = no body sleeps.
  double sleep_time = 0.5;
  Vec3 gravity{0, 0, -9.81};
  MagneticsSettings magnetics;
  std::vector<Material> materials;
  std::vector<Body> bodies;
  std::vector<Joint> joints;            ///< format 1.1
  std::optional<std::string> cache;     ///< as written (relative to the working directory)
  std::optional<std::string> usd;       ///< outputs.usd: a USD stage (.usda) the bake writes at its end (docs/usd.md)
  std::optional<FieldOutput> field;
  std::optional<PreviewOutput> preview;

  /// Time (s) of a frame: (f - first) / fps.
  double frame_time(int f) const { return (f - first_frame) / fps; }
  /// Nominal physics steps between two frames: dt rounded down so that whole steps land on the
  /// frame times, ceil((1/fps) / dt), at least 1. Each step is (1/fps) / this long.
  int steps_per_frame() const {
    const double n = std::ceil(1.0 / (fps * dt) - 1e-9);
    return n < 1 ? 1 : static_cast<int>(n);
  }
  int body_index(const std::string& name) const;
  /// The uniform applied field (T, world) at time t (s): constant, keyed or rotating.
  Vec3 applied_field(double t) const;
  /// True when the applied field changes with time (keys or rotating).
  bool applied_field_animated() const {
    return magnetics.external_field_keys.size() > 1 || (magnetics.rotating_field && magnetics.rotating_field->frequency != 0);
  }
};

}  // namespace magbake::scene
