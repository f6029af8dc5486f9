// Closed-form references the tests compare the dipole method against (physics-notes §7).
// Implemented here, independently of the library.
#pragma once

#include <Eigen/Core>

namespace magbake::testing {

using Vec3 = Eigen::Vector3d;

/// Akoun & Yonnet (1984): force (N) on cuboid 2 from cuboid 1, both axis-aligned and magnetized
/// along +z with signed polarizations J1, J2 (T); half-edges h1, h2 (m); d = centre2 - centre1.
/// Contact (a zero gap) is the limit of a vanishing positive gap.
Vec3 akoun_yonnet_force(double J1, double J2, const Vec3& h1, const Vec3& h2, const Vec3& d);

/// Furlani (2001), eqs. 4.49–4.51: field B (T) at x of a cuboid centred at the origin with
/// half-edges h, uniformly magnetized along +z with polarization J (T). Valid outside the cuboid.
Vec3 furlani_cuboid_field(double J, const Vec3& h, const Vec3& x);

/// Exact field of a point dipole (also of a uniformly magnetized sphere outside it), T.
Vec3 point_dipole_field(const Vec3& m, const Vec3& r);

}  // namespace magbake::testing
