#pragma once
// Contacts that exist from the moment two bodies touch: Bullet collision algorithms for box-box
// and sphere-sphere pairs with a contact skin.

#include <BulletCollision/CollisionDispatch/btCollisionCreateFunc.h>

namespace magbake::sim {

/// Creates box-box collision algorithms with a contact skin. Bullet's own box-box detector
/// (ODE's dBoxBox) reports points only where the boxes already interpenetrate: two boxes exactly
/// touching, or pushed apart to zero depth by the position correction, have no contact in the
/// next step, and a magnetic pull of thousands of g then drives them ~0.1 mm into each other
/// before the solver sees them. The skin algorithm runs the same detector on boxes grown by
/// `skin = 1e-3 x the smaller box's smallest extent` (10 um for a 1 cm cube) and reports each
/// point back at its true place and distance (distance = depth - 2 skin, point moved back onto
/// box B), so touching and nearly touching faces keep a speculative contact: the solver lets
/// the gap close, never more. Register it for (BOX_SHAPE_PROXYTYPE, BOX_SHAPE_PROXYTYPE).
struct SkinBoxBoxCreateFunc : public btCollisionAlgorithmCreateFunc {
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override;
};

/// Creates sphere-sphere collision algorithms with the same skin (1e-3 of the smaller diameter).
/// Bullet's own reports a point only once the spheres overlap, so a resting pair of ball
/// magnets lost its contact whenever the correction pushed it back to zero depth. Register it
/// for (SPHERE_SHAPE_PROXYTYPE, SPHERE_SHAPE_PROXYTYPE).
struct SkinSphereSphereCreateFunc : public btCollisionAlgorithmCreateFunc {
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override;
};

}  // namespace magbake::sim
