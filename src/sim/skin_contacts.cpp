#include "skin_contacts.h"

#include <BulletCollision/CollisionDispatch/btActivatingCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btBoxBoxDetector.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>

#include <algorithm>
#include <new>

namespace magbake::sim {
namespace {

// The contact skin of a pair: 1e-3 of the smaller body's smallest extent, from the two bodies'
// smallest half extents (radii for spheres), m.
btScalar contact_skin(btScalar half_a, btScalar half_b) { return 2e-3 * std::min(half_a, half_b); }

// Passes the grown boxes' points on with the skin taken off again. Bullet's convention:
// normal on B pointing towards A, point on B, depth < 0 for penetration.
struct SkinResult : public btDiscreteCollisionDetectorInterface::Result {
  btManifoldResult* out = nullptr;
  btScalar skin = 0;
  void setShapeIdentifiersA(int part, int index) override { out->setShapeIdentifiersA(part, index); }
  void setShapeIdentifiersB(int part, int index) override { out->setShapeIdentifiersB(part, index); }
  void addContactPoint(const btVector3& normal_on_b, const btVector3& point_on_b, btScalar depth) override {
    out->addContactPoint(normal_on_b, point_on_b - normal_on_b * skin, depth + 2 * skin);
  }
};

// An algorithm owning one persistent manifold (as Bullet's own pairwise algorithms).
class ManifoldAlgorithm : public btActivatingCollisionAlgorithm {
 public:
  ManifoldAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* a,
                    const btCollisionObjectWrapper* b)
      : btActivatingCollisionAlgorithm(ci, a, b) {
    if (m_dispatcher->needsCollision(a->getCollisionObject(), b->getCollisionObject())) {
      manifold_ = m_dispatcher->getNewManifold(a->getCollisionObject(), b->getCollisionObject());
    }
  }
  ~ManifoldAlgorithm() override {
    if (manifold_) m_dispatcher->releaseManifold(manifold_);
  }
  btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                 btManifoldResult*) override {
    return 1;  // as Bullet's box-box and sphere-sphere algorithms: no time of impact
  }
  void getAllContactManifolds(btManifoldArray& manifolds) override {
    if (manifold_) manifolds.push_back(manifold_);
  }

 protected:
  btPersistentManifold* manifold_ = nullptr;  // owned
};

class SkinBoxBoxAlgorithm : public ManifoldAlgorithm {
 public:
  using ManifoldAlgorithm::ManifoldAlgorithm;

  void processCollision(const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b,
                        const btDispatcherInfo& info, btManifoldResult* out) override {
    if (!manifold_) return;
    const btVector3 ha = static_cast<const btBoxShape*>(a->getCollisionShape())->getHalfExtentsWithMargin();
    const btVector3 hb = static_cast<const btBoxShape*>(b->getCollisionShape())->getHalfExtentsWithMargin();
    const btScalar skin = contact_skin(ha[ha.minAxis()], hb[hb.minAxis()]);
    const btBoxShape grown_a(ha + btVector3(skin, skin, skin));
    const btBoxShape grown_b(hb + btVector3(skin, skin, skin));
    out->setPersistentManifold(manifold_);
    btDiscreteCollisionDetectorInterface::ClosestPointInput input;
    input.m_maximumDistanceSquared = BT_LARGE_FLOAT;
    input.m_transformA = a->getWorldTransform();
    input.m_transformB = b->getWorldTransform();
    SkinResult result;
    result.out = out;
    result.skin = skin;
    btBoxBoxDetector detector(&grown_a, &grown_b);
    detector.getClosestPoints(input, result, info.m_debugDraw);
    out->refreshContactPoints();
  }
};

class SkinSphereSphereAlgorithm : public ManifoldAlgorithm {
 public:
  using ManifoldAlgorithm::ManifoldAlgorithm;

  void processCollision(const btCollisionObjectWrapper* a, const btCollisionObjectWrapper* b,
                        const btDispatcherInfo&, btManifoldResult* out) override {
    if (!manifold_) return;
    out->setPersistentManifold(manifold_);
    const btScalar ra = static_cast<const btSphereShape*>(a->getCollisionShape())->getRadius();
    const btScalar rb = static_cast<const btSphereShape*>(b->getCollisionShape())->getRadius();
    const btVector3 diff = a->getWorldTransform().getOrigin() - b->getWorldTransform().getOrigin();
    const btScalar len = diff.length();
    const btScalar skin = contact_skin(ra, rb);
    if (len > ra + rb + skin || len <= SIMD_EPSILON * (ra + rb)) {
      out->refreshContactPoints();
      return;
    }
    const btVector3 normal_on_b = diff / len;  // from B towards A
    out->addContactPoint(normal_on_b, b->getWorldTransform().getOrigin() + normal_on_b * rb, len - ra - rb);
    out->refreshContactPoints();
  }
};

}  // namespace

btCollisionAlgorithm* SkinBoxBoxCreateFunc::CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                                     const btCollisionObjectWrapper* body0,
                                                                     const btCollisionObjectWrapper* body1) {
  void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(SkinBoxBoxAlgorithm));
  return new (mem) SkinBoxBoxAlgorithm(ci, body0, body1);
}

btCollisionAlgorithm* SkinSphereSphereCreateFunc::CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                                           const btCollisionObjectWrapper* body0,
                                                                           const btCollisionObjectWrapper* body1) {
  void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(SkinSphereSphereAlgorithm));
  return new (mem) SkinSphereSphereAlgorithm(ci, body0, body1);
}

}  // namespace magbake::sim
