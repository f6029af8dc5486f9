// Closed-form point-dipole kernels (physics-notes §2), in double precision.
// Every function is exact for point dipoles; the adaptive traversal calls them for aggregated
// (node) dipoles, the block kernels evaluate the same formulas for many cell pairs at once.
#pragma once

#include "types.h"

namespace magbake::magnetics {

/// Field B (tesla) at offset r = x - x_i (m) from a point dipole of moment m_i (A·m²).
/// r must be non-zero.
inline Vec3 dipole_field(const Vec3& r, const Vec3& m_i) {
  const double d2 = r.squaredNorm();
  const double inv = 1.0 / std::sqrt(d2);
  const double inv5 = inv * inv * inv * inv * inv;
  return kMu0Over4Pi * inv5 * (3.0 * m_i.dot(r) * r - d2 * m_i);
}

/// Field B (tesla) and its gradient G(a,b) = dB_a/dx_b (T/m) at offset r from a point dipole.
inline void dipole_field_gradient(const Vec3& r, const Vec3& m, Vec3& B, Mat3& G) {
  const double d2 = r.squaredNorm();
  const double inv = 1.0 / std::sqrt(d2);
  const double inv2 = inv * inv;
  const double inv5 = inv2 * inv2 * inv;
  const double mr = m.dot(r);
  B = kMu0Over4Pi * inv5 * (3.0 * mr * r - d2 * m);
  // d/dx_b of (3 (m.r) r_a - d2 m_a) / d^5
  //  = [3 m_b r_a + 3 (m.r) delta_ab - 2 r_b m_a] / d^5 - 5 r_b (3 (m.r) r_a - d2 m_a) / d^7
  const Vec3 q = 3.0 * mr * r - d2 * m;
  G = kMu0Over4Pi * inv5 *
      (3.0 * r * m.transpose() + 3.0 * mr * Mat3::Identity() - 2.0 * m * r.transpose() -
       5.0 * inv2 * q * r.transpose());
}

/// Fields and gradients that two point dipoles put on each other, sharing one distance
/// evaluation: dipole a (moment m_a at x_a) feels B_a, G_a from dipole b (moment m_b at x_b), and
/// b feels B_b, G_b from a, with r = x_a - x_b (non-zero). The same values as
/// dipole_field_gradient(r, m_b) and dipole_field_gradient(-r, m_a) up to rounding: with
/// mu = m.r, G(r, m) = k/d^5 [3 (r m^T + m r^T) + mu (3 I - 15 r r^T / d^2)], odd in r.
inline void dipole_mutual_fields(const Vec3& r, const Vec3& m_a, const Vec3& m_b, Vec3& B_a, Mat3& G_a, Vec3& B_b,
                                 Mat3& G_b) {
  const double d2 = r.squaredNorm();
  const double inv = 1.0 / std::sqrt(d2);
  const double inv2 = inv * inv;
  const double k5 = kMu0Over4Pi * inv2 * inv2 * inv;
  const double mu_a = m_a.dot(r), mu_b = m_b.dot(r);
  B_a = k5 * (3.0 * mu_b * r - d2 * m_b);
  B_b = k5 * (3.0 * mu_a * r - d2 * m_a);
  // The radial part 3 I - 15 r r^T / d^2, shared by both gradients.
  Mat3 radial = (-15.0 * inv2) * (r * r.transpose());
  radial.diagonal().array() += 3.0;
  const Mat3 rb = r * m_b.transpose(), ra = r * m_a.transpose();
  G_a = k5 * (3.0 * (rb + rb.transpose()) + mu_b * radial);
  G_b = -k5 * (3.0 * (ra + ra.transpose()) + mu_a * radial);
}

/// Interaction of two point dipoles: the force and torque on dipole k (moment m_k at x_k) due to
/// dipole i (moment m_i at x_i), r = x_k - x_i. The torque is about x_k. Energy U = -m_k·B_i(x_k).
/// Dipole i feels F_i = -F_k and T_i = -(T_k + r × F_k) (momentum conservation, physics-notes §2).
struct DipolePair {
  Vec3 force;      ///< N, on k
  Vec3 torque;     ///< N·m, on k about x_k
  double energy;   ///< J, interaction energy of the pair
};

/// Evaluates the pair with the distance clamped to at least d_min (m, physics-notes §6);
/// the direction of r is kept. Inside the clamp the force and torque are those at the clamped
/// separation r_c and the energy is continued linearly along r, U(r_c) + F·(r_c - r), so that
/// the radial force stays the energy's gradient (physics.md §8).
inline DipolePair dipole_pair(const Vec3& r_in, const Vec3& m_k, const Vec3& m_i, double d_min = 0.0) {
  Vec3 r = r_in;
  double d2 = r.squaredNorm();
  double shift = 0.0;  // |r_c| - |r|, m
  if (d2 < d_min * d_min) {
    shift = d_min - std::sqrt(d2);
    r *= d_min / std::sqrt(d2);
    d2 = d_min * d_min;
  }
  const double inv = 1.0 / std::sqrt(d2);
  const double inv2 = inv * inv;
  const double inv5 = inv2 * inv2 * inv;
  const double a = m_k.dot(r), b = m_i.dot(r), c = m_k.dot(m_i);
  const double s = c - 5.0 * a * b * inv2;
  DipolePair p;
  p.force = (3.0 * kMu0Over4Pi * inv5) * (a * m_i + b * m_k + s * r);
  const Vec3 B = (kMu0Over4Pi * inv5) * (3.0 * b * r - d2 * m_i);
  p.torque = m_k.cross(B);
  p.energy = -m_k.dot(B);
  if (shift > 0.0) p.energy += p.force.dot(r) * inv * shift;  // F . (r_c - r)
  return p;
}

}  // namespace magbake::magnetics
