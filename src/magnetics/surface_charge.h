// Exact fields of uniformly magnetized polyhedra from their surface charge (physics.md §12):
// a magnetization M that is uniform inside a closed surface is the same source as a charge
// density sigma = M . n on that surface, and a flat triangle of constant charge has a closed-form
// field. A permanent part whose surface is a triangle mesh (a mesh magnet, or a cylinder
// tessellated within a tolerance) thus gets a field that is exact up to the tessellation,
// right down to its surface and inside it, where its cells' point dipoles are far off.
#pragma once

#include <cstdint>

#include <vector>

#include "types.h"

namespace magbake::magnetics {

/// Signed solid angle (sr) of the triangle with corners a, b, c seen from the origin (a, b, c are
/// the corners minus the viewpoint): positive when the origin lies on the side that (b - a) x
/// (c - a) points away from. Van Oosterom & Strackee (1983).
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c);

/// Field integral E(x) = ∫_T (x - y) / |x - y|³ dA_y of the flat triangle (a, b, c) with unit
/// charge density (m⁰; multiply by sigma / 4pi for H in A/m). Closed form: the signed solid angle
/// along the normal plus one logarithm per edge in the plane. Singular only on the triangle's
/// edges; finite (and discontinuous in its normal part) on the triangle itself.
Vec3 triangle_field(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c);

/// Flux density B (tesla) at x of a uniformly magnetized polyhedron, all in one frame (m, A/m):
/// `ntri` triangles whose corners are vertex[3t], vertex[3t+1], vertex[3t+2] (counter-clockwise
/// seen from outside, the surface closed), sigma[t] = M . n_t (A/m), magnetization M.
/// B = mu0 (H + M) inside (the faces' solid angles sum to 4pi there), mu0 H outside.
Vec3 surface_b_field(const Vec3* vertex, const double* sigma, int ntri, const Vec3& M, const Vec3& x);

/// The same surface prepared for many targets. Corners are shared by their triangles. Each
/// edge's in-plane term is taken once for the two triangles that share it (the line integral
/// of 1/R along an edge does not depend on its direction), with the triangles' charge densities
/// folded into one constant vector; edges inside a flat patch of equal charge (a cylinder's
/// caps, the diagonals of its side quads) then weigh nothing and are dropped. Triangles of one
/// plane and one charge density form a group whose solid angles are summed as one: the half-
/// angles' tangents multiply as complex numbers (num, den), and a flat patch is seen under less
/// than 2pi, so one arctangent per group suffices. Per target: one distance per corner, one
/// logarithm per edge left, one arctangent per group. All in one frame (the part's body frame).
struct SurfaceMesh {
  std::vector<Vec3> point;                  ///< corners, m
  std::vector<Eigen::Vector2i> edge;        ///< corner pairs (a, b) of the edges that weigh something
  std::vector<Vec3> edge_tangent;           ///< unit (b - a)
  std::vector<Vec3> edge_weight;            ///< sum over the edge's two triangles of sigma (t x n), A/m
  std::vector<Eigen::Vector3i> face;        ///< corners, counter-clockwise seen from outside, by group
  std::vector<int> group_begin;             ///< (ngroup + 1) faces of group g: [begin[g], begin[g+1])
  std::vector<Vec3> group_weight;           ///< sigma n of the group's faces, A/m
  /// (ngroup) 1 for a group that carries charge. An uncharged group (weight exactly zero: the
  /// side of a cylinder magnetized along its axis) adds nothing to B or G; its solid angle only
  /// tells whether x is inside, so it is skipped for points outside `bounds`.
  std::vector<std::uint8_t> group_charged;
  Box3 bounds;                              ///< of the corners, m
  /// Boundary of each group, for the gradient: the directed edges (a -> b, counter-clockwise
  /// seen from outside) of its faces that no other face of the group runs the other way;
  /// group g's are [loop_begin[g], loop_begin[g+1]).
  std::vector<int> loop_begin;
  std::vector<Eigen::Vector2i> loop_edge;
  std::vector<Vec3> loop_tangent;   ///< unit (b - a) of each boundary edge
  std::vector<double> loop_length;  ///< |b - a|, m
  Vec3 magnetization = Vec3::Zero();        ///< M, A/m (added inside)

  /// From a closed triangle soup as surface_b_field() takes it (corners that are bitwise equal
  /// are one corner). Returns false if some edge is not shared by exactly two triangles.
  bool build(const Vec3* vertex, const double* sigma, int ntri, const Vec3& M);
  /// B (tesla) at x, as surface_b_field() of the soup it was built from (to ~1e-12 relative).
  /// `scratch` is resized to the corner count (reuse it across calls).
  Vec3 b_field(const Vec3& x, std::vector<double>& scratch) const;
  /// B (tesla) at x and its gradient G(i, j) = dB_i/dx_j (T/m), both in the mesh's frame: the
  /// edge logarithms differentiated, and each group's solid angle through the Biot–Savart line
  /// integral around its boundary (physics.md §12). Outside the magnet G is symmetric and
  /// traceless, and the force on a point dipole m at x is G^T m. Same edge and corner guards as
  /// b_field (a term that is infinite at x is left out).
  void b_field_gradient(const Vec3& x, std::vector<double>& scratch, Vec3& B, Mat3& G) const;
};

}  // namespace magbake::magnetics
