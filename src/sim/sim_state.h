// SimState: everything that changes during a bake, as flat arrays per body (index = scene body).
#pragma once

#include <cstdint>
#include <vector>

#include "magnetics/types.h"

namespace magbake::sim {

using magnetics::Mat3;
using magnetics::Quat;
using magnetics::Vec3;

/// Where a body is on its way to sleep (Bullet's activation states, in our numbering).
enum SleepState : std::uint8_t {
  kAwake = 0,    ///< stepped; at rest for rest_time s so far
  kResting = 1,  ///< at rest for sleep_time s, waiting for the rest of its island
  kAsleep = 2,   ///< not stepped; woken by a contact or a change of its magnetic force
};

/// A stuck contact (StuckContacts): bodies a < b (scene indices) held at their relative pose by
/// a point-to-point joint and a joint locking their relative turn. Part of the state, so that a
/// bake resumed from a cache frame holds the same pairs with the same joints. Frames are Bullet's
/// body frames (centre of mass, principal axes); all values are copied bit for bit.
struct StuckJoint {
  int a = -1, b = -1;
  Vec3 normal_in_a = Vec3::Zero();  ///< unit contact normal in a's frame, pushing a away from b
  double mu = 0;                    ///< the contact's combined friction coefficient
  double lever = 0;                 ///< lever of the tilt and twist limits, m
  Vec3 pivot_a = Vec3::Zero(), pivot_b = Vec3::Zero();  ///< the joint point in a's and b's frames, m
  Mat3 basis_a = Mat3::Identity(), basis_b = Mat3::Identity();  ///< turn joint frame axes in a's, b's frames
  Vec3 origin_a = Vec3::Zero(), origin_b = Vec3::Zero();  ///< turn joint frame origins in a's, b's frames, m
  /// Number of doubles in a flat record (cache row): a, b, then the members in declaration
  /// order, matrices row-major.
  static constexpr int kValues = 37;
};

/// The body origin (scene body frame) of a body whose centre of mass is at `com_world` (world,
/// m), turned by q, with its centre of mass at `com_body` in the body frame. The cache stores
/// this; com_from_origin() undoes it. Simulator rounds every frame's state through both, so a
/// state read back from a cache is bit for bit the state the bake went on from.
inline Vec3 body_origin(const Vec3& com_world, const Quat& q, const Vec3& com_body) { return com_world - q * com_body; }
/// The centre of mass (world, m) of a body whose origin is at `origin` (world, m).
inline Vec3 com_from_origin(const Vec3& origin, const Quat& q, const Vec3& com_body) { return origin + q * com_body; }

/// State of every body at one instant. Poses are of the centre-of-mass frame with the body's
/// own axes (scene body frame shifted to the centre of mass), world frame.
struct SimState {
  double time = 0;                       ///< s since the first frame
  std::vector<Vec3> com_position;        ///< (nbody x 3) m
  std::vector<Quat> orientation;         ///< (nbody) body axes -> world
  std::vector<Vec3> velocity;            ///< (nbody x 3) of the centre of mass, m/s
  std::vector<Vec3> angular_velocity;    ///< (nbody x 3) world, rad/s
  std::vector<Vec3> magnetic_force;      ///< (nbody x 3) last substep's, N
  std::vector<Vec3> magnetic_torque;     ///< (nbody x 3) last substep's, about the COM, N·m
  double magnetic_energy = 0;            ///< J, pair energy of the evaluation that gave the forces above
  std::vector<Vec3> induced_moment;      ///< (ninduced x 3) world, A·m² (Model::induced_cells order)
  // Sleeping (Scene::sleep_time; saved in the cache so that a resumed bake sleeps as the
  // uninterrupted one does). Static and kinematic bodies stay kAwake with rest_time 0.
  std::vector<std::uint8_t> sleep;       ///< (nbody) a SleepState
  std::vector<double> rest_time;         ///< (nbody) s the body has been below its sleep speeds
  std::vector<Vec3> sleep_force;         ///< (nbody x 3) magnetic force when it fell asleep, N (wake-up reference)
  std::vector<Vec3> sleep_torque;        ///< (nbody x 3) magnetic torque then, N·m
  /// Stuck contacts now, by (a, b) (RigidWorld::get_state fills it; RigidWorld::reset remakes them).
  std::vector<StuckJoint> stuck_joints;

  void resize(std::size_t nbody) {
    com_position.assign(nbody, Vec3::Zero());
    orientation.assign(nbody, Quat::Identity());
    velocity.assign(nbody, Vec3::Zero());
    angular_velocity.assign(nbody, Vec3::Zero());
    magnetic_force.assign(nbody, Vec3::Zero());
    magnetic_torque.assign(nbody, Vec3::Zero());
    sleep.assign(nbody, 0);
    rest_time.assign(nbody, 0.0);
    sleep_force.assign(nbody, Vec3::Zero());
    sleep_torque.assign(nbody, Vec3::Zero());
  }
};

/// Per-frame diagnostics (what happened between the previous frame and this one).
struct FrameDiagnostics {
  double kinetic_energy = 0;         ///< J (translation + rotation)
  double gravity_energy = 0;         ///< J, -sum m g.x (dynamic bodies)
  double magnetic_energy = 0;        ///< J, pair energy of the last substep (see magnetics::Result)
  Vec3 momentum = Vec3::Zero();      ///< kg m/s, dynamic bodies
  Vec3 angular_momentum = Vec3::Zero();  ///< kg m²/s about the world origin, dynamic bodies
  double magnetics_seconds = 0;      ///< wall time in the magnetics library
  double rigid_seconds = 0;          ///< wall time in Bullet
  long long cells_visited = 0;       ///< cell pairs + node pairs evaluated, summed over substeps
  long long cell_pairs = 0;          ///< of which cell-cell pairs in leaf blocks (magnetics::EvalStats)
  long long node_pairs = 0;          ///< of which aggregated node-node dipole pairs
  long long near_pairs = 0;          ///< cell pairs given the exact cuboid near field, summed
  int evaluations = 0;               ///< magnetics evaluations (one per substep, one per frame)
  int induction_iterations = 0;      ///< GMRES iterations summed over substeps
  double induction_residual = 0;     ///< largest final residual over the substeps
  int substeps = 0;                  ///< physics substeps taken (more than nominal when refined)
  /// Bodies stepped, summed over the substeps (a dynamic body that is awake and not held counts
  /// once per Bullet step): with per-island substeps, body_steps / (dynamic bodies x nominal
  /// steps) is how much of the world was refined.
  long long body_steps = 0;
  /// Change of the total energy (kinetic + gravity + magnetic) since the previous frame, J.
  /// Without moving kinematic bodies it should never be clearly positive (contact and friction
  /// only remove energy).
  double energy_drift = 0;
  double max_speed = 0;              ///< largest linear speed of a dynamic body at the frame, m/s
  int max_speed_body = -1;           ///< that body (scene index), -1 if none
  double max_penetration = 0;        ///< deepest contact penetration over the frame's substeps, m
  int penetration_a = -1, penetration_b = -1;  ///< the two bodies of that contact (-1 if none)
  int sleeping = 0;                  ///< bodies asleep at the frame (Scene::sleep_time)
  int wake_ups = 0;                  ///< sleeping bodies woken by a change of their magnetic force

  /// Kinetic + gravity + magnetic energy, J.
  double total_energy() const { return kinetic_energy + gravity_energy + magnetic_energy; }
};

}  // namespace magbake::sim
