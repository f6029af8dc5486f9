#include "block_kernel.h"

#include <algorithm>
#include <cmath>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>

#include "simd_rsqrt.h"
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
    Real U = 0, W = 0;  // W: the clamp's energy continuation, sum of F.(r_c - r) (units of F)
    for (int i = sb; i < se; ++i) {
      V r = xk - s.cell_offset[i].cast<Real>();
      const V mi = s.total.cell[i].cast<Real>();
      Real d2 = r.squaredNorm();
      Real stretch = 0;  // 1 - |r| / |r_c| when clamped
      if (clamp) {
        const Real dmin = Real(s.fclamp[k]) + Real(s.fclamp[i]);
        if (d2 < dmin * dmin) {
          stretch = Real(1) - std::sqrt(d2) / dmin;
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
      const V Fp = inv5 * (a * mi + b * mk + sc * r);
      F += Fp;
      if (stretch > 0) W += stretch * Fp.dot(r);
      const V B = Real(3) * b * r - d2 * mi;
      T += inv5 * mk.cross(B);
      U += inv5 * mk.dot(B);
    }
    // Lever arm about the body origin: p_k x F_k (F in units of 3 mu0/4pi, T of mu0/4pi).
    const V G = Real(3) * pk.cross(F) + T;
    for (int a = 0; a < 3; ++a) f_sum[a] += F[a], g_sum[a] += G[a];
    u_sum += U - Real(3) * W;  // energy -K u: the continuation +3K W enters as -3 W
  }
  out.force = 3.0 * kMu0Over4Pi * Vec3(f_sum[0], f_sum[1], f_sum[2]);
  out.torque = kMu0Over4Pi * Vec3(g_sum[0], g_sum[1], g_sum[2]);
  out.energy = -kMu0Over4Pi * double(u_sum);
}

#ifdef MAGBAKE_AVX2
inline double hsum(__m256 v) {
  alignas(32) float t[8];
  _mm256_store_ps(t, v);
  double s = 0;
  for (float x : t) s += x;  // fixed order
  return s;
}

// Targets in the 8 lanes, sources broadcast; per-lane sums over all sources. The loop is
// bound by the number of vector operations (~50 per 8 pairs), so constants are folded and the
// torque and energy are formed once per target from the accumulated field.
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
      // Per target: F (force) and B (field of all sources). Torque mk x B and energy -mk.B
      // follow after the loop, since mk is the same for every source.
      // The b5 mk term of F shares mk across sources: its scalar factor is summed (SB) and
      // multiplied by mk once after the loop.
      __m256 FX = _mm256_setzero_ps(), FY = FX, FZ = FX, BX = FX, BY = FX, BZ = FX, SB = FX, WW = FX;
      for (int i = sb; i < se; ++i) {
        __m256 rx = _mm256_sub_ps(X, _mm256_set1_ps(s.fx[i]));
        __m256 ry = _mm256_sub_ps(Y, _mm256_set1_ps(s.fy[i]));
        __m256 rz = _mm256_sub_ps(Z, _mm256_set1_ps(s.fz[i]));
        const __m256 bmx = _mm256_set1_ps(s.fmx[i]), bmy = _mm256_set1_ps(s.fmy[i]), bmz = _mm256_set1_ps(s.fmz[i]);
        __m256 d2 = _mm256_fmadd_ps(rz, rz, _mm256_fmadd_ps(ry, ry, _mm256_mul_ps(rx, rx)));
        __m256 z = two_over_sqrt(d2);  // 2/d
        [[maybe_unused]] __m256 stretch = _mm256_setzero_ps();
        if constexpr (kClamp) {
          // Keep the direction, lengthen r to at least the contact distance of the two cells.
          const __m256 dmin = _mm256_add_ps(CL, _mm256_set1_ps(s.fclamp[i]));
          const __m256 sc = _mm256_max_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(dmin, _mm256_mul_ps(_mm256_set1_ps(0.5f), z)));
          rx = _mm256_mul_ps(rx, sc), ry = _mm256_mul_ps(ry, sc), rz = _mm256_mul_ps(rz, sc);
          d2 = _mm256_mul_ps(d2, _mm256_mul_ps(sc, sc));
          const __m256 inv_sc = _mm256_div_ps(_mm256_set1_ps(1.0f), sc);  // |r| / |r_c|
          z = _mm256_mul_ps(z, inv_sc);                                    // 2 / |r_c|
          stretch = _mm256_sub_ps(_mm256_set1_ps(1.0f), inv_sc);           // 1 - |r|/|r_c|
        }
        // In units of 1/d = z/2: inv2 = z²/4, inv5 = z⁵/32 (the 1/4, 1/32 go into the constants).
        const __m256 z2 = _mm256_mul_ps(z, z);
        const __m256 z3 = _mm256_mul_ps(z2, z);
        const __m256 z5 = _mm256_mul_ps(z3, z2);
        const __m256 a = _mm256_fmadd_ps(MZ, rz, _mm256_fmadd_ps(MY, ry, _mm256_mul_ps(MX, rx)));   // mk.r
        const __m256 b = _mm256_fmadd_ps(bmz, rz, _mm256_fmadd_ps(bmy, ry, _mm256_mul_ps(bmx, rx)));  // mi.r
        const __m256 c = _mm256_fmadd_ps(MZ, bmz, _mm256_fmadd_ps(MY, bmy, _mm256_mul_ps(MX, bmx)));  // mk.mi
        const __m256 a5 = _mm256_mul_ps(a, z5), b5 = _mm256_mul_ps(b, z5);
        // B'/K = 3 b5 r - d² z⁵ mi (x 32) = 4 (0.75 b5 r - z³ mi): the bracket is summed, the 4
        // applied after the loop (d² z⁵ = 4 z³ saves a multiplication per pair).
        const __m256 bq = _mm256_mul_ps(b5, _mm256_set1_ps(0.75f));
        BX = _mm256_fnmadd_ps(z3, bmx, _mm256_fmadd_ps(bq, rx, BX));
        BY = _mm256_fnmadd_ps(z3, bmy, _mm256_fmadd_ps(bq, ry, BY));
        BZ = _mm256_fnmadd_ps(z3, bmz, _mm256_fmadd_ps(bq, rz, BZ));
        // F/(3K) = a5 mi + b5 mk + (c z5 - 5 a b5 z²/4) r   (x 32)
        const __m256 ab = _mm256_mul_ps(a, b5);
        const __m256 s5 = _mm256_fnmadd_ps(ab, _mm256_mul_ps(z2, _mm256_set1_ps(1.25f)), _mm256_mul_ps(c, z5));
        FX = _mm256_fmadd_ps(s5, rx, _mm256_fmadd_ps(a5, bmx, FX));
        FY = _mm256_fmadd_ps(s5, ry, _mm256_fmadd_ps(a5, bmy, FY));
        FZ = _mm256_fmadd_ps(s5, rz, _mm256_fmadd_ps(a5, bmz, FZ));
        SB = _mm256_add_ps(SB, b5);
        if constexpr (kClamp) {
          // Energy continuation F_pair . (r_c - r) = stretch (F_pair . r_c), F_pair . r_c =
          // a5 b + b5 a + s5 d² (same units as F).
          const __m256 fr = _mm256_fmadd_ps(s5, d2, _mm256_fmadd_ps(a5, b, _mm256_mul_ps(b5, a)));
          WW = _mm256_fmadd_ps(stretch, fr, WW);
        }
      }
      FX = _mm256_fmadd_ps(SB, MX, FX), FY = _mm256_fmadd_ps(SB, MY, FY), FZ = _mm256_fmadd_ps(SB, MZ, FZ);
      const __m256 four = _mm256_set1_ps(4.0f);
      BX = _mm256_mul_ps(BX, four), BY = _mm256_mul_ps(BY, four), BZ = _mm256_mul_ps(BZ, four);
      // Torque mk x B, energy mk.B, and the lever arm about the body origin: G = 3 p x F' + T'.
      const __m256 TX = _mm256_fmsub_ps(MY, BZ, _mm256_mul_ps(MZ, BY));
      const __m256 TY = _mm256_fmsub_ps(MZ, BX, _mm256_mul_ps(MX, BZ));
      const __m256 TZ = _mm256_fmsub_ps(MX, BY, _mm256_mul_ps(MY, BX));
      const __m256 UU = _mm256_fmadd_ps(MZ, BZ, _mm256_fmadd_ps(MY, BY, _mm256_mul_ps(MX, BX)));
      const __m256 three = _mm256_set1_ps(3.0f);
      const __m256 GX = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PY, FZ, _mm256_mul_ps(PZ, FY)), TX);
      const __m256 GY = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PZ, FX, _mm256_mul_ps(PX, FZ)), TY);
      const __m256 GZ = _mm256_fmadd_ps(three, _mm256_fmsub_ps(PX, FY, _mm256_mul_ps(PY, FX)), TZ);
      f[0] += hsum(FX), f[1] += hsum(FY), f[2] += hsum(FZ);
      g[0] += hsum(GX), g[1] += hsum(GY), g[2] += hsum(GZ);
      u += hsum(UU);
      if constexpr (kClamp) u -= 3.0 * hsum(WW);  // energy -K u / 32: the continuation enters as -3 W
    }
  }
  constexpr double k32 = 1.0 / 32.0;  // z⁵ = 32 / d⁵
  out.force = 3.0 * kMu0Over4Pi * k32 * Vec3(f[0], f[1], f[2]);
  out.torque = kMu0Over4Pi * k32 * Vec3(g[0], g[1], g[2]);
  out.energy = -kMu0Over4Pi * k32 * u;
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
