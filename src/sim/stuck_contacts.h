// Face contacts of magnets at rest, held by a fixed joint while friction and the contact face
// could hold them (physics.md §8, "Stuck contacts").
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "magnetics/types.h"
#include "sim_state.h"

class btCollisionDispatcher;
class btDiscreteDynamicsWorld;
class btPersistentManifold;
class btRigidBody;

namespace magbake::sim {

using magnetics::Vec3;

/// Distance (m) below which a manifold point counts as touching (RigidWorld::contact_normals).
inline constexpr double kTouchingDistance = 1e-4;

/// The first (at most four) points of a manifold closer than kTouchingDistance, world frame,
/// on body B; returns how many.
int touching_points(const btPersistentManifold& manifold, Vec3 (&points)[4]);

/// Whether the points span a face: three of them span a triangle of at least half the square of
/// a tenth of `size` (m, the smaller body's smallest extent). A persistent manifold of a rolling
/// ball keeps stale points close together, which do not count; anything else is a point or line
/// contact, about which a body can roll or rock.
bool spans_face(const Vec3* points, int count, double size);

/// Stuck contacts (physics.md §8 item 11). Two magnets resting face to face feel stiff coupled
/// magnetic modes (a pair of 1 cm N42 cubes: a common yaw with opposite sliding at
/// 1.6 N·m/rad, h·omega = 3.6 at dt 1 ms) that an explicit force resolves only in short pieces,
/// although static friction and the contact face hold the pair still. Here such a pair is held
/// at its current relative pose by two Bullet constraints (a point-to-point joint at the
/// contact's centroid and a 6-dof constraint locking the rotations only), which the constraint
/// solver resolves implicitly, so the pair takes a substep in one piece. After every step the
/// wrench that the pair exchanged through the joints is checked against what the contact alone
/// could carry: a compressive normal force F_n, a shear within mu F_n, a twist within mu F_n r
/// and a tilting torque within F_n r (r half the contact points' mean distance from their
/// centroid); outside that cone the joints are removed and the pair moves freely again.
/// Joints are made only for a face contact whose points move relative to each other by less
/// than 1e-3 of the smaller body's smallest extent over the step, and whose friction is below
/// 90% of its limit, so holding removes at most the kinetic energy of that relative motion and
/// never adds any. Two permanent magnets in a point or line contact (ball magnets in a chain)
/// are held the same way when they are also balanced (their relative velocities changed by less
/// than that over the step: a swing's turning point is still but not balanced); such a contact
/// carries no couple of its own, and is let go when the couple it holds would roll the pair by
/// more than 0.01 rad against the magnets' mutual stiffness (about F_n d / 3 per radian).
class StuckContacts {
 public:
  /// What decides whether a pair may stick, per scene body.
  struct Body {
    bool dynamic = false;    ///< moved by forces (static and kinematic bodies are not)
    bool magnetic = false;   ///< has a magnetic material
    bool permanent = false;  ///< has a permanently magnetized material
    double extent = 0;       ///< smallest bounding-box extent of its shape, m
  };
  explicit StuckContacts(std::vector<Body> bodies);
  ~StuckContacts();
  StuckContacts(const StuckContacts&) = delete;
  StuckContacts& operator=(const StuckContacts&) = delete;

  /// Before a Bullet step, with the forces (N) and torques (N·m, about the centre of mass) to be
  /// applied, world frame, per scene body: each group of bodies held together (through any chain
  /// of joints) gets its summed force and torque shared as one rigid body would feel them,
  /// F_i = m_i (a + alpha x r_i), T_i = I_i alpha (r_i from the group's centre of mass, a and
  /// alpha the group's accelerations; a group joined to a static body gets none). Their sum and
  /// moment are unchanged, so momentum and angular momentum are kept exactly, and the joints carry
  /// only what holds the group together besides: the pull of two magnets on each other, hundreds
  /// of times their weight, no longer passes through Bullet's iterative solve (whose residual,
  /// against the table's friction, turned a held pair slowly on its table). What was taken from
  /// or given to each body is kept for the release test of after_step().
  void share(const std::vector<std::unique_ptr<btRigidBody>>& bodies, std::vector<Vec3>& force,
             std::vector<Vec3>& torque);
  /// share()'s shares, without recording anything: what each body of a held group feels of the
  /// group's load from outside it (the force guard's input, Simulator::body_splits).
  void shared(const std::vector<std::unique_ptr<btRigidBody>>& bodies, std::vector<Vec3>& force,
              std::vector<Vec3>& torque) const;
  /// Before a Bullet step: clears the joints' force feedback.
  void before_step();
  /// After a Bullet step of h seconds: removes the joints whose pair left the contact's cone or
  /// its face contact, and joins the eligible face contacts at rest (a permanent magnet against
  /// a magnetic body, at least one of them dynamic and not kinematic). `bodies` are Bullet's
  /// bodies by scene index (their user index).
  void after_step(btDiscreteDynamicsWorld& world, btCollisionDispatcher& dispatcher,
                  const std::vector<std::unique_ptr<btRigidBody>>& bodies, double h);
  /// Removes every joint and forgets the last step's velocities (a new state was set).
  void clear(btDiscreteDynamicsWorld& world);
  /// The joints now, in (a, b) order (SimState::stuck_joints).
  void save(std::vector<StuckJoint>& out) const;
  /// Replaces the joints by `joints` (records of save(), e.g. from a cache; a < b, valid
  /// indices), added to `world` in their order, and takes the bodies' current velocities as the
  /// last step's (the balance test of after_step()).
  void restore(btDiscreteDynamicsWorld& world, const std::vector<std::unique_ptr<btRigidBody>>& bodies,
               const std::vector<StuckJoint>& joints);
  /// Appends, per scene body, the contact normal of each of its stuck contacts (world frame,
  /// pushing the body away from its partner) to `out`, and a 1 to `stuck` (optional) beside it.
  /// Held pairs have no contact points of their own (RigidWorld::contact_normals).
  void normals(std::vector<std::vector<Vec3>>& out, std::vector<std::vector<std::uint8_t>>* stuck) const;
  /// Whether bodies a and b (scene indices) are held together now.
  bool stuck(int a, int b) const;
  /// Number of pairs held together now.
  int count() const { return static_cast<int>(joints_.size()); }

 private:
  struct Joint;
  static void remove(btDiscreteDynamicsWorld& world, Joint& joint);
  /// Makes the joints of `rec` and adds them to `world`.
  void add(btDiscreteDynamicsWorld& world, const std::vector<std::unique_ptr<btRigidBody>>& bodies, const StuckJoint& rec);
  std::vector<Body> bodies_;
  std::vector<Vec3> moved_force_, moved_torque_;  // per body: share()'s change to its force, torque
  std::vector<Vec3> last_v_, last_w_;  // per body: velocities after the previous step (m/s, rad/s)
  std::map<std::pair<int, int>, std::unique_ptr<Joint>> joints_;  // by (smaller, larger) index
};

}  // namespace magbake::sim
