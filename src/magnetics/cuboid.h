// Exact fields and interactions of uniformly magnetized cuboids (the shape of every dipole cell).
// Used for the near-field correction: two cells closer than a few cell sizes interact as the
// cuboids they are, not as point dipoles (point dipoles are 40% off for touching cube magnets).
#pragma once

#include <array>
#include <cstdint>
#include <map>

#include "types.h"

namespace magbake::magnetics {

/// Magnetic field H (A/m) at x (cuboid frame, m) of a cuboid centred at the origin with half-edges
/// `half` (m) and uniform magnetization M (A/m, cuboid frame); magnetic-charge model, closed form.
/// Exact everywhere except on the charged faces themselves (where the caller picks a side).
Vec3 cuboid_h_field(const Vec3& half, const Vec3& M, const Vec3& x);

/// Magnetic scalar potential (A) at x (cuboid frame) of the same cuboid: H = -grad phi outside
/// (closed form, from the same corner terms as cuboid_h_field).
double cuboid_potential(const Vec3& half, const Vec3& M, const Vec3& x);

/// The full field tensor N at x (cuboid frame): H(x) = N M for any magnetization M. Per cuboid
/// vertex three logarithms and three arctangents (cheaper than three cuboid_h_field calls).
Mat3 cuboid_h_tensor(const Vec3& half, const Vec3& x);

/// Flux density B (tesla) at x (cuboid frame): mu0 (H + M) inside the cuboid, mu0 H outside.
Vec3 cuboid_b_field(const Vec3& half, const Vec3& M, const Vec3& x);

/// A uniformly magnetized cuboid placed in the world.
struct Cuboid {
  Vec3 center;       ///< world, m
  Mat3 rotation;     ///< cuboid frame -> world
  Vec3 half;         ///< half-edges in the cuboid frame, m
  Vec3 magnetization;///< world, A/m
};

/// Force (N, world) on cuboid k due to cuboid i, and torque (N·m, world) on k about k's centre.
/// Surface-charge integral over k's charged faces of i's closed-form field, Gauss–Legendre of
/// order `order` per edge with end-point clustering; faces are split along i's face edges when
/// the two cuboids are parallel, so coplanar contact converges. The cuboids must not overlap.
/// With `energy`, also the interaction energy (J) -mu0 int M_k.H_i dV = mu0 oint sigma_k phi_i dA
/// by the same quadrature, so the force is its negative gradient to quadrature accuracy.
void cuboid_pair(const Cuboid& k, const Cuboid& i, int order, Vec3& force, Vec3& torque, double* energy = nullptr);

/// Minimum translation that separates two overlapping cuboids (separating-axis test over the 15
/// box axes): returns true and sets `shift` (world, m) when k overlaps i, so that k moved by
/// `shift` just touches i; false (shift zero) when they are apart or touch. Close-range callers
/// evaluate overlapping cells (bodies penetrating by a contact solver's tolerance) at the
/// touching pose, so the near field stays continuous through contact.
bool cuboid_overlap_shift(const Cuboid& k, const Cuboid& i, Vec3& shift);

/// Mean field tensor N (world frame, dimensionless): the H field of `source` averaged over the
/// volume of `target` is N * M_source. With target == source this is minus the cuboid's own
/// demagnetizing tensor. Volume Gauss–Legendre of order `order` per axis with end-point
/// clustering, split along the source's face planes when the cuboids are parallel.
/// Magnetizations of the arguments are ignored.
Mat3 cuboid_mean_field_tensor(const Cuboid& target, const Cuboid& source, int order);

/// Mean-field tensors between cells of one lattice (identical, parallel cuboids) by integer
/// offset, in the lattice frame, computed once and reused (every part with the same cell size
/// shares them). Not thread-safe.
class LatticeTensors {
 public:
  /// Tensor N with mean H over the cell at `offset` (in cells) = N M of the cell at the origin.
  const Mat3& get(const Vec3& half, const Eigen::Vector3i& offset);

 private:
  std::map<std::array<std::int64_t, 6>, Mat3> cache_;
};

}  // namespace magbake::magnetics
