// The HDF5 cache of a bake (H5MD-inspired; layout in docs/cache-format.md). Written frame by
// frame in SWMR mode so a process killed at any moment leaves every completed frame readable;
// read back by diff, info, field export, previews and --resume.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cache_layout.h"
#include "h5.h"
#include "magnetics/model.h"
#include "scene/scene.h"

namespace magbake::io {

using magnetics::Quat;
using magnetics::Vec3;

/// Whether `path` is an HDF5 file (by its signature), so commands that take a scene or a cache
/// can tell them apart. False for a missing or unreadable file.
bool is_hdf5_file(const std::string& path);

/// What a cache says about how its bake ended (dataset /bake/status).
enum class BakeStatus : int { kRunning = 0, kComplete = 1, kInterrupted = 2, kFailed = 3 };
const char* status_name(BakeStatus s);

/// The per-frame observables a cache stores (/observables, docs/cache-format.md): energies (J),
/// momenta (kg m/s, kg m²/s), wall times (s), work counters, the last substep's induction
/// residual, energy drift (J), the fastest body's speed (m/s), the deepest penetration (m) and
/// the number of bodies asleep.
struct FrameObservables {
  double kinetic_energy = 0, gravity_energy = 0, magnetic_energy = 0;
  Vec3 momentum = Vec3::Zero(), angular_momentum = Vec3::Zero();
  double magnetics_seconds = 0, rigid_seconds = 0;
  double cells_visited = 0, induction_iterations = 0, induction_residual = 0, substeps = 0;
  double energy_drift = 0, max_speed = 0, max_penetration = 0, sleeping = 0, body_steps = 0;
  Vec3 applied_field = Vec3::Zero();  ///< the uniform applied field at the frame, T (scene 1.1)
};

/// One stuck contact joint as stored (a row of /contacts/stuck): the two body indices (a < b)
/// then the joint's frames, kStuckValues doubles (layout in docs/cache-format.md; what they mean
/// belongs to the simulator, bake/cache_state.cpp converts).
using StuckRow = std::array<double, kStuckValues>;

/// One frame as stored.
struct CacheFrame {
  int frame = 0;
  double time = 0;
  std::vector<Vec3> position;          ///< body origin (scene body frame), world, m
  std::vector<Quat> orientation;       ///< body -> world
  std::vector<Vec3> velocity, angular_velocity, force, torque;
  std::vector<Vec3> induced_moment;    ///< world, A·m², Model::induced_cells order
  /// (nbody x 2) sleep state and seconds at rest, (nbody x 6) wake-up reference force (N) and
  /// torque (N·m); empty for caches written before sleeping (writing: empty = every body awake).
  std::vector<double> sleep, sleep_reference;
  /// The applied field at the frame (T, world), as read (CacheReader::applied_field); a writer
  /// takes it from FrameObservables instead.
  Vec3 applied_field = Vec3::Zero();
};

/// Writes a cache. Frames must be appended in order.
class CacheWriter {
 public:
  /// Creates `path` (replacing it), writes everything constant (scene text and hash, versions,
  /// resolved parameters, body constants, the magnetic cells, render geometry), then switches
  /// to SWMR writing. Throws h5::Error.
  CacheWriter(const std::string& path, const scene::Scene& scene, const magnetics::Model& model,
              const std::string& magbake_version);
  ~CacheWriter();

  /// Appends one frame (its poses at the body origin, velocities, forces, induced moments, sleep
  /// state), its observables and its stuck joints (ascending pairs), and flushes it to disk;
  /// frames_done is updated last. Throws h5::Error (also for counts that do not fit the cache).
  void append(const CacheFrame& frame, const FrameObservables& observables, const std::vector<StuckRow>& stuck);
  /// Copies the first `count` frames of `from` verbatim (bit for bit), for --resume.
  void copy_frames_from(const class CacheReader& from, int count);
  void set_status(BakeStatus status);
  int frames_written() const { return frames_; }
  /// Flushes and closes (also done by the destructor, which never throws).
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int frames_ = 0;
};


/// The render geometry of a cache: every body's shape and parts as triangle meshes in the body
/// frame (m). Indices are checked at open: triangles index `vertices`, submesh ranges lie inside.
struct RenderGeometry {
  struct Submesh {
    int body = 0;                          ///< body index
    std::int64_t vertex_begin = 0, vertex_count = 0;
    std::int64_t triangle_begin = 0, triangle_count = 0;
    std::string role;                      ///< "body" or "part"
    std::string material_kind;             ///< permanent | soft | linear | superconductor | none
    Vec3 magnetization = Vec3::Zero();     ///< unit direction (permanent), body frame
    /// The scene's `color` (RGB 0..1, sRGB as picked; scene 1.1) for this body or part, unset
    /// where the scene gave none (drawn by material kind) and in caches written before it.
    std::optional<Vec3> color;
  };
  std::vector<Vec3> vertices;
  std::vector<std::array<std::int64_t, 3>> triangles;
  std::vector<Submesh> submeshes;
};

/// Reads a cache written by magbake (also one left behind by a crash). The constructor checks
/// the whole layout (cache_layout.h): a reader never indexes outside what the file holds, and
/// frame() refuses frames with non-finite or invalid poses.
class CacheReader {
 public:
  /// Opens `path`; throws std::runtime_error naming the problem for a missing, unreadable,
  /// corrupt or foreign file.
  explicit CacheReader(const std::string& path);
  ~CacheReader();

  const std::string& path() const { return path_; }
  int frame_count() const { return frames_; }   ///< completed frames
  int first_frame() const { return first_frame_; }
  double fps() const { return fps_; }
  BakeStatus status() const { return status_; }
  const std::vector<std::string>& body_names() const { return names_; }
  std::string scene_text() const;
  std::string scene_hash() const;
  std::string attribute(const std::string& name) const;  ///< a /parameters string attribute
  std::vector<double> parameter_doubles(const std::string& name) const;  ///< a /parameters numeric attribute
  std::vector<Vec3> centers_of_mass() const;             ///< body frame
  /// What the cache says of each body besides its name: motion (static, kinematic, dynamic),
  /// material name ("" for none) and mass (kg). Strings missing or of the wrong count read "".
  struct BodyInfo {
    std::string motion, material;
    double mass = 0;
  };
  std::vector<BodyInfo> body_info() const;
  RenderGeometry geometry() const;
  /// A scalar per-frame observable (e.g. "magnetics_seconds") over the completed frames; empty
  /// when the cache does not hold it.
  std::vector<double> observable(const std::string& name) const;
  /// The uniform applied field (T, world) at completed frame `index`: the per-frame record
  /// (observables/applied_field, scene 1.1: animated fields), else the constant
  /// /parameters@external_field of older caches. Throws h5::Error for a record that is not
  /// [frames, 3] of finite values.
  Vec3 applied_field(int index) const;

  CacheFrame frame(int index) const;                   ///< 0-based index of a completed frame
  /// One value of a scalar observable (e.g. "magnetic_energy") at a completed frame; throws
  /// std::runtime_error when the cache does not hold it or it is not finite.
  double observable_at(const std::string& name, int index) const;
  /// The stuck joints stored with a completed frame (empty for caches written before them);
  /// throws std::runtime_error for a row whose bodies are not a valid ascending pair or whose
  /// values are not finite.
  std::vector<StuckRow> stuck_rows(int index) const;
  /// The magnetic model (cells and hierarchies) rebuilt from the stored cells. If given,
  /// induced_order[k] receives the stored rank of the model's k-th induced cell (the order of
  /// CacheFrame::induced_moment), so frames' moments can be reordered for the model.
  magnetics::Model model(std::vector<int>* induced_order = nullptr) const;

  hid_t file() const;

 private:
  friend class CacheWriter;  // copy_frames_from reads the layout's stuck-joint offsets
  std::string path_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int frames_ = 0, first_frame_ = 0;
  double fps_ = 0;
  BakeStatus status_ = BakeStatus::kRunning;
  std::vector<std::string> names_;
  CacheLayout layout_;
};

}  // namespace magbake::io
