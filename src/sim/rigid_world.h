// Bullet (double precision) behind a small interface: one rigid body per scene body.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "scene/scene.h"
#include "sim_state.h"

namespace magbake::sim {

/// The rigid-body world. Bullet's body frame is the centre of mass with principal axes; this
/// class converts to and from the scene's body axes (SimState) so nothing else sees Bullet.
class RigidWorld {
 public:
  explicit RigidWorld(const scene::Scene& scene);
  ~RigidWorld();
  RigidWorld(const RigidWorld&) = delete;
  RigidWorld& operator=(const RigidWorld&) = delete;

  /// Puts every body at the state's poses and velocities (initial state or a resumed frame).
  void set_state(const SimState& s);
  /// Starts Bullet afresh at the state: a new world (broadphase, pair cache, contact manifolds,
  /// constraint solver) with every body added in scene order at the state's pose, velocities and
  /// sleep state, the state's stuck joints (SimState::stuck_joints) made again, and one collision
  /// detection, so that the contacts of the first step are known. Nothing of the steps before is
  /// kept: the simulator calls it at every frame, and a bake resumed from a cache frame goes on
  /// from the same world as the uninterrupted bake (physics.md §8, cache-format.md).
  void reset(const SimState& s);
  /// Reads poses, velocities, sleep states and stuck joints back (centre-of-mass frames, body axes).
  void get_state(SimState& s) const;
  /// Advances by h seconds: kinematic bodies move to their keyed pose at t + h (their velocity
  /// follows from the finite difference), dynamic bodies feel gravity plus the given magnetic
  /// forces and torques (world frame, about the centre of mass; held constant over the step).
  /// `held` (optional, per body): dynamic bodies marked 1 are held where they are for this step
  /// (not moved, no force applied, activation and rest clock kept). Per-island substeps
  /// (Simulator) step the islands that need short pieces while the others are held, and the
  /// others in one piece while the first are held; an island whose bodies are all held is not
  /// solved at all.
  void step(double t, double h, const std::vector<Vec3>& force, const std::vector<Vec3>& torque,
            const std::vector<std::uint8_t>* held = nullptr);
  /// Puts kinematic bodies back at their keyed pose at time t (s), so that a second pass over
  /// the interval starting at t moves them from there again (their contact velocity is Bullet's
  /// finite difference of the pose change).
  void rewind_kinematic(double t);
  /// Islands of dynamic bodies (scene index of each body's island, the smallest body index in
  /// it; -1 for static and kinematic bodies): bodies linked through Bullet's pair cache
  /// (bounding boxes, padded and swept over the last step, that overlap), as Bullet's own
  /// simulation islands. Bodies of different islands cannot touch within a step.
  void islands(std::vector<int>& island) const;

  /// A pair of bodies (scene indices; b = -1 for none) and how deep they interpenetrate, m.
  struct Penetration {
    int a = -1, b = -1;
    double depth = 0;
  };
  /// Approach speed (m/s, along the line between the centres) over `length` (m) of the
  /// pairs of bodies whose swept bounding boxes overlapped in the last step (Bullet's pair
  /// cache: bodies that may touch within a step) but are not yet in contact (no contact point
  /// closer than 0.1 mm), both permanent magnets and at least one dynamic; `length` is 1% of the smaller
  /// body's smallest extent. Multiplied by a step h it says how many substeps keep such a pair
  /// from sinking more than that length into each other at impact. Per body (s^-1): the
  /// largest such rate over its pairs, 0 when no pair of it qualifies; `rate` is resized.
  void closing_rates(std::vector<double>& rate) const;
  /// Deepest penetration among the contact points of the last step's collision detection.
  Penetration deepest_penetration() const;
  /// Contact normals of the last step's collision detection, per scene body: for every manifold
  /// with a point closer than 0.1 mm, the unit normal (world frame) along which the contact
  /// pushes that body away from its partner. Bodies without such a contact get an empty list.
  /// `face_slip` (optional, per body, m/s): over the body's manifolds with such points, the
  /// largest speed of one body's contact point relative to the other's; infinite when one of
  /// them is not a face contact (no three of its points within 0.1 mm span a triangle of area
  /// 0.005 s², s the smaller body's smallest extent), i.e. a point or line contact about which
  /// the body can roll or rock freely; 0 without contacts. `stuck` (optional, per body, parallel
  /// to `out`): 1 where the contact is a stuck contact (StuckContacts: the pair is held by a
  /// joint), else 0. `partner_speed` (optional, per body, m/s): over the body's manifolds with
  /// such points, the largest speed of its centre of mass relative to its partner (the partner's
  /// velocity at that point, spin included): a ball rolling over a magnet moves, one resting on
  /// it does not; 0 without contacts.
  void contact_normals(std::vector<std::vector<Vec3>>& out, std::vector<double>* face_slip = nullptr,
                       std::vector<std::vector<std::uint8_t>>* stuck = nullptr,
                       std::vector<double>* partner_speed = nullptr) const;
  /// Number of face contacts held by a joint now (StuckContacts).
  int stuck_contacts() const;
  /// Replaces the forces (N) and torques (N·m, about the centre of mass, world frame) of the
  /// bodies held together by stuck contacts by their shares of their group's load, as step()
  /// applies them (StuckContacts::shared); others are unchanged.
  void stuck_shares(std::vector<Vec3>& force, std::vector<Vec3>& torque) const;
  /// Moves dynamic bodies apart along their contact normals until no pair penetrates deeper
  /// than `tolerance` (m). Positions only: velocities are kept, so no kinetic energy is added.
  /// Returns the pairs that overlapped by more than `tolerance` before, deepest first.
  std::vector<Penetration> separate_overlaps(double tolerance, int max_iterations = 200);

  /// Sleeping (Scene::sleep_time > 0; get_state/set_state carry it as SimState::sleep and
  /// rest_time). Whether body i sleeps (is not stepped) now.
  bool asleep(int i) const;
  /// Wakes body i if it sleeps or waits to; the rest of its island wakes at the next step.
  void wake(int i);
  /// Restarts body i's rest clock (it is moving or not balanced, so it must not fall asleep);
  /// wakes it if it waits to sleep. No effect on static, kinematic or never-sleeping bodies.
  void keep_awake(int i);

  /// Bullet's version, e.g. "3.24".
  static std::string bullet_version();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace magbake::sim
