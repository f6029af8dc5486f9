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
    const double rv[3] = {r[0], r[1], r[2]}, mv[3] = {m[0], m[1], m[2]};
    double t[kTerms];
    dipole_terms(rv, mv, [](double d2) { return 1.0 / std::sqrt(d2); }, t);
    add_terms(t);
  }

  /// Number of distinct terms: b, g and h in storage order.
  static constexpr int kTerms = 19;

  /// The kTerms terms of add_dipole(r, m) for T = double or a vector of doubles with
  /// element-wise operators (inv_sqrt(d2) = 1 / sqrt(d2), correctly rounded): the same
  /// operations in the same order either way, so a batch of dipoles evaluated in SIMD lanes adds
  /// exactly what one at a time adds.
  template <class T, class InvSqrt>
  static void dipole_terms(const T r[3], const T m[3], InvSqrt inv_sqrt, T out[kTerms]) {
    const T d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    const T inv = inv_sqrt(d2);
    const T inv2 = inv * inv;
    const T inv5 = kMu0Over4Pi * inv2 * inv2 * inv;  // k / r^5
    const T inv7 = inv5 * inv2, inv9 = inv7 * inv2;
    const T mr = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
    for (int i = 0; i < 3; ++i) out[i] = inv5 * (3.0 * mr * r[i] - d2 * m[i]);
    const T e3 = 3.0 * inv5, c15 = 15.0 * inv7, a105 = 105.0 * mr * inv9, q15 = c15 * mr;
    T* g = out + 3;
    g[0] = g_term<0, 0>(r, m, mr, e3, q15), g[1] = g_term<0, 1>(r, m, mr, e3, q15);
    g[2] = g_term<0, 2>(r, m, mr, e3, q15), g[3] = g_term<1, 1>(r, m, mr, e3, q15);
    g[4] = g_term<1, 2>(r, m, mr, e3, q15), g[5] = g_term<2, 2>(r, m, mr, e3, q15);
    T* h = out + 9;
    h[0] = h_term<0, 0, 0>(r, m, mr, a105, c15, e3), h[1] = h_term<0, 0, 1>(r, m, mr, a105, c15, e3);
    h[2] = h_term<0, 0, 2>(r, m, mr, a105, c15, e3), h[3] = h_term<0, 1, 1>(r, m, mr, a105, c15, e3);
    h[4] = h_term<0, 1, 2>(r, m, mr, a105, c15, e3), h[5] = h_term<0, 2, 2>(r, m, mr, a105, c15, e3);
    h[6] = h_term<1, 1, 1>(r, m, mr, a105, c15, e3), h[7] = h_term<1, 1, 2>(r, m, mr, a105, c15, e3);
    h[8] = h_term<1, 2, 2>(r, m, mr, a105, c15, e3), h[9] = h_term<2, 2, 2>(r, m, mr, a105, c15, e3);
  }

  /// Adds terms made by dipole_terms().
  void add_terms(const double t[kTerms]) {
    for (int i = 0; i < 3; ++i) b[i] += t[i];
    for (int q = 0; q < 6; ++q) g[q] += t[3 + q];
    for (int q = 0; q < 10; ++q) h[q] += t[9 + q];
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
  template <int I, int K, class T>
  static T g_term(const T* r, const T* m, T mr, T e3, T q15) {
    T s = m[I] * r[K] + m[K] * r[I];
    if constexpr (I == K) s = s + mr;
    return e3 * s - q15 * r[I] * r[K];
  }
  template <int I, int K, int L, class T>
  static T h_term(const T* r, const T* m, T mr, T a105, T c15, T e3) {
    T del{}, dm{};  // sum of r and of m over the Kronecker deltas that are 1
    if constexpr (K == L) del = del + r[I], dm = dm + m[I];
    if constexpr (I == L) del = del + r[K], dm = dm + m[K];
    if constexpr (I == K) del = del + r[L], dm = dm + m[L];
    const T lin = m[I] * r[K] * r[L] + m[K] * r[I] * r[L] + m[L] * r[I] * r[K];
    return a105 * r[I] * r[K] * r[L] - c15 * (mr * del + lin) + e3 * dm;
  }
};

}  // namespace magbake::magnetics
