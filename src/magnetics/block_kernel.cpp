#include "block_kernel.h"

#include <algorithm>
#include <cmath>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define MAGBAKE_AVX2 1
#endif

namespace magbake::magnetics {
namespace {

constexpr int kChunk = 64;  // targets handled per pass (stack buffers, multiple of 8)

// Scalar reference kernel, any precision. Accumulates per target, then adds p_k x F_k + T_k.
template <class Real>
void block_scalar(const State& s, int tb, int te, int sb, int se, const Vec3& delta, bool clamp, BlockSum& out) {
  using V = Eigen::Matrix<Real, 3, 1>;
  const V d = delta.cast<Real>();
  Real f_sum[3] = {0, 0, 0}, g_sum[3] = {0, 0, 0}, u_sum = 0;
  for (int k = tb; k < te; ++k) {
    const V pk = s.cell_offset[k].cast<Real>();
    const V xk = pk + d;
    const V mk = s.total.cell[k].cast<Real>();
    V F = V::Zero(), T = V::Zero();
    Real U = 0;
    for (int i = sb; i < se; ++i) {
      V r = xk - s.cell_offset[i].cast<Real>();
      const V mi = s.total.cell[i].cast<Real>();
      Real d2 = r.squaredNorm();
      if (clamp) {
        const Real dmin = Real(s.fclamp[k]) + Real(s.fclamp[i]);
        if (d2 < dmin * dmin) {
          r *= dmin / std::sqrt(d2 > 0 ? d2 : Real(1e-300));
          if (!(d2 > 0)) r = V(0, 0, dmin);
          d2 = dmin * dmin;
        }
      }
      const Real inv = Real(1) / std::sqrt(d2);
      const Real inv2 = inv * inv;
      const Real inv5 = inv2 * inv2 * inv;
      const Real a = mk.dot(r), b = mi.dot(r), c = mk.dot(mi);
      const Real sc = c - Real(5) * a * b * inv2;
      F += inv5 * (a * mi + b * mk + sc * r);
      const V B = Real(3) * b * r - d2 * mi;
      T += inv5 * mk.cross(B);
      U += inv5 * mk.dot(B);
    }
    // Lever arm about the body origin: p_k x F_k (F in units of 3 mu0/4pi, T of mu0/4pi).
    const V G = Real(3) * pk.cross(F) + T;
    for (int a = 0; a < 3; ++a) f_sum[a] += F[a], g_sum[a] += G[a];
    u_sum += U;
  }
  out.force = 3.0 * kMu0Over4Pi * Vec3(f_sum[0], f_sum[1], f_sum[2]);
  out.torque = kMu0Over4Pi * Vec3(g_sum[0], g_sum[1], g_sum[2]);
  out.energy = -kMu0Over4Pi * double(u_sum);
}

#ifdef MAGBAKE_AVX2
inline __m256 rsqrt_nr(__m256 x) {
  const __m256 y = _mm256_rsqrt_ps(x);
  const __m256 hx = _mm256_mul_ps(_mm256_set1_ps(0.5f), x);
  return _mm256_mul_ps(y, _mm256_fnmadd_ps(_mm256_mul_ps(hx, y), y, _mm256_set1_ps(1.5f)));
}

inline double hsum(__m256 v) {
  alignas(32) float t[8];
  _mm256_store_ps(t, v);
  double s = 0;
  for (float x : t) s += x;  // fixed order
  return s;
}

// Targets in the 8 lanes, sources broadcast; per-lane sums over all sources.
template <bool kClamp>
void block_avx2(const State& s, int tb, int te, int sb, int se, const Vec3& delta, BlockSum& out) {
  alignas(32) float px[kChunk], py[kChunk], pz[kChunk], mx[kChunk], my[kChunk], mz[kChunk], cl[kChunk];
  const float dx = float(delta[0]), dy = float(delta[1]), dz = float(delta[2]);
  double f[3] = {0, 0, 0}, g[3] = {0, 0, 0}, u = 0;
  for (int c0 = tb; c0 < te; c0 += kChunk) {
    const int n = std::min(kChunk, te - c0);
    const int npad = (n + 7) & ~7;
    for (int q = 0; q < npad; ++q) {
      if (q < n) {
        px[q] = s.fx[c0 + q], py[q] = s.fy[c0 + q], pz[q] = s.fz[c0 + q];
        mx[q] = s.fmx[c0 + q], my[q] = s.fmy[c0 + q], mz[q] = s.fmz[c0 + q];
        cl[q] = s.fclamp[c0 + q];
      } else {  // padding lanes: far away, no moment -> exactly zero contribution
        px[q] = 1e6f, py[q] = 1e6f, pz[q] = 1e6f, mx[q] = my[q] = mz[q] = 0.0f, cl[q] = 0.0f;
      }
    }
    for (int q = 0; q < npad; q += 8) {
      const __m256 PX = _mm256_load_ps(px + q), PY = _mm256_load_ps(py + q), PZ = _mm256_load_ps(pz + q);
      const __m256 X = _mm256_add_ps(PX, _mm256_set1_ps(dx));
      const __m256 Y = _mm256_add_ps(PY, _mm256_set1_ps(dy));
      const __m256 Z = _mm256_add_ps(PZ, _mm256_set1_ps(dz));
      const __m256 MX = _mm256_load_ps(mx + q), MY = _mm256_load_ps(my + q), MZ = _mm256_load_ps(mz + q);
      const __m256 CL = _mm256_load_ps(cl + q);
      __m256 FX = _mm256_setzero_ps(), FY = FX, FZ = FX, TX = FX, TY = FX, TZ = FX, UU = FX;
      const __m256 five = _mm256_set1_ps(5.0f), three = _mm256_set1_ps(3.0f);
      for (int i = sb; i < se; ++i) {
        __m256 rx = _mm256_sub_ps(X, _mm256_set1_ps(s.fx[i]));
        __m256 ry = _mm256_sub_ps(Y, _mm256_set1_ps(s.fy[i]));
        __m256 rz = _mm256_sub_ps(Z, _mm256_set1_ps(s.fz[i]));
        const __m256 bmx = _mm256_set1_ps(s.fmx[i]), bmy = _mm256_set1_ps(s.fmy[i]), bmz = _mm256_set1_ps(s.fmz[i]);
        __m256 d2 = _mm256_fmadd_ps(rz, rz, _mm256_fmadd_ps(ry, ry, _mm256_mul_ps(rx, rx)));
        __m256 inv = rsqrt_nr(d2);
        if constexpr (kClamp) {
          // Keep the direction, lengthen r to at least the contact distance of the two cells.
          const __m256 dmin = _mm256_add_ps(CL, _mm256_set1_ps(s.fclamp[i]));
          const __m256 dist = _mm256_mul_ps(d2, inv);
          const __m256 sc = _mm256_max_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(dmin, inv));
          rx = _mm256_mul_ps(rx, sc), ry = _mm256_mul_ps(ry, sc), rz = _mm256_mul_ps(rz, sc);
          const __m256 dc = _mm256_max_ps(dist, dmin);
          d2 = _mm256_mul_ps(dc, dc);
          inv = rsqrt_nr(d2);
        }
        const __m256 inv2 = _mm256_mul_ps(inv, inv);
        const __m256 inv5 = _mm256_mul_ps(_mm256_mul_ps(inv2, inv2), inv);
        const __m256 a = _mm256_fmadd_ps(MZ, rz, _mm256_fmadd_ps(MY, ry, _mm256_mul_ps(MX, rx)));
        const __m256 b = _mm256_fmadd_ps(bmz, rz, _mm256_fmadd_ps(bmy, ry, _mm256_mul_ps(bmx, rx)));
        const __m256 c = _mm256_fmadd_ps(MZ, bmz, _mm256_fmadd_ps(MY, bmy, _mm256_mul_ps(MX, bmx)));
        const __m256 sc = _mm256_fnmadd_ps(_mm256_mul_ps(five, _mm256_mul_ps(a, b)), inv2, c);
        // F/(3K) += inv5 (a mi + b mk + s r)
        FX = _mm256_fmadd_ps(inv5, _mm256_fmadd_ps(sc, rx, _mm256_fmadd_ps(b, MX, _mm256_mul_ps(a, bmx))), FX);
        FY = _mm256_fmadd_ps(inv5, _mm256_fmadd_ps(sc, ry, _mm256_fmadd_ps(b, MY, _mm256_mul_ps(a, bmy))), FY);
        FZ = _mm256_fmadd_ps(inv5, _mm256_fmadd_ps(sc, rz, _mm256_fmadd_ps(b, MZ, _mm256_mul_ps(a, bmz))), FZ);
        // B/K = inv5 (3 b r - d2 mi); T/K += mk x B; U/K += mk . B
        const __m256 b3 = _mm256_mul_ps(three, b);
        const __m256 Bx = _mm256_mul_ps(inv5, _mm256_fmsub_ps(b3, rx, _mm256_mul_ps(d2, bmx)));
        const __m256 By = _mm256_mul_ps(inv5, _mm256_fmsub_ps(b3, ry, _mm256_mul_ps(d2, bmy)));
        const __m256 Bz = _mm256_mul_ps(inv5, _mm256_fmsub_ps(b3, rz, _mm256_mul_ps(d2, bmz)));
        TX = _mm256_add_ps(TX, _mm256_fmsub_ps(MY, Bz, _mm256_mul_ps(MZ, By)));
        TY = _mm256_add_ps(TY, _mm256_fmsub_ps(MZ, Bx, _mm256_mul_ps(MX, Bz)));
        TZ = _mm256_add_ps(TZ, _mm256_fmsub_ps(MX, By, _mm256_mul_ps(MY, Bx)));
        UU = _mm256_fmadd_ps(MZ, Bz, _mm256_fmadd_ps(MY, By, _mm256_fmadd_ps(MX, Bx, UU)));
      }
      // Lever arm about the target body's origin: G = 3 p x F' + T'.
      const __m256 GX = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PY, FZ, _mm256_mul_ps(PZ, FY)), TX);
      const __m256 GY = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PZ, FX, _mm256_mul_ps(PX, FZ)), TY);
      const __m256 GZ = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PX, FY, _mm256_mul_ps(PY, FX)), TZ);
      f[0] += hsum(FX), f[1] += hsum(FY), f[2] += hsum(FZ);
      g[0] += hsum(GX), g[1] += hsum(GY), g[2] += hsum(GZ);
      u += hsum(UU);
    }
  }
  out.force = 3.0 * kMu0Over4Pi * Vec3(f[0], f[1], f[2]);
  out.torque = kMu0Over4Pi * Vec3(g[0], g[1], g[2]);
  out.energy = -kMu0Over4Pi * u;
}
#endif

}  // namespace

void block_interaction(const State& s, int tb, int te, int sb, int se, const Vec3& delta, bool clamp,
                       KernelPrecision precision, BlockSum& out) {
  if (precision == KernelPrecision::kDouble) {
    block_scalar<double>(s, tb, te, sb, se, delta, clamp, out);
    return;
  }
#ifdef MAGBAKE_AVX2
  if (clamp) {
    block_avx2<true>(s, tb, te, sb, se, delta, out);
  } else {
    block_avx2<false>(s, tb, te, sb, se, delta, out);
  }
#else
  block_scalar<float>(s, tb, te, sb, se, delta, clamp, out);
#endif
}

const char* block_kernel_isa() {
#ifdef MAGBAKE_AVX2
  return "avx2+fma float32x8";
#else
  return "scalar float32";
#endif
}

}  // namespace magbake::magnetics
