#include "stuck_contacts.h"

#include <BulletDynamics/ConstraintSolver/btGeneric6DofSpring2Constraint.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace magbake::sim {
namespace {

Vec3 eig(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }
btVector3 bt(const Vec3& v) { return btVector3(v[0], v[1], v[2]); }
Mat3 mat(const btMatrix3x3& m) {
  Mat3 out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = m[r][c];
  return out;
}
btMatrix3x3 bt(const Mat3& m) {
  return btMatrix3x3(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
}

// Relative speed (m/s) below which a face contact counts as at rest: its points move by less
// than this fraction of the smaller body's smallest extent over the step.
constexpr double kRestFraction = 1e-3;
// Deepest interpenetration, as a fraction of the smaller body's smallest extent, at which a face
// contact may stick: a pair that has just snapped and still overlaps is left to the contact's
// position correction first (held, it would stay inside each other).
constexpr double kStickDepth = 5e-4;
// Largest friction impulse, as a share of what the contact's friction can carry (mu times its
// normal impulse), at which a face contact may stick: a pair whose friction was saturated is
// sliding, or was just let go, and stays free.
constexpr double kFrictionShare = 0.9;
// Share of the contact points' mean distance from their centroid used as the lever of the face's
// friction twist and of its tilting resistance (a square face's corners: the inscribed radius is
// 0.71 of their mean distance, the mean lever of uniform pressure 0.54; 0.5 stays inside both).
constexpr double kLeverShare = 0.5;
// A point or line contact between two permanent magnets (ball magnets) carries no couple of its
// own: their mutual torque holds them against rolling on each other, with a stiffness of about
// F_n d / 3 per radian. Held, it may carry the couple that would roll the pair by kRollTolerance
// (rad) before it found its own equilibrium: its lever is kRollTolerance d / 3.
constexpr double kRollTolerance = 0.01;

}  // namespace

int touching_points(const btPersistentManifold& manifold, Vec3 (&points)[4]) {
  int n = 0;
  for (int c = 0; c < manifold.getNumContacts() && n < 4; ++c) {
    const btManifoldPoint& pt = manifold.getContactPoint(c);
    if (pt.getDistance() >= kTouchingDistance) continue;
    points[n++] = eig(pt.getPositionWorldOnB());
  }
  return n;
}

bool spans_face(const Vec3* p, int n, double size) {
  double area2 = 0;  // twice the largest triangle's area, m²
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int q = j + 1; q < n; ++q) area2 = std::max(area2, (p[j] - p[i]).cross(p[q] - p[i]).norm());
  return area2 >= 0.01 * size * size;
}

// A joint's record (a, b, normal_in_a, mu, lever: kLeverShare x the contact points' mean distance
// from their centroid, or the roll lever; frames) and its Bullet constraints.
struct StuckContacts::Joint : StuckJoint {
  std::unique_ptr<btPoint2PointConstraint> point;  // at the contact's centroid
  std::unique_ptr<btGeneric6DofSpring2Constraint> turn;  // turns locked, translations free
  btJointFeedback point_feedback, turn_feedback;
};

StuckContacts::StuckContacts(std::vector<Body> bodies) : bodies_(std::move(bodies)) {}
StuckContacts::~StuckContacts() = default;

void StuckContacts::share(const std::vector<std::unique_ptr<btRigidBody>>& bodies, std::vector<Vec3>& force,
                          std::vector<Vec3>& torque) {
  const std::vector<Vec3> f0 = force, t0 = torque;
  shared(bodies, force, torque);
  moved_force_.resize(f0.size());
  moved_torque_.resize(t0.size());
  for (std::size_t i = 0; i < f0.size(); ++i) moved_force_[i] = force[i] - f0[i], moved_torque_[i] = torque[i] - t0[i];
}

void StuckContacts::shared(const std::vector<std::unique_ptr<btRigidBody>>& bodies, std::vector<Vec3>& force,
                           std::vector<Vec3>& torque) const {
  const std::size_t n = bodies_.size();
  if (joints_.empty()) return;
  std::vector<int> root(n), joints_of(n, 0);
  for (std::size_t i = 0; i < n; ++i) root[i] = static_cast<int>(i);
  auto find = [&](int i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  for (const auto& [key, j] : joints_) {
    ++joints_of[j->a], ++joints_of[j->b];
    root[find(j->a)] = find(j->b);
  }
  struct Group {
    double mass = 0;
    Vec3 moment = Vec3::Zero();  // sum of m_i x_i, kg·m
    Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
    magnetics::Mat3 inertia = magnetics::Mat3::Zero();
    bool anchored = false;  // joined to a static body
  };
  std::map<int, Group> groups;  // by root, in index order
  auto com = [&](std::size_t i) { return eig(bodies[i]->getCenterOfMassPosition()); };
  auto inertia = [&](std::size_t i) {  // world frame, kg·m²
    const btMatrix3x3 inv = bodies[i]->getInvInertiaTensorWorld();
    magnetics::Mat3 inv_i;
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) inv_i(row, col) = inv[row][col];
    return magnetics::Mat3(inv_i.inverse());
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!joints_of[i]) continue;
    Group& g = groups[find(static_cast<int>(i))];
    if (!bodies_[i].dynamic) {
      g.anchored = true;
      continue;
    }
    const double m = 1.0 / bodies[i]->getInvMass();
    g.mass += m;
    g.moment += m * com(i);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!joints_of[i] || !bodies_[i].dynamic) continue;
    Group& g = groups[find(static_cast<int>(i))];
    if (g.anchored) continue;
    const Vec3 r = com(i) - g.moment / g.mass;
    const double m = 1.0 / bodies[i]->getInvMass();
    g.force += force[i];
    g.torque += torque[i] + r.cross(force[i]);
    g.inertia += inertia(i) + m * (r.squaredNorm() * magnetics::Mat3::Identity() - r * r.transpose());
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!joints_of[i] || !bodies_[i].dynamic) continue;
    const Group& g = groups[find(static_cast<int>(i))];
    Vec3 f = Vec3::Zero(), t = Vec3::Zero();
    if (!g.anchored) {
      const Vec3 r = com(i) - g.moment / g.mass;
      const double m = 1.0 / bodies[i]->getInvMass();
      const Vec3 alpha = g.inertia.ldlt().solve(g.torque);
      f = m * (g.force / g.mass + alpha.cross(r));
      t = inertia(i) * alpha;
    }
    force[i] = f, torque[i] = t;
  }
}

void StuckContacts::before_step() {
  for (auto& [key, j] : joints_) {
    const btRigidBody& ra = j->point->getRigidBodyA();
    const btRigidBody& rb = j->point->getRigidBodyB();
    // Solved only while one of its bodies is solved (neither held nor asleep): a joint between
    // two bodies that sit out this step must not enter another island's solve.
    const bool live = ra.isActive() || rb.isActive();
    j->point->setEnabled(live);
    j->turn->setEnabled(live);
    for (btJointFeedback* f : {&j->point_feedback, &j->turn_feedback}) {
      f->m_appliedForceBodyA.setZero();
      f->m_appliedTorqueBodyA.setZero();
      f->m_appliedForceBodyB.setZero();
      f->m_appliedTorqueBodyB.setZero();
    }
  }
}

void StuckContacts::remove(btDiscreteDynamicsWorld& world, Joint& j) {
  world.removeConstraint(j.point.get());
  world.removeConstraint(j.turn.get());
}

void StuckContacts::add(btDiscreteDynamicsWorld& world, const std::vector<std::unique_ptr<btRigidBody>>& bodies,
                        const StuckJoint& rec) {
  btRigidBody& ra = *bodies[rec.a];
  btRigidBody& rb = *bodies[rec.b];
  auto joint = std::make_unique<Joint>();
  static_cast<StuckJoint&>(*joint) = rec;
  joint->point = std::make_unique<btPoint2PointConstraint>(ra, rb, bt(rec.pivot_a), bt(rec.pivot_b));
  joint->turn = std::make_unique<btGeneric6DofSpring2Constraint>(ra, rb, btTransform(bt(rec.basis_a), bt(rec.origin_a)),
                                                                 btTransform(bt(rec.basis_b), bt(rec.origin_b)));
  joint->turn->setLinearLowerLimit(btVector3(1, 1, 1));  // lower > upper: free
  joint->turn->setLinearUpperLimit(btVector3(-1, -1, -1));
  joint->turn->setAngularLowerLimit(btVector3(0, 0, 0));
  joint->turn->setAngularUpperLimit(btVector3(0, 0, 0));
  joint->point->setJointFeedback(&joint->point_feedback);
  joint->turn->setJointFeedback(&joint->turn_feedback);
  world.addConstraint(joint->point.get(), true);
  world.addConstraint(joint->turn.get(), true);
  joints_.emplace(std::make_pair(rec.a, rec.b), std::move(joint));
}

void StuckContacts::save(std::vector<StuckJoint>& out) const {
  out.clear();
  for (const auto& [key, j] : joints_) out.push_back(static_cast<const StuckJoint&>(*j));
}

void StuckContacts::restore(btDiscreteDynamicsWorld& world, const std::vector<std::unique_ptr<btRigidBody>>& bodies,
                            const std::vector<StuckJoint>& joints) {
  clear(world);
  for (const StuckJoint& rec : joints) {
    assert(rec.a >= 0 && rec.a < rec.b && rec.b < static_cast<int>(bodies.size()));
    add(world, bodies, rec);
  }
  // The velocities of the state as the last step's: the balance test of the next step sees the
  // change over that step, as it would have without the restart.
  last_v_.resize(bodies_.size());
  last_w_.resize(bodies_.size());
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    last_v_[i] = eig(bodies[i]->getLinearVelocity());
    last_w_[i] = eig(bodies[i]->getAngularVelocity());
  }
}

void StuckContacts::clear(btDiscreteDynamicsWorld& world) {
  for (auto& [key, j] : joints_) remove(world, *j);
  joints_.clear();
  last_v_.clear(), last_w_.clear();  // velocities of another state: no balance test against them
}

bool StuckContacts::stuck(int a, int b) const {
  return joints_.count({std::min(a, b), std::max(a, b)}) > 0;
}

void StuckContacts::normals(std::vector<std::vector<Vec3>>& out, std::vector<std::vector<std::uint8_t>>* stuck) const {
  for (const auto& [key, j] : joints_) {
    const btRigidBody& ra = j->point->getRigidBodyA();
    const Vec3 n = eig(ra.getWorldTransform().getBasis() * bt(j->normal_in_a));
    out[j->a].push_back(n);
    out[j->b].push_back(-n);
    if (stuck) (*stuck)[j->a].push_back(1), (*stuck)[j->b].push_back(1);
  }
}

void StuckContacts::after_step(btDiscreteDynamicsWorld& world, btCollisionDispatcher& dispatcher,
                               const std::vector<std::unique_ptr<btRigidBody>>& bodies, double h) {
  assert(h > 0);
  std::vector<int> joints_of(bodies_.size(), 0);
  for (const auto& [key, j] : joints_) ++joints_of[j->a], ++joints_of[j->b];
  moved_force_.resize(bodies_.size(), Vec3::Zero());
  moved_torque_.resize(bodies_.size(), Vec3::Zero());
  // Release: the joint's force on A (at the contact's centroid) and its couple, over the step,
  // against the contact's cone. The pair's contact points are off while it is held (Bullet does
  // not collide bodies joined by a constraint), so the joint carries the whole contact wrench.
  // The joints as they were in the step, as adjacency lists (other body, joint), and
  // side_load(): over the bodies reachable from `from` without crossing joint j, the sum of
  // share()'s moved forces and their moments (with the moved torques) about `pivot`; false when
  // `to` is reachable (a loop) or a static body is (its reaction is unknown).
  const std::size_t graph = joints_.empty() ? 0 : bodies_.size();  // nothing to cut without joints
  std::vector<std::vector<std::pair<int, const Joint*>>> adjacent(graph);
  for (const auto& [key, jt] : joints_) {
    adjacent[jt->a].push_back({jt->b, jt.get()});
    adjacent[jt->b].push_back({jt->a, jt.get()});
  }
  std::vector<int> seen_by(graph, -1);  // per body: the last traversal that reached it
  int traversal = 0;
  std::vector<int> stack;
  auto side_load = [&](const Joint& j, int from, int to, const Vec3& pivot, Vec3& f, Vec3& t) {
    f.setZero(), t.setZero();
    ++traversal;
    stack.assign(1, from);
    seen_by[from] = traversal;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      if (i == to || !bodies_[i].dynamic) return false;
      f += moved_force_[i];
      t += moved_torque_[i] + (eig(bodies[i]->getCenterOfMassPosition()) - pivot).cross(moved_force_[i]);
      for (const auto& [other, via] : adjacent[i]) {
        if (via == &j || seen_by[other] == traversal) continue;
        seen_by[other] = traversal;
        stack.push_back(other);
      }
    }
    return true;
  };
  for (auto it = joints_.begin(); it != joints_.end();) {
    Joint& j = *it->second;
    const btRigidBody& ra = j.point->getRigidBodyA();
    if (!ra.isActive() && !j.point->getRigidBodyB().isActive()) {  // not solved (held or asleep)
      ++it;
      continue;
    }
    const Vec3 n = eig(ra.getWorldTransform().getBasis() * bt(j.normal_in_a));
    const Vec3 pivot = eig(ra.getWorldTransform() * j.point->getPivotInA());
    // The wrench on A from B: the joints' (force at the pivot, couple), and what share() moved
    // off the loads of the bodies on A's side of this joint (the group cut here), which the
    // joint would carry had share() not moved it; or minus that of B's side when A's side holds
    // a static body. In a group with a loop of joints the cut is not unique: there, A's own
    // moved load shared among its joints (from the side with fewer joints).
    Vec3 moved_f = Vec3::Zero(), moved_t = Vec3::Zero();
    if (!side_load(j, j.a, j.b, pivot, moved_f, moved_t)) {
      if (side_load(j, j.b, j.a, pivot, moved_f, moved_t)) {
        moved_f = -moved_f, moved_t = -moved_t;
      } else {
        const bool from_a = bodies_[j.a].dynamic && (!bodies_[j.b].dynamic || joints_of[j.a] <= joints_of[j.b]);
        const int side = from_a ? j.a : j.b;
        const double sign = from_a ? 1.0 : -1.0;
        moved_f = sign * moved_force_[side] / std::max(1, joints_of[side]);
        const Vec3 at = eig(bodies[side]->getCenterOfMassPosition());
        moved_t = sign * moved_torque_[side] / std::max(1, joints_of[side]) + (at - pivot).cross(moved_f);
      }
    }
    // Over the step, about the pivot (the contact's centroid).
    const Vec3 force = eig(j.point_feedback.m_appliedForceBodyA) + moved_f;
    const Vec3 couple = eig(j.turn_feedback.m_appliedTorqueBodyA) + moved_t;
    const double fn = force.dot(n);
    const double shear = (force - fn * n).norm();
    const double twist = std::abs(couple.dot(n));
    const double tilt = (couple - couple.dot(n) * n).norm();
    if (fn > 0 && shear <= j.mu * fn && twist <= j.mu * fn * j.lever && tilt <= fn * j.lever) {
      ++it;
    } else {
      remove(world, j);
      it = joints_.erase(it);
    }
  }

  // Join: eligible face contacts at rest that press (a positive normal impulse). A face needs
  // three points, and one manifold per pair: compounds of several shapes (a manifold per
  // child) never stick.
  // Candidates are taken in pair order.
  auto pieces = [](const btCollisionObject* o) {  // a compound of several shapes
    const btCollisionShape* shape = o->getCollisionShape();
    return shape->isCompound() && static_cast<const btCompoundShape*>(shape)->getNumChildShapes() > 1;
  };
  std::vector<std::pair<std::pair<int, int>, btPersistentManifold*>> candidates;
  for (int k = 0; k < dispatcher.getNumManifolds(); ++k) {
    btPersistentManifold* mf = dispatcher.getManifoldByIndexInternal(k);
    if (mf->getNumContacts() < 1) continue;
    const int a = mf->getBody0()->getUserIndex(), b = mf->getBody1()->getUserIndex();
    if (a < 0 || b < 0 || a == b) continue;
    const Body &ba = bodies_[a], &bb = bodies_[b];
    if (!(ba.dynamic || bb.dynamic) || !ba.magnetic || !bb.magnetic || !(ba.permanent || bb.permanent)) continue;
    if (mf->getNumContacts() < 3 && !(ba.permanent && bb.permanent)) continue;
    if (pieces(mf->getBody0()) || pieces(mf->getBody1())) continue;
    candidates.push_back({{std::min(a, b), std::max(a, b)}, mf});
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  for (const auto& [key, mf] : candidates) {
    if (joints_.count(key)) continue;
    const auto [a, b] = key;
    const Body &ba = bodies_[a], &bb = bodies_[b];
    btRigidBody& ra = *bodies[a];
    btRigidBody& rb = *bodies[b];
    if (ra.isKinematicObject() || rb.isKinematicObject() || (!ra.isActive() && !rb.isActive())) continue;
    Vec3 p[4];
    const int n = touching_points(*mf, p);
    const double size = std::min(ba.extent, bb.extent);
    if (n < 1) continue;
    const bool face = n >= 3 && spans_face(p, n, size);
    if (!face && !(ba.permanent && bb.permanent)) continue;
    if (!face) {
      // Rest is not balance: a pair at the turning point of a swing is still, and pulled. Its
      // relative velocities must also have changed by less than the rest speed over the step.
      if (last_v_.size() != bodies_.size()) continue;
      const Vec3 dv = (eig(rb.getLinearVelocity()) - last_v_[b]) - (eig(ra.getLinearVelocity()) - last_v_[a]);
      const Vec3 dw = (eig(rb.getAngularVelocity()) - last_w_[b]) - (eig(ra.getAngularVelocity()) - last_w_[a]);
      if ((dv.norm() + 0.5 * size * dw.norm()) * h >= kRestFraction * size) continue;
    }
    double pressed = 0, slip = 0, depth = 0;
    btVector3 friction(0, 0, 0);  // the contact's friction impulse, N·s
    for (int c = 0; c < mf->getNumContacts(); ++c) {
      const btManifoldPoint& pt = mf->getContactPoint(c);
      if (pt.getDistance() >= kTouchingDistance) continue;
      pressed += pt.getAppliedImpulse();
      friction += pt.m_appliedImpulseLateral1 * pt.m_lateralFrictionDir1 + pt.m_appliedImpulseLateral2 * pt.m_lateralFrictionDir2;
      depth = std::max(depth, -static_cast<double>(pt.getDistance()));
      const btVector3& w = pt.getPositionWorldOnB();
      const btVector3 v = rb.getVelocityInLocalPoint(w - rb.getCenterOfMassPosition()) -
                          ra.getVelocityInLocalPoint(w - ra.getCenterOfMassPosition());
      slip = std::max(slip, static_cast<double>(v.length()));
    }
    // Friction that was at its limit in this step (a pair sliding slowly, or one just let go)
    // does not stick.
    const double mu = mf->getContactPoint(0).m_combinedFriction;
    if (pressed <= 0 || slip * h >= kRestFraction * size || depth > kStickDepth * size ||
        friction.length() > kFrictionShare * mu * pressed) {
      continue;
    }
    StuckJoint rec;
    rec.a = a, rec.b = b;
    // Bullet's normal on B points towards body 0; A is the key's first body.
    const btVector3 normal = mf->getContactPoint(0).m_normalWorldOnB * (mf->getBody0() == &ra ? 1.0 : -1.0);
    rec.normal_in_a = eig(ra.getWorldTransform().getBasis().transpose() * normal);
    rec.mu = mu;
    Vec3 centroid = Vec3::Zero();
    for (int i = 0; i < n; ++i) centroid += p[i] / n;
    if (face) {
      for (int i = 0; i < n; ++i) rec.lever += kLeverShare * (p[i] - centroid).norm() / n;
    } else {
      const double d = (eig(ra.getCenterOfMassPosition()) - eig(rb.getCenterOfMassPosition())).norm();
      rec.lever = kRollTolerance * d / 3.0;
    }
    rec.pivot_a = eig(ra.getWorldTransform().inverse() * bt(centroid));
    rec.pivot_b = eig(rb.getWorldTransform().inverse() * bt(centroid));
    btTransform at;
    at.setIdentity();
    at.setOrigin(bt(centroid));
    const btTransform fa = ra.getWorldTransform().inverse() * at, fb = rb.getWorldTransform().inverse() * at;
    rec.basis_a = mat(fa.getBasis()), rec.origin_a = eig(fa.getOrigin());
    rec.basis_b = mat(fb.getBasis()), rec.origin_b = eig(fb.getOrigin());
    // The pair no longer collides (its contact is the joint now); its stale points are dropped.
    add(world, bodies, rec);
    mf->clearManifold();
  }
  last_v_.resize(bodies_.size());
  last_w_.resize(bodies_.size());
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    last_v_[i] = eig(bodies[i]->getLinearVelocity());
    last_w_[i] = eig(bodies[i]->getAngularVelocity());
  }
}

}  // namespace magbake::sim
