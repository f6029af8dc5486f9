// Second-order local (Taylor) expansion of a magnetic field about a point: what a group of
// targets feels from far sources, handed down the target hierarchy of the field walk
// (field.cpp) so that a far group of sources is summed once per group of targets, not once per
// target.
#pragma once

#include <array>
#include <cmath>

#include "types.h"

namespace magbake::magnetics {

/// B(c + x) ~ b + g x + 1/2 [x^T h_i x]_i about a centre c (world frame): b in T, g(i, k) =
/// dB_i/dx_k in T/m, h_i(k, l) = d2B_i/dx_k dx_l in T/m². Outside the sources B is the gradient
/// of a harmonic potential, so g is symmetric and h fully symmetric: they are stored as their 6
/// and 10 distinct components (index maps sym2/sym3).
struct LocalExpansion {
  Vec3 b = Vec3::Zero();
  std::array<double, 6> g{};   ///< xx xy xz yy yz zz
  std::array<double, 10> h{};  ///< xxx xxy xxz xyy xyz xzz yyy yyz yzz zzz

  /// Storage index of the symmetric pair (i, k) and triple (i, k, l), any order.
  static constexpr int sym2(int i, int k) {
    constexpr int t[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    return t[i][k];
  }
  static constexpr int sym3(int i, int k, int l) {
    constexpr int t[3][3][3] = {{{0, 1, 2}, {1, 3, 4}, {2, 4, 5}},
                                {{1, 3, 4}, {3, 6, 7}, {4, 7, 8}},
                                {{2, 4, 5}, {4, 7, 8}, {5, 8, 9}}};
    return t[i][k][l];
  }

  /// dB_i/dx_k, T/m.
  Mat3 gradient() const {
    Mat3 G;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) G(i, k) = g[sym2(i, k)];
    return G;
  }
  /// d2B_i/dx_k dx_l, T/m².
  double hessian(int i, int k, int l) const { return h[sym3(i, k, l)]; }

  /// Adds the expansion, about offset r = c - x_s (m, non-zero) from a point dipole of moment m
  /// (A·m²) at x_s, of that dipole's field. Closed forms: B_i = k m_j d_ij(1/r), g and h the
  /// next two derivatives of 1/r contracted with m (k = mu0 / 4 pi, docs/physics.md §9):
  ///   g_ik  = k [3 (m_i r_k + m_k r_i + (m.r) d_ik) / r^5 - 15 (m.r) r_i r_k / r^7]
  ///   h_ikl = k [105 (m.r) r_i r_k r_l / r^9
  ///              - 15 ((m.r)(r_i d_kl + r_k d_il + r_l d_ik) + m_i r_k r_l + m_k r_i r_l + m_l r_i r_k) / r^7
  ///              + 3 (m_i d_kl + m_k d_il + m_l d_ik) / r^5]
  void add_dipole(const Vec3& r, const Vec3& m) {
    const double d2 = r.squaredNorm();
    const double inv = 1.0 / std::sqrt(d2);
    const double inv2 = inv * inv;
    const double inv5 = kMu0Over4Pi * inv2 * inv2 * inv;  // k / r^5
    const double inv7 = inv5 * inv2, inv9 = inv7 * inv2;
    const double mr = m.dot(r);
    b += inv5 * (3.0 * mr * r - d2 * m);
    const double e3 = 3.0 * inv5, c15 = 15.0 * inv7, a105 = 105.0 * mr * inv9, q15 = c15 * mr;
    add_g<0, 0>(r, m, mr, e3, q15), add_g<0, 1>(r, m, mr, e3, q15), add_g<0, 2>(r, m, mr, e3, q15);
    add_g<1, 1>(r, m, mr, e3, q15), add_g<1, 2>(r, m, mr, e3, q15), add_g<2, 2>(r, m, mr, e3, q15);
    add_h<0, 0, 0>(r, m, mr, a105, c15, e3), add_h<0, 0, 1>(r, m, mr, a105, c15, e3);
    add_h<0, 0, 2>(r, m, mr, a105, c15, e3), add_h<0, 1, 1>(r, m, mr, a105, c15, e3);
    add_h<0, 1, 2>(r, m, mr, a105, c15, e3), add_h<0, 2, 2>(r, m, mr, a105, c15, e3);
    add_h<1, 1, 1>(r, m, mr, a105, c15, e3), add_h<1, 1, 2>(r, m, mr, a105, c15, e3);
    add_h<1, 2, 2>(r, m, mr, a105, c15, e3), add_h<2, 2, 2>(r, m, mr, a105, c15, e3);
  }

  /// Adds this expansion re-centred at c + delta (m) to `out` (exact: the expansion is a
  /// polynomial of degree two).
  void shift_into(const Vec3& delta, LocalExpansion& out) const {
    out.b += at(delta);
    for (int i = 0; i < 3; ++i) {
      for (int k = i; k < 3; ++k) {
        double s = g[sym2(i, k)];
        for (int l = 0; l < 3; ++l) s += h[sym3(i, k, l)] * delta[l];
        out.g[sym2(i, k)] += s;
      }
    }
    for (int q = 0; q < 10; ++q) out.h[q] += h[q];
  }

  /// The field at offset x (m) from the centre, T.
  Vec3 at(const Vec3& x) const {
    Vec3 B;
    for (int i = 0; i < 3; ++i) {
      double s = b[i];
      for (int k = 0; k < 3; ++k) {
        double t = g[sym2(i, k)];
        for (int l = 0; l < 3; ++l) t += 0.5 * h[sym3(i, k, l)] * x[l];
        s += t * x[k];
      }
      B[i] = s;
    }
    return B;
  }

 private:
  template <int I, int K>
  void add_g(const Vec3& r, const Vec3& m, double mr, double e3, double q15) {
    constexpr double dik = I == K;
    g[sym2(I, K)] += e3 * (m[I] * r[K] + m[K] * r[I] + mr * dik) - q15 * r[I] * r[K];
  }
  template <int I, int K, int L>
  void add_h(const Vec3& r, const Vec3& m, double mr, double a105, double c15, double e3) {
    constexpr double dkl = K == L, dil = I == L, dik = I == K;
    h[sym3(I, K, L)] += a105 * r[I] * r[K] * r[L] -
                        c15 * (mr * (r[I] * dkl + r[K] * dil + r[L] * dik) + m[I] * r[K] * r[L] + m[K] * r[I] * r[L] +
                               m[L] * r[I] * r[K]) +
                        e3 * (m[I] * dkl + m[K] * dil + m[L] * dik);
  }
};

}  // namespace magbake::magnetics
