#include "rigid_world.h"

#include "skin_contacts.h"
#include "stuck_contacts.h"

#include <BulletCollision/CollisionDispatch/btInternalEdgeUtility.h>
#include <HACD/hacdHACD.h>
#include <btBulletDynamicsCommon.h>
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

namespace magbake::sim {
namespace {

btVector3 bt(const Vec3& v) { return btVector3(v[0], v[1], v[2]); }
Vec3 eig(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }
btQuaternion bt(const Quat& q) { return btQuaternion(q.x(), q.y(), q.z(), q.w()); }
Quat eig(const btQuaternion& q) { return Quat(q.w(), q.x(), q.y(), q.z()); }

// Convex hulls approximating a closed mesh (HACD, Bullet extras), for dynamic concave bodies.
std::vector<std::vector<Vec3>> convex_pieces(const geometry::Tessellation& t) {
  // HACD works in normalized coordinates: scale to a unit bounding box.
  Eigen::AlignedBox3d bb;
  for (const Vec3& v : t.vertices) bb.extend(v);
  const double s = 1.0 / std::max(bb.sizes().maxCoeff(), 1e-12);
  std::vector<HACD::Vec3<HACD::Real>> pts;
  std::vector<HACD::Vec3<long>> tris;
  for (const Vec3& v : t.vertices) pts.emplace_back((v[0] - bb.center()[0]) * s, (v[1] - bb.center()[1]) * s, (v[2] - bb.center()[2]) * s);
  for (const auto& f : t.triangles) tris.emplace_back(f[0], f[1], f[2]);
  HACD::HACD h;
  h.SetPoints(pts.data());
  h.SetNPoints(pts.size());
  h.SetTriangles(tris.data());
  h.SetNTriangles(tris.size());
  h.SetCompacityWeight(0.1);
  h.SetVolumeWeight(0.0);
  h.SetNClusters(1);
  h.SetNVerticesPerCH(64);
  h.SetConcavity(0.03);
  h.SetAddExtraDistPoints(false);
  h.SetAddNeighboursDistPoints(false);
  h.SetAddFacesPoints(false);
  h.Compute();
  std::vector<std::vector<Vec3>> out;
  for (std::size_t c = 0; c < h.GetNClusters(); ++c) {
    std::vector<HACD::Vec3<HACD::Real>> cp(h.GetNPointsCH(c));
    std::vector<HACD::Vec3<long>> ct(h.GetNTrianglesCH(c));
    h.GetCH(c, cp.data(), ct.data());
    std::vector<Vec3> hull;
    for (const auto& p : cp) hull.push_back(Vec3(p.X(), p.Y(), p.Z()) / s + bb.center());
    if (hull.size() >= 4) out.push_back(std::move(hull));
  }
  return out;
}

// Smooths contacts of bodies rolling over the internal edges of static triangle meshes.
bool adjust_internal_edges(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int part0, int index0,
                           const btCollisionObjectWrapper* w1, int part1, int index1) {
  (void)part0, (void)index0;
  btAdjustInternalEdgeContacts(cp, w1, w0, part1, index1);
  return true;
}

// Bullet's world with two changes before each contact solve, for every contact point of a
// magnetic body: its point on A is moved onto the line through its point on B along the contact
// normal (p_A = p_B + d n), and its warm-start impulses are cleared. Bullet applies a contact impulse j at p_A to one body and -j at p_B to the
// other; a stale persistent point whose two ends have drifted apart sideways (by 0.1-1 um in a
// snapped, spinning pair) then applies a net torque (p_A - p_B) x j. Against a magnetic pull of
// tens of newtons that torque is what turned a magnetically held dumbbell over (its angular
// momentum lost or doubled within 0.1 s, measured in Bullet alone with a constant 55 N pull);
// with both ends on the normal every impulse conserves angular momentum exactly.
class ContactWorld : public btDiscreteDynamicsWorld {
 public:
  ContactWorld(btDispatcher* d, btBroadphaseInterface* b, btConstraintSolver* s, btCollisionConfiguration* c,
               const std::vector<bool>* magnetic, const std::vector<double>* aabb_pad)
      : btDiscreteDynamicsWorld(d, b, s, c), magnetic_(magnetic), aabb_pad_(aabb_pad) {}

  // Bullet pads every broadphase box by gContactBreakingThreshold, 2 cm, whatever the body's
  // size: 2 mm spheres 8 mm apart then all overlapped each other up to 4.4 cm away, so the pair
  // count (and the narrowphase work and memory) grew as N^2 (issue 13: 1.0 GB at N = 1000). Here
  // each box is padded by its own body's pad (RigidWorld: at most 2 cm, half the body's smallest
  // extent for small bodies), which still covers Bullet's contact-breaking distance (0.02 of a
  // shape's size) and our contact skin; otherwise as btCollisionWorld::updateSingleAabb.
  void updateAabbs() override {
    for (int i = 0; i < m_collisionObjects.size(); ++i) {
      btCollisionObject* o = m_collisionObjects[i];
      if (!m_forceUpdateAllAabbs && !o->isActive()) continue;
      const int body = o->getUserIndex();
      const btScalar pad = body >= 0 ? btScalar((*aabb_pad_)[body]) : gContactBreakingThreshold;
      const btVector3 grow(pad, pad, pad);
      btVector3 lo, hi;
      o->getCollisionShape()->getAabb(o->getWorldTransform(), lo, hi);
      lo -= grow, hi += grow;
      if (getDispatchInfo().m_useContinuous && o->getInternalType() == btCollisionObject::CO_RIGID_BODY &&
          !o->isStaticOrKinematicObject()) {
        btVector3 lo2, hi2;  // the box at the end of the step too (swept)
        o->getCollisionShape()->getAabb(o->getInterpolationWorldTransform(), lo2, hi2);
        lo.setMin(lo2 - grow), hi.setMax(hi2 + grow);
      }
      if (o->isStaticObject() || (hi - lo).length2() < btScalar(1e12)) {
        m_broadphasePairCache->setAabb(o->getBroadphaseHandle(), lo, hi, m_dispatcher1);
      } else {
        o->setActivationState(DISABLE_SIMULATION);  // as Bullet does for a runaway body
      }
    }
  }

  // Contacts of cylinders (convex hulls, Impl::cylinder_hull) are made afresh in every step:
  // their manifolds are emptied before collision detection, so the clipped contact face of this
  // step is all there is. Kept, a persistent manifold's four slots held stale points of the face a
  // rolling cylinder had left (inside the breaking distance), and a rim that sank elsewhere was
  // seen only when it replaced one of them, 0.1 mm deep (physics.md §8 item 10).
  void performDiscreteCollisionDetection() override {
    auto hull = [](const btCollisionObject* o) {
      return o->getCollisionShape()->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE;
    };
    for (int k = 0; k < m_dispatcher1->getNumManifolds(); ++k) {
      btPersistentManifold* mf = m_dispatcher1->getManifoldByIndexInternal(k);
      if (hull(mf->getBody0()) || hull(mf->getBody1())) mf->clearManifold();
    }
    btDiscreteDynamicsWorld::performDiscreteCollisionDetection();
    for (int k = 0; k < m_dispatcher1->getNumManifolds(); ++k) add_hull_vertices_in_box(m_dispatcher1->getManifoldByIndexInternal(k));
  }

  // A cylinder hull's vertices inside a box, added to their pair's manifold when they are deeper
  // than anything Bullet found. Bullet's SAT clipping (btPolyhedralContactClipping) misses a
  // tilted cylinder's rim on a box face: at 10-34 degrees of tilt with the rim 0.17 mm into the
  // box it returned one or two points 0.6-1.6 mm above the face, so a cylinder rolling on its rim
  // sank up to 3 mm into a table over a dozen steps and was then thrown out (an N42 cylinder
  // tipped over by a steel ball gained 4-10% of the pair's binding energy; a wooden one rolling
  // on its rim, 63%). Each vertex takes the box face it is least deep behind (normal and depth),
  // as the box-box skin does; the four deepest are added (Bullet's manifold keeps four).
  static void add_hull_vertices_in_box(btPersistentManifold* mf) {
    const btCollisionObject *o0 = mf->getBody0(), *o1 = mf->getBody1();
    auto type = [](const btCollisionObject* o) { return o->getCollisionShape()->getShapeType(); };
    const bool hull_first = type(o0) == CONVEX_HULL_SHAPE_PROXYTYPE && type(o1) == BOX_SHAPE_PROXYTYPE;
    const bool hull_second = type(o1) == CONVEX_HULL_SHAPE_PROXYTYPE && type(o0) == BOX_SHAPE_PROXYTYPE;
    if (!hull_first && !hull_second) return;
    const btCollisionObject* ho = hull_first ? o0 : o1;
    const btCollisionObject* bo = hull_first ? o1 : o0;
    const auto* hs = static_cast<const btConvexHullShape*>(ho->getCollisionShape());
    const auto* bs = static_cast<const btBoxShape*>(bo->getCollisionShape());
    const btVector3 half = bs->getHalfExtentsWithMargin();
    const btTransform& tb = bo->getWorldTransform();
    const btTransform to_box = tb.inverse() * ho->getWorldTransform();
    const btScalar threshold = mf->getContactBreakingThreshold();
    btScalar found = std::numeric_limits<btScalar>::infinity();  // deepest point Bullet found
    for (int c = 0; c < mf->getNumContacts(); ++c) found = std::min(found, mf->getContactPoint(c).getDistance());
    struct Vertex {
      btScalar depth;          // signed distance to the box face, m (negative inside)
      btVector3 at, on, normal;  // world: the vertex, its point on the face, the face's outward normal
    };
    std::vector<Vertex> inside;
    const btVector3* v = hs->getUnscaledPoints();
    for (int i = 0; i < hs->getNumPoints(); ++i) {
      const btVector3 p = to_box * v[i];
      int axis = -1;
      btScalar pen = std::numeric_limits<btScalar>::infinity();
      for (int a = 0; a < 3; ++a) {
        const btScalar pa = half[a] - std::abs(p[a]);
        if (pa < pen) pen = pa, axis = a;
      }
      if (-pen > 0) continue;  // outside the box (a vertex beside it touches through Bullet's points)
      btVector3 n(0, 0, 0), q = p;
      n[axis] = p[axis] < 0 ? -1 : 1;
      q[axis] = n[axis] * half[axis];
      inside.push_back({-pen, tb * p, tb * q, tb.getBasis() * n});
    }
    if (inside.empty()) return;
    std::sort(inside.begin(), inside.end(), [](const Vertex& a, const Vertex& b) { return a.depth < b.depth; });
    // Only when Bullet's points miss the deepest vertex by more than 1 um (its own points are kept).
    if (!(inside[0].depth < found - btScalar(1e-6))) return;
    for (std::size_t k = 0; k < inside.size() && k < 4 && inside[k].depth < threshold; ++k) {
      const Vertex& x = inside[k];
      // Bullet's convention: the normal on body 1 points towards body 0; distance (pA - pB) . n.
      const btVector3 n = hull_first ? x.normal : -x.normal;
      const btVector3 pb = hull_first ? x.on : x.at;
      const btVector3 pa = pb + n * x.depth;
      btManifoldPoint pt(o0->getWorldTransform().invXform(pa), o1->getWorldTransform().invXform(pb), n, x.depth);
      pt.m_positionWorldOnA = pa;
      pt.m_positionWorldOnB = pb;
      pt.m_combinedFriction = btManifoldResult::calculateCombinedFriction(o0, o1);
      pt.m_combinedRestitution = btManifoldResult::calculateCombinedRestitution(o0, o1);
      pt.m_combinedRollingFriction = btManifoldResult::calculateCombinedRollingFriction(o0, o1);
      pt.m_combinedSpinningFriction = btManifoldResult::calculateCombinedSpinningFriction(o0, o1);
      const int slot = mf->getCacheEntry(pt);
      if (slot >= 0) {
        mf->replaceContactPoint(pt, slot);
      } else {
        mf->addManifoldPoint(pt);
      }
    }
  }

  void solveConstraints(btContactSolverInfo& info) override {
    for (int k = 0; k < m_dispatcher1->getNumManifolds(); ++k) {
      btPersistentManifold* mf = m_dispatcher1->getManifoldByIndexInternal(k);
      const int a = mf->getBody0()->getUserIndex(), b = mf->getBody1()->getUserIndex();
      if ((a < 0 || !(*magnetic_)[a]) && (b < 0 || !(*magnetic_)[b])) continue;
      for (int c = 0; c < mf->getNumContacts(); ++c) {
        btManifoldPoint& pt = mf->getContactPoint(c);
        pt.m_positionWorldOnA = pt.m_positionWorldOnB + pt.m_normalWorldOnB * pt.getDistance();
        // No warm start: Bullet would start the solve from 85% of last substep's impulses, which
        // are wrong once the magnetic pull has changed; the error showed up as hops of snapped
        // magnets (a snapped cube pair gained 2.2% of its binding energy at dt 1 ms with warm
        // starting, 1.0% without). Other contacts keep it.
        pt.m_appliedImpulse = 0;
        pt.m_appliedImpulseLateral1 = 0;
        pt.m_appliedImpulseLateral2 = 0;
      }
    }
    btDiscreteDynamicsWorld::solveConstraints(info);
  }

 private:
  const std::vector<bool>* magnetic_;  // per body, owned by RigidWorld::Impl
  const std::vector<double>* aabb_pad_;  // per body, m, owned by RigidWorld::Impl
};

}  // namespace

struct RigidWorld::Impl {
  const scene::Scene& scene;
  btDefaultCollisionConfiguration config;
  SkinBoxBoxCreateFunc box_box;  // contacts from touching on (skin_contacts.h)
  SkinSphereSphereCreateFunc sphere_sphere;
  // Bullet's world and what carries over between its steps (pair cache, contact manifolds,
  // solver): made afresh by make_world() at every frame (RigidWorld::reset). Declared in the
  // order they are built; the world is destroyed first.
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;  // every shape, children included
  std::vector<std::unique_ptr<btTriangleMesh>> meshes;
  std::vector<std::unique_ptr<btTriangleInfoMap>> edge_infos;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::vector<bool> magnetic;    // per body: has magnetic material
  std::vector<bool> permanent;   // per body: has permanently magnetized material
  std::vector<double> extent;    // per body: smallest bounding-box extent of its shape, m
  // Per body: how far a turn about its centre of mass can move its surface, m (half its bounding
  // box's diagonal plus the centre's offset; 0 for a sphere about its centre, which a turn maps
  // onto itself).
  std::vector<double> turn_reach;
  std::vector<double> aabb_pad;  // per body: broadphase box padding, m (ContactWorld::updateAabbs)
  std::unique_ptr<StuckContacts> stuck;  // face contacts of magnets at rest, held by joints
  std::vector<Vec3> shared_force, shared_torque;  // per body: step()'s forces after StuckContacts::share
  // Bullet's dynamic-tree margin (the global gDbvtMargin, 5 cm by default: a proxy's tree box
  // is that much larger than its AABB, and pairs live while tree boxes overlap). Set to this
  // world's value before every Bullet call that runs the broadphase, since it is a global.
  double dbvt_margin = 0.05;
  // Scene::sleep_time: Bullet's global gDeactivationTime (how long a body must be below its sleep
  // speeds), set before every step like gDbvtMargin; 0 = no dynamic body sleeps.
  double sleep_time = 0;
  // Collision shapes shared by bodies of the same scene shape (Bullet allows sharing): a heap of
  // 50 identical meshes is decomposed into convex pieces once, not 50 times.
  std::map<std::tuple<const geometry::Shape*, bool, double>, btCollisionShape*> shared;
  // Bullet's body frame in the scene body frame: x_body = principal * x_bullet + origin.
  std::vector<Mat3> principal;
  std::vector<Vec3> origin;
  // The scene's joints (format 1.1) as Bullet constraints, made afresh with the world at every
  // reset (their warm-start impulses are not part of the state, so a resumed bake matches).
  std::vector<std::unique_ptr<btTypedConstraint>> joints;

  explicit Impl(const scene::Scene& s) : scene(s) {}

  // Every body at the state's pose and velocities (interpolation transform and velocities too,
  // so nothing of the previous state is left in a body), activation from its sleep state.
  void put_bodies(const SimState& s) {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      btRigidBody* b = bodies[i].get();
      const btTransform tr = bullet_transform(int(i), s.orientation[i], s.com_position[i]);
      b->setWorldTransform(tr);
      b->setInterpolationWorldTransform(tr);
      b->setCenterOfMassTransform(tr);
      const bool dynamic = scene.bodies[i].motion == scene::Motion::kDynamic;
      // Bullet's origin is the centre of mass for dynamic bodies.
      const btVector3 v = dynamic ? bt(s.velocity[i]) : btVector3(0, 0, 0);
      const btVector3 w = dynamic ? bt(s.angular_velocity[i]) : btVector3(0, 0, 0);
      b->setLinearVelocity(v);
      b->setAngularVelocity(w);
      b->setInterpolationLinearVelocity(v);
      b->setInterpolationAngularVelocity(w);
      if (dynamic && sleep_time > 0 && i < s.sleep.size()) {
        static constexpr int kBullet[] = {ACTIVE_TAG, WANTS_DEACTIVATION, ISLAND_SLEEPING};
        b->forceActivationState(kBullet[std::min<int>(s.sleep[i], 2)]);
        b->setDeactivationTime(btScalar(s.rest_time[i]));
      } else if (dynamic) {
        b->forceActivationState(DISABLE_DEACTIVATION);
      }
      b->clearForces();
    }
  }

  // A new Bullet world with our settings and no bodies (the constructor and reset() add them).
  void make_world() {
    world.reset();
    solver.reset();
    broadphase.reset();
    dispatcher.reset();
    dispatcher = std::make_unique<btCollisionDispatcher>(&config);
    broadphase = std::make_unique<btDbvtBroadphase>();
    solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    world = std::make_unique<ContactWorld>(dispatcher.get(), broadphase.get(), solver.get(), &config, &magnetic, &aabb_pad);
    dispatcher->registerCollisionCreateFunc(BOX_SHAPE_PROXYTYPE, BOX_SHAPE_PROXYTYPE, &box_box);
    dispatcher->registerCollisionCreateFunc(SPHERE_SHAPE_PROXYTYPE, SPHERE_SHAPE_PROXYTYPE, &sphere_sphere);
    world->setGravity(bt(scene.gravity));
    world->getDispatchInfo().m_deterministicOverlappingPairs = true;
    // Polyhedral pairs (a cylinder against a box, a cylinder or a triangle of a static mesh) clip
    // their contact faces along the separating axis found by SAT, not along GJK's normal: with
    // GJK's normal (computed between margin-shrunk cores) a cylinder lying on a box clipped the
    // wrong facet while its rim sank 0.15 mm, and the late push-out gained 7-20% of the pair's
    // binding energy at any dt (physics.md §8 item 10). The convex pieces of dynamic meshes have
    // no polyhedral features and stay with GJK: given them, Bowl2008's iron digits (HACD pieces)
    // against the bowl's triangles threw 28 bodies out of the scene.
    world->getDispatchInfo().m_enableSatConvex = true;
    btContactSolverInfo& si = world->getSolverInfo();
    si.m_numIterations = 20;
    // Stop iterating once no contact row changes a velocity by more than 1e-7 m/s (Bullet's
    // residual is the largest squared velocity change of an iteration). Bullet's default, 0, runs
    // all 20 iterations; measured on a magnetically held spinning pair (55 N pull, 1 cm cubes),
    // the solve converges in 8-10 iterations to a residual of 1e-15, but carried on to 20 it ended
    // at 1e-9, unconverged, and every few hundred substeps the pair "clacked": its cubes' spins
    // jumped by up to 90 rad/s for a substep (tests/sim/contact_test.cpp, physics.md §8).
    si.m_leastSquaresResidualThreshold = 1e-14;
    // Every island in a solve of its own: Bullet batches small islands into one solve, and with the
    // residual test above the batch's iteration count would depend on its other islands, so a
    // body's motion would depend on unrelated bodies elsewhere in the scene (physics.md §8 item 9).
    si.m_minimumSolverBatchSize = 1;
    si.m_splitImpulse = 1;
    si.m_splitImpulsePenetrationThreshold = -0.0002;  // cm-scale bodies (Bullet assumes metres)
  }

  btCollisionShape* own(btCollisionShape* sh) {
    shapes.emplace_back(sh);
    return sh;
  }

  // A cylinder hull's margin lies outside its vertices (a box's and a btCylinderShape's inside
  // their sizes): GJK pairs (a sphere on the cylinder) meet the hull grown by it, SAT-clipped
  // pairs the vertices themselves. At most 1 um, so that both see the same surface (a steel ball
  // resting on a cylinder magnet sat 10 um above it with 10 um).
  static double hull_margin(double margin) { return std::min(margin, 1e-6); }

  // A cylinder as the convex hull of its area-true prism (geometry::CylinderShape::surface),
  // its sides within 2e-3 of the radius of the circle (50 sides), with polyhedral features. Bullet's
  // btCylinderShape goes through GJK, which finds one contact point per step: a cylinder lying
  // on a face (a line contact) rocked about that point until its far rim sank 0.16 mm unseen,
  // and the push-out then threw the pair apart (a magnet box and a cylinder gained 10-20% of
  // their binding energy at any dt, physics.md §8). Polyhedral hulls get the whole clipped
  // contact face in every step, like boxes (Bullet's btPolyhedralContactClipping).
  btCollisionShape* cylinder_hull(const geometry::Shape& shape, double radius, double margin) {
    std::vector<Vec3> v;
    std::vector<Eigen::Vector3i> t;
    shape.surface(2e-3 * radius, v, t);
    auto* h = new btConvexHullShape();
    for (const Vec3& p : v) h->addPoint(bt(p), false);
    h->recalcLocalAabb();
    h->setMargin(hull_margin(margin));
    h->initializePolyhedralFeatures();
    return own(h);
  }

  // Collision shape of a scene shape in its own frame.
  btCollisionShape* make_shape(const scene::ShapeDesc& d, bool dynamic, double margin) {
    using geometry::ShapeKind;
    switch (d.kind) {
      case ShapeKind::kBox: {
        auto* s = new btBoxShape(bt(0.5 * d.size));
        s->setMargin(margin);
        s->initializePolyhedralFeatures();
        return own(s);
      }
      case ShapeKind::kSphere: return own(new btSphereShape(d.radius));
      case ShapeKind::kCylinder: return cylinder_hull(*d.shape, d.radius, margin);
      case ShapeKind::kTorus:
      case ShapeKind::kMesh: break;
    }
    const geometry::Tessellation t = geometry::tessellate(*d.shape, 48);
    if (!dynamic) {
      // Static and kinematic concave shapes: a BVH triangle mesh with internal-edge info.
      auto mesh = std::make_unique<btTriangleMesh>(true, false);
      for (const auto& f : t.triangles) mesh->addTriangle(bt(t.vertices[f[0]]), bt(t.vertices[f[1]]), bt(t.vertices[f[2]]));
      auto* s = new btBvhTriangleMeshShape(mesh.get(), true);
      s->setMargin(margin);
      own(s);
      auto info = std::make_unique<btTriangleInfoMap>();
      btGenerateInternalEdgeInfo(s, info.get());
      edge_infos.push_back(std::move(info));
      meshes.push_back(std::move(mesh));
      return s;
    }
    // Dynamic concave shapes: a compound of convex hulls.
    std::vector<std::vector<Vec3>> pieces;
    if (d.kind == ShapeKind::kTorus) {
      // Exact-enough sectors: the hull of the tube between two angles.
      const int n = 24, m = 16;
      for (int k = 0; k < n; ++k) {
        std::vector<Vec3> hull;
        for (int e = 0; e <= 1; ++e) {
          const double a = 2 * std::numbers::pi * (k + e) / n;
          for (int j = 0; j < m; ++j) {
            const double b = 2 * std::numbers::pi * j / m;
            const double rho = d.major + d.minor * std::cos(b);
            hull.emplace_back(rho * std::cos(a), rho * std::sin(a), d.minor * std::sin(b));
          }
        }
        pieces.push_back(hull);
      }
    } else {
      pieces = convex_pieces(t);
    }
    auto* compound = new btCompoundShape();
    own(compound);
    for (const auto& hull : pieces) {
      auto* h = new btConvexHullShape();
      for (const Vec3& p : hull) h->addPoint(bt(p), false);
      h->recalcLocalAabb();
      h->setMargin(margin);
      own(h);
      btTransform id;
      id.setIdentity();
      compound->addChildShape(id, h);
    }
    return compound;
  }

  // A frame given in the scene body frame of body b (the world if b < 0) in Bullet's frame of
  // that body: x_bullet = P^T (x_body - o).
  btTransform joint_frame(int b, const magnetics::Pose& f, const Quat& turn = Quat::Identity()) const {
    const Mat3 Pt = b < 0 ? Mat3::Identity() : Mat3(principal[b].transpose());
    const Vec3 o = b < 0 ? Vec3::Zero() : origin[b];
    btTransform tr;
    tr.setOrigin(bt(Vec3(Pt * (f.position - o))));
    tr.setBasis(btMatrix3x3(bt(Quat(Pt * (f.rotation * turn).toRotationMatrix()).normalized())));
    return tr;
  }

  void clear_joints() {
    for (auto& c : joints) world->removeConstraint(c.get());
    joints.clear();
  }

  // The scene's joints between the current bodies; collisions between the two bodies of a joint
  // are off (a needle on its pin, a hinge's leaves).
  void make_joints() {
    for (const scene::Joint& j : scene.joints) {
      btRigidBody& a = *bodies[j.a];
      btRigidBody& b = j.b >= 0 ? *bodies[j.b] : btTypedConstraint::getFixedBody();
      std::unique_ptr<btTypedConstraint> c;
      switch (j.type) {
        case scene::JointType::kHinge: {
          auto h = std::make_unique<btHingeConstraint>(a, b, joint_frame(j.a, j.frame_a), joint_frame(j.b, j.frame_b), false);
          if (j.limits) h->setLimit(btScalar(j.limits->first), btScalar(j.limits->second));
          c = std::move(h);
          break;
        }
        case scene::JointType::kBall:
          c = std::make_unique<btPoint2PointConstraint>(a, b, joint_frame(j.a, j.frame_a).getOrigin(),
                                                         joint_frame(j.b, j.frame_b).getOrigin());
          break;
        case scene::JointType::kFixed:
          c = std::make_unique<btFixedConstraint>(a, b, joint_frame(j.a, j.frame_a), joint_frame(j.b, j.frame_b));
          break;
        case scene::JointType::kSlider: {
          // Bullet slides along its frames' x: turn the joint frame's z (the axis) onto x, and give
          // b first, so that Bullet's position is a's slide along +axis relative to b.
          const Quat z_to_x(Eigen::AngleAxisd(-std::numbers::pi / 2, Vec3::UnitY()));
          auto sl = std::make_unique<btSliderConstraint>(b, a, joint_frame(j.b, j.frame_b, z_to_x),
                                                         joint_frame(j.a, j.frame_a, z_to_x), true);
          if (j.limits) {
            sl->setLowerLinLimit(btScalar(j.limits->first));
            sl->setUpperLinLimit(btScalar(j.limits->second));
          } else {
            sl->setLowerLinLimit(1), sl->setUpperLinLimit(-1);  // free
          }
          sl->setLowerAngLimit(0), sl->setUpperAngLimit(0);  // no turning about the axis
          c = std::move(sl);
          break;
        }
      }
      world->addConstraint(c.get(), true);
      joints.push_back(std::move(c));
    }
  }

  btTransform bullet_transform(int b, const Quat& q_body, const Vec3& com_world) const {
    // x_world = R (x_body - com) + com_world; x_body = P x_bullet + o.
    const Mat3 R = q_body.toRotationMatrix();
    const Vec3 pos = com_world + R * (origin[b] - scene.bodies[b].com);
    btTransform tr;
    tr.setOrigin(bt(pos));
    tr.setRotation(bt(Quat(R * principal[b]).normalized()));
    return tr;
  }

  // Bullet transform of body b at its keyed pose at time t (kinematic bodies).
  btTransform keyed_transform(int b, double t) const {
    const scene::Body& sb = scene.bodies[b];
    const magnetics::Pose p = sb.pose_at(t);
    return bullet_transform(b, p.rotation, p.position + p.rotation * sb.com);
  }
};

RigidWorld::RigidWorld(const scene::Scene& scene) : impl_(std::make_unique<Impl>(scene)) {
  Impl& m = *impl_;
  m.sleep_time = scene.sleep_time;
  gContactAddedCallback = adjust_internal_edges;
  m.make_world();
  m.principal.resize(scene.bodies.size(), Mat3::Identity());
  m.origin.resize(scene.bodies.size(), Vec3::Zero());

  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const scene::Body& b = scene.bodies[i];
    const bool dynamic = b.motion == scene::Motion::kDynamic;
    const double extent = b.shape.shape->bounds().sizes().minCoeff();
    const double margin = std::min(5e-4, 0.1 * extent);
    btCollisionShape*& cached = m.shared[{b.shape.shape.get(), dynamic, margin}];
    if (!cached) cached = m.make_shape(b.shape, dynamic, margin);
    btCollisionShape* shape = cached;
    btVector3 inertia(0, 0, 0);
    if (dynamic) {
      // Bullet wants principal axes at the centre of mass: diagonalize (deterministic).
      Eigen::SelfAdjointEigenSolver<Mat3> es(b.inertia);
      Mat3 P = es.eigenvectors();
      if (P.determinant() < 0) P.col(2) = -P.col(2);
      const bool simple = (b.com.norm() < 1e-12) && (b.inertia - Mat3(b.inertia.diagonal().asDiagonal())).norm() <=
                                                        1e-12 * b.inertia.norm();
      if (simple) {
        inertia = bt(b.inertia.diagonal());
      } else {
        m.principal[i] = P;
        m.origin[i] = b.com;
        inertia = bt(es.eigenvalues());
        // Child transform: shape frame in Bullet's frame, x_bullet = P^T (x_shape - com).
        auto* compound = new btCompoundShape();
        m.own(compound);
        btTransform child;
        child.setBasis(btMatrix3x3(bt(Quat(P.transpose()).normalized())));
        child.setOrigin(bt(-(P.transpose() * b.com)));
        compound->addChildShape(child, shape);
        shape = compound;
      }
    }
    btRigidBody::btRigidBodyConstructionInfo ci(dynamic ? b.mass : 0.0, nullptr, shape, inertia);
    ci.m_friction = b.friction;
    ci.m_restitution = b.restitution;
    // Damping (scene 1.1): Bullet scales the velocities by (1 - d)^h after each step of h
    // seconds, before the contacts are solved (btRigidBody::applyDamping).
    ci.m_linearDamping = b.linear_damping;
    ci.m_angularDamping = b.angular_damping;
    auto body = std::make_unique<btRigidBody>(ci);
    // Bullet's default implicit gyroscopic update does not carry angular momentum correctly for
    // small, fast-turning bodies (a constant torque on a 6 mm magnet: 25% off after 2 turns,
    // measured); the explicit term (with our small substeps) conserves it.
    if (dynamic) body->setFlags(BT_ENABLE_GYROSCOPIC_FORCE_EXPLICIT);
    if (b.motion == scene::Motion::kKinematic) {
      body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      body->setActivationState(DISABLE_DEACTIVATION);
    } else if (b.motion == scene::Motion::kStatic) {
      body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
    } else {
      // Sleeping (Scene::sleep_time): a sleeping body ignores applied forces, so the simulator
      // wakes a magnetic body when its magnetic force changes (Simulator::update_sleep). Sleep
      // speeds: 5 mm/s, or a tenth of the body's smallest extent per second if smaller, and the
      // spin that moves its surface that fast (at least 0.05 rad/s): a magnet chain resting on a
      // table chatters at 0.005-0.05 rad/s, 30-60 µm/s (5 mm balls, dt 1 ms).
      if (scene.sleep_time <= 0) body->setActivationState(DISABLE_DEACTIVATION);
      const double sleep_speed = std::min(0.005, 0.1 * extent);
      body->setSleepingThresholds(sleep_speed, std::max(0.05, 2 * sleep_speed / extent));
      // Continuous collision for small fast bodies.
      body->setCcdMotionThreshold(0.5 * extent);
      body->setCcdSweptSphereRadius(0.4 * extent);
    }
    if (b.shape.kind == geometry::ShapeKind::kMesh || b.shape.kind == geometry::ShapeKind::kTorus) {
      if (!dynamic) body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    }
    body->setUserIndex(static_cast<int>(i));
    m.magnetic.push_back(b.magnetic(scene.materials));
    bool perm = b.material >= 0 && scene.materials[b.material].kind == magnetics::MaterialKind::kPermanent;
    for (const auto& p : b.parts) perm = perm || (p.material >= 0 && scene.materials[p.material].kind == magnetics::MaterialKind::kPermanent);
    m.permanent.push_back(perm);
    m.extent.push_back(extent);
    const Eigen::AlignedBox3d box = b.shape.shape->bounds();
    const bool round = b.shape.kind == geometry::ShapeKind::kSphere && b.com.norm() < 1e-12;
    m.turn_reach.push_back(round ? 0.0 : 0.5 * box.sizes().norm() + (box.center() - b.com).norm());
    m.aabb_pad.push_back(std::min<double>(gContactBreakingThreshold, 0.5 * extent));
    if (dynamic) m.dbvt_margin = std::min(m.dbvt_margin, 0.25 * extent);
    // At its initial pose before it enters the broadphase: added at the origin, every body's box
    // overlapped every other's and Bullet stored all N^2/2 pairs until the first step (268 MB of
    // pair cache at 3000 bodies, measured with heaptrack).
    const magnetics::Pose p0 = b.pose_at(0.0);
    body->setWorldTransform(m.bullet_transform(int(i), p0.rotation, p0.position + p0.rotation * b.com));
    m.world->addRigidBody(body.get());
    m.bodies.push_back(std::move(body));
  }
  std::vector<StuckContacts::Body> stick(scene.bodies.size());
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    stick[i] = {scene.bodies[i].motion == scene::Motion::kDynamic, m.magnetic[i], m.permanent[i], m.extent[i]};
  }
  m.stuck = std::make_unique<StuckContacts>(std::move(stick));
  m.make_joints();
}

RigidWorld::~RigidWorld() {
  impl_->clear_joints();
  impl_->stuck->clear(*impl_->world);
  for (auto& b : impl_->bodies) impl_->world->removeRigidBody(b.get());
}

void RigidWorld::set_state(const SimState& s) {
  Impl& m = *impl_;
  m.stuck->clear(*m.world);
  m.put_bodies(s);
}

void RigidWorld::reset(const SimState& s) {
  Impl& m = *impl_;
  m.clear_joints();
  m.stuck->clear(*m.world);
  for (auto& b : m.bodies) m.world->removeRigidBody(b.get());
  m.make_world();
  m.put_bodies(s);
  for (auto& b : m.bodies) m.world->addRigidBody(b.get());
  m.make_joints();
  m.stuck->restore(*m.world, m.bodies, s.stuck_joints);
  gDbvtMargin = m.dbvt_margin;
  m.world->performDiscreteCollisionDetection();
}

void RigidWorld::get_state(SimState& s) const {
  const Impl& m = *impl_;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const btRigidBody* b = m.bodies[i].get();
    const btTransform& tr = b->getCenterOfMassTransform();
    const Quat qb = eig(tr.getRotation());
    const Mat3 R = qb.toRotationMatrix() * m.principal[i].transpose();  // body axes -> world
    const Quat q = Quat(R).normalized();
    const Vec3 com_world = eig(tr.getOrigin()) + R * (m.scene.bodies[i].com - m.origin[i]);
    const Vec3 w = eig(b->getAngularVelocity());
    s.orientation[i] = q;
    s.com_position[i] = com_world;
    s.angular_velocity[i] = w;
    s.velocity[i] = eig(b->getLinearVelocity()) + w.cross(com_world - eig(tr.getOrigin()));
    if (i < s.sleep.size()) {
      const bool dynamic = m.scene.bodies[i].motion == scene::Motion::kDynamic;
      const int a = dynamic ? b->getActivationState() : ACTIVE_TAG;  // Bullet's static bodies "sleep"
      s.sleep[i] = a == ISLAND_SLEEPING ? kAsleep : a == WANTS_DEACTIVATION ? kResting : kAwake;
      s.rest_time[i] = m.sleep_time > 0 && m.scene.bodies[i].motion == scene::Motion::kDynamic ? b->getDeactivationTime() : 0.0;
    }
  }
  m.stuck->save(s.stuck_joints);
}

bool RigidWorld::asleep(int i) const { return impl_->bodies[i]->getActivationState() == ISLAND_SLEEPING; }

void RigidWorld::wake(int i) {
  btRigidBody* b = impl_->bodies[i].get();
  if (b->getActivationState() == ISLAND_SLEEPING || b->getActivationState() == WANTS_DEACTIVATION) b->activate(true);
}

void RigidWorld::keep_awake(int i) {
  btRigidBody* b = impl_->bodies[i].get();
  if (b->getActivationState() == DISABLE_DEACTIVATION || b->isStaticOrKinematicObject()) return;
  if (b->getActivationState() != ACTIVE_TAG) b->activate(true);
  b->setDeactivationTime(0);
}

void RigidWorld::step(double t, double h, const std::vector<Vec3>& force, const std::vector<Vec3>& torque,
                      const std::vector<std::uint8_t>* held) {
  Impl& m = *impl_;
  // Held bodies: DISABLE_SIMULATION for this step (Bullet neither integrates nor solves a body
  // that is not active, and skips islands with no active body); their own activation state and
  // rest clock are put back afterwards, so holding does not count as resting.
  struct Saved {
    int body, state;
    btScalar rest;
  };
  std::vector<Saved> saved;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const scene::Body& sb = m.scene.bodies[i];
    btRigidBody* b = m.bodies[i].get();
    if (sb.motion == scene::Motion::kKinematic) {
      // The pose at the end of the step; Bullet derives the contact velocity from the change.
      b->setWorldTransform(m.keyed_transform(int(i), t + h));
    } else if (sb.motion == scene::Motion::kDynamic && held && (*held)[i]) {
      saved.push_back({int(i), b->getActivationState(), b->getDeactivationTime()});
      b->forceActivationState(DISABLE_SIMULATION);
    }
  }
  // Bodies held together by stuck contacts move as one rigid body under their summed force and
  // torque (StuckContacts::share); forces are cleared by every stepSimulation call, which also
  // applies gravity once.
  m.shared_force = force;
  m.shared_torque = torque;
  m.stuck->share(m.bodies, m.shared_force, m.shared_torque);
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (m.scene.bodies[i].motion != scene::Motion::kDynamic || (held && (*held)[i])) continue;
    m.bodies[i]->applyCentralForce(bt(m.shared_force[i]));
    m.bodies[i]->applyTorque(bt(m.shared_torque[i]));
  }
  gDbvtMargin = m.dbvt_margin;
  if (m.sleep_time > 0) gDeactivationTime = btScalar(m.sleep_time);
  m.stuck->before_step();
  m.world->stepSimulation(h, 0, h);
  m.stuck->after_step(*m.world, *m.dispatcher, m.bodies, h);
  for (const Saved& sv : saved) {
    btRigidBody* b = m.bodies[sv.body].get();
    b->forceActivationState(sv.state);
    b->setDeactivationTime(sv.rest);
  }
}

void RigidWorld::rewind_kinematic(double t) {
  Impl& m = *impl_;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const scene::Body& sb = m.scene.bodies[i];
    if (sb.motion != scene::Motion::kKinematic) continue;
    const btTransform tr = m.keyed_transform(int(i), t);
    btRigidBody* b = m.bodies[i].get();
    b->setWorldTransform(tr);
    b->setInterpolationWorldTransform(tr);
  }
}

void RigidWorld::islands(std::vector<int>& island) const {
  const Impl& m = *impl_;
  const int n = static_cast<int>(m.bodies.size());
  island.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    if (m.scene.bodies[i].motion == scene::Motion::kDynamic) island[i] = i;
  }
  auto root = [&](int i) {
    while (island[i] != i) i = island[i] = island[island[i]];
    return i;
  };
  const btBroadphasePairArray& pairs = m.world->getBroadphase()->getOverlappingPairCache()->getOverlappingPairArray();
  for (int k = 0; k < pairs.size(); ++k) {
    const int i = static_cast<const btCollisionObject*>(pairs[k].m_pProxy0->m_clientObject)->getUserIndex();
    const int j = static_cast<const btCollisionObject*>(pairs[k].m_pProxy1->m_clientObject)->getUserIndex();
    if (i < 0 || j < 0 || island[i] < 0 || island[j] < 0) continue;
    const int a = root(i), b = root(j);
    if (a != b) island[std::max(a, b)] = std::min(a, b);  // the smaller index is the root
  }
  for (const scene::Joint& j : m.scene.joints) {  // jointed bodies move together
    if (j.b < 0 || island[j.a] < 0 || island[j.b] < 0) continue;
    const int a = root(j.a), b = root(j.b);
    if (a != b) island[std::max(a, b)] = std::min(a, b);
  }
  for (int i = 0; i < n; ++i) {
    if (island[i] >= 0) island[i] = root(i);
  }
}

void RigidWorld::closing_rates(std::vector<double>& rate) const {
  const Impl& m = *impl_;
  rate.assign(m.bodies.size(), 0.0);
  btOverlappingPairCache* cache = m.world->getBroadphase()->getOverlappingPairCache();
  const btBroadphasePairArray& pairs = cache->getOverlappingPairArray();
  btManifoldArray manifolds;  // reused: one allocation, not one per pair
  for (int k = 0; k < pairs.size(); ++k) {
    const auto* o0 = static_cast<const btCollisionObject*>(pairs[k].m_pProxy0->m_clientObject);
    const auto* o1 = static_cast<const btCollisionObject*>(pairs[k].m_pProxy1->m_clientObject);
    const int i = o0->getUserIndex(), j = o1->getUserIndex();
    if (i < 0 || j < 0) continue;
    const bool dyn_i = m.scene.bodies[i].motion == scene::Motion::kDynamic;
    const bool dyn_j = m.scene.bodies[j].motion == scene::Motion::kDynamic;
    // Two permanent magnets (their mutual pull is what a deep penetration works against, and
    // the strongest there is), one dynamic. Steel meeting a magnet is left to the force guard:
    // guarding it too made the 250 steel balls of DragonLow take 37 pieces per 1 ms, not 6.
    if (!m.permanent[i] || !m.permanent[j] || !(dyn_i || dyn_j)) continue;
    if (m.stuck->stuck(i, j)) continue;  // held together: neither closes nor turns
    // Pairs already touching are the contact solver's (it stops them within the step) as far as
    // their approach goes; but one that turns against the other (a tumbling cylinder that has
    // met a box with its rim and slams its side down) closes elsewhere at up to the turn rate
    // times its reach: the smaller of the two bodies' turn reaches, relative turn rate.
    const auto* b0 = btRigidBody::upcast(o0);
    const auto* b1 = btRigidBody::upcast(o1);
    const double length = 0.01 * std::min(m.extent[i], m.extent[j]);
    if (pairs[k].m_algorithm) {
      manifolds.resize(0);
      pairs[k].m_algorithm->getAllContactManifolds(manifolds);
      bool touching = false;
      for (int q = 0; q < manifolds.size() && !touching; ++q) {
        for (int c = 0; c < manifolds[q]->getNumContacts(); ++c) {
          if (manifolds[q]->getContactPoint(c).getDistance() < 1e-4) touching = true;
        }
      }
      if (touching) {
        const double turn = (b1->getAngularVelocity() - b0->getAngularVelocity()).length() *
                            std::min(m.turn_reach[i], m.turn_reach[j]);
        rate[i] = std::max(rate[i], turn / length);
        rate[j] = std::max(rate[j], turn / length);
        continue;
      }
    }
    const btVector3 dir = b1->getCenterOfMassPosition() - b0->getCenterOfMassPosition();
    if (dir.length2() == 0) continue;
    const double approach = (b0->getLinearVelocity() - b1->getLinearVelocity()).dot(dir.normalized());
    if (approach <= 0) continue;
    rate[i] = std::max(rate[i], approach / length);
    rate[j] = std::max(rate[j], approach / length);
  }
}

RigidWorld::Penetration RigidWorld::deepest_penetration() const {
  const Impl& m = *impl_;
  Penetration out;
  btCollisionDispatcher& d = *m.dispatcher;
  for (int k = 0; k < d.getNumManifolds(); ++k) {
    const btPersistentManifold* mf = d.getManifoldByIndexInternal(k);
    for (int c = 0; c < mf->getNumContacts(); ++c) {
      const double depth = -mf->getContactPoint(c).getDistance();
      if (depth > out.depth) out = {mf->getBody0()->getUserIndex(), mf->getBody1()->getUserIndex(), depth};
    }
  }
  return out;
}

void RigidWorld::contact_normals(std::vector<std::vector<Vec3>>& out, std::vector<double>* face_slip,
                                 std::vector<std::vector<std::uint8_t>>* stuck,
                                 std::vector<double>* partner_speed) const {
  const Impl& m = *impl_;
  out.resize(m.scene.bodies.size());
  for (auto& n : out) n.clear();
  if (stuck) {
    stuck->resize(m.scene.bodies.size());
    for (auto& n : *stuck) n.clear();
  }
  if (face_slip) face_slip->assign(m.scene.bodies.size(), 0.0);
  if (partner_speed) partner_speed->assign(m.scene.bodies.size(), 0.0);
  btCollisionDispatcher& d = *m.dispatcher;
  for (int k = 0; k < d.getNumManifolds(); ++k) {
    const btPersistentManifold* mf = d.getManifoldByIndexInternal(k);
    const int a = mf->getBody0()->getUserIndex(), b = mf->getBody1()->getUserIndex();
    const btRigidBody* ra = btRigidBody::upcast(mf->getBody0());
    const btRigidBody* rb = btRigidBody::upcast(mf->getBody1());
    Vec3 p[4];
    double slip = 0;  // largest speed of B's contact point relative to A's, m/s
    int touching = 0;
    for (int c = 0; c < mf->getNumContacts() && touching < 4; ++c) {
      const btManifoldPoint& pt = mf->getContactPoint(c);
      if (pt.getDistance() >= kTouchingDistance) continue;
      const btVector3& w = pt.getPositionWorldOnB();
      p[touching] = Vec3(w.x(), w.y(), w.z());
      if (face_slip) {
        btVector3 v(0, 0, 0);
        if (ra) v -= ra->getVelocityInLocalPoint(w - ra->getCenterOfMassPosition());
        if (rb) v += rb->getVelocityInLocalPoint(w - rb->getCenterOfMassPosition());
        slip = std::max(slip, static_cast<double>(v.length()));
      }
      if (touching++ > 0) continue;  // one normal per manifold: its points share it
      // Bullet's normal on B points towards A: it pushes A away from B, and B the other way.
      const Vec3 n(pt.m_normalWorldOnB.x(), pt.m_normalWorldOnB.y(), pt.m_normalWorldOnB.z());
      if (a >= 0) out[a].push_back(n);
      if (b >= 0) out[b].push_back(-n);
      if (stuck) {
        if (a >= 0) (*stuck)[a].push_back(0);
        if (b >= 0) (*stuck)[b].push_back(0);
      }
    }
    if (partner_speed && touching > 0) {
      // Each body's centre against the partner's motion there (static partners: zero motion).
      auto relative = [](const btRigidBody* self, const btRigidBody* other) {
        btVector3 v = self ? self->getLinearVelocity() : btVector3(0, 0, 0);
        if (other && self) v -= other->getVelocityInLocalPoint(self->getCenterOfMassPosition() - other->getCenterOfMassPosition());
        return static_cast<double>(v.length());
      };
      if (a >= 0 && b >= 0 && m.permanent[b]) (*partner_speed)[a] = std::max((*partner_speed)[a], relative(ra, rb));
      if (a >= 0 && b >= 0 && m.permanent[a]) (*partner_speed)[b] = std::max((*partner_speed)[b], relative(rb, ra));
    }
    if (!face_slip || touching == 0) continue;
    // A face contact (spans_face); anything else is a point or line contact.
    double size = std::numeric_limits<double>::infinity();
    if (a >= 0) size = std::min(size, m.extent[a]);
    if (b >= 0) size = std::min(size, m.extent[b]);
    if (!spans_face(p, touching, size)) slip = std::numeric_limits<double>::infinity();
    if (a >= 0) (*face_slip)[a] = std::max((*face_slip)[a], slip);
    if (b >= 0) (*face_slip)[b] = std::max((*face_slip)[b], slip);
  }
  m.stuck->normals(out, stuck);
}

int RigidWorld::stuck_contacts() const { return impl_->stuck->count(); }

void RigidWorld::stuck_shares(std::vector<Vec3>& force, std::vector<Vec3>& torque) const {
  impl_->stuck->shared(impl_->bodies, force, torque);
}

std::vector<RigidWorld::Penetration> RigidWorld::separate_overlaps(double tolerance, int max_iterations) {
  Impl& m = *impl_;
  std::map<std::pair<int, int>, double> first;  // initial depth per pair
  for (int it = 0; it < max_iterations; ++it) {
    gDbvtMargin = m.dbvt_margin;
    m.world->performDiscreteCollisionDetection();
    double worst = 0;
    for (int k = 0; k < m.dispatcher->getNumManifolds(); ++k) {
      btPersistentManifold* mf = m.dispatcher->getManifoldByIndexInternal(k);
      auto* b0 = const_cast<btRigidBody*>(btRigidBody::upcast(mf->getBody0()));
      auto* b1 = const_cast<btRigidBody*>(btRigidBody::upcast(mf->getBody1()));
      if (!b0 || !b1) continue;
      const double w0 = b0->getInvMass(), w1 = b1->getInvMass();
      if (w0 + w1 == 0) continue;
      // The deepest point of the pair: normal on B points towards A.
      int deepest = -1;
      double depth = tolerance;
      for (int c = 0; c < mf->getNumContacts(); ++c) {
        if (-mf->getContactPoint(c).getDistance() > depth) depth = -mf->getContactPoint(c).getDistance(), deepest = c;
      }
      if (deepest < 0) continue;
      worst = std::max(worst, depth);
      const std::pair<int, int> key(std::min(b0->getUserIndex(), b1->getUserIndex()),
                                    std::max(b0->getUserIndex(), b1->getUserIndex()));
      if (it == 0) first[key] = std::max(first[key], depth);
      // Move a little past half the depth per pass (contacts of a pile interact); positions only.
      const btVector3 n = mf->getContactPoint(deepest).m_normalWorldOnB;
      const double push = 0.6 * depth;
      for (auto [b, share] : {std::pair{b0, w0 / (w0 + w1)}, std::pair{b1, -w1 / (w0 + w1)}}) {
        if (share == 0) continue;
        btTransform tr = b->getWorldTransform();
        tr.setOrigin(tr.getOrigin() + n * (push * share));
        b->setWorldTransform(tr);
        b->setInterpolationWorldTransform(tr);
        b->setCenterOfMassTransform(tr);
      }
    }
    if (worst <= tolerance) break;
  }
  // Contacts found while separating are not the simulation's: start it with fresh manifolds.
  // (One pass over the pairs: cleanProxyFromPairs per body scans every pair for each body,
  // N x pairs, 12% of the first second of a 10,000-body bake.)
  btOverlappingPairCache* pair_cache = m.world->getBroadphase()->getOverlappingPairCache();
  btBroadphasePairArray& all_pairs = pair_cache->getOverlappingPairArray();
  for (int k = 0; k < all_pairs.size(); ++k) pair_cache->cleanOverlappingPair(all_pairs[k], m.dispatcher.get());
  std::vector<Penetration> out;
  for (const auto& [key, depth] : first) out.push_back({key.first, key.second, depth});
  std::sort(out.begin(), out.end(), [](const Penetration& x, const Penetration& y) { return x.depth > y.depth; });
  return out;
}

std::string RigidWorld::bullet_version() {
  const int v = btGetVersion();
  return std::to_string(v / 100) + "." + std::to_string(v % 100);
}

}  // namespace magbake::sim
