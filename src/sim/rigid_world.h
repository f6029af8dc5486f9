// Bullet (double precision) behind a small interface: one rigid body per scene body.
#pragma once

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
  /// Reads poses and velocities back (centre-of-mass frames, body axes).
  void get_state(SimState& s) const;
  /// Advances by h seconds: kinematic bodies move to their keyed pose at t + h (their velocity
  /// follows from the finite difference), dynamic bodies feel gravity plus the given magnetic
  /// forces and torques (world frame, about the centre of mass; held constant over the step).
  void step(double t, double h, const std::vector<Vec3>& force, const std::vector<Vec3>& torque);

  /// Bullet's version, e.g. "3.24".
  static std::string bullet_version();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace magbake::sim
