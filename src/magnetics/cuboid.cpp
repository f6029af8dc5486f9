#include "cuboid.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <limits>

#if defined(__AVX2__)
#include <immintrin.h>

// glibc's vector math library (libmvec, part of libm): 4-lane AVX2 atan2, at most 4 ulp from
// the correctly rounded result. Called explicitly (not through -ffast-math auto-vectorization),
// so every build type evaluates the same function. A MAGBAKE_PORTABLE (baseline x86-64) build
// uses scalar libm instead, as it does for the block kernels. Its AVX2 log is not used: it
// starts from vrcpps, an estimate whose bits differ between Intel and AMD CPUs, so its results
// could depend on the machine (the atan2 path has no such estimate).
extern "C" __m256d _ZGVdN4vv_atan2(__m256d y, __m256d x);
#endif

namespace magbake::magnetics {
namespace {

// a + R without cancellation when a ~ -R (R = sqrt(a² + q2), q2 = the other two squares).
inline double plus_r(double a, double R, double q2) {
  if (a >= 0.0) return a + R;
  // a + R = q2 / (R - a); on the extension of an edge q2 -> 0 and the two corners that share
  // the line cancel, so a tiny floor keeps both terms finite and equal.
  return std::max(q2, 1e-300 * R * R + 1e-300) / (R - a);
}

// out[i] = atan2(y[i], x[i]) for n values (n a multiple of 4, arrays 32-byte aligned): libmvec's
// 4-lane AVX2 atan2 where built for AVX2, scalar libm otherwise (see the note at the top).
inline void atan2_batch(const double* y, const double* x, double* out, int n) {
#if defined(__AVX2__)
  for (int i = 0; i < n; i += 4) _mm256_store_pd(out + i, _ZGVdN4vv_atan2(_mm256_load_pd(y + i), _mm256_load_pd(x + i)));
#else
  for (int i = 0; i < n; ++i) out[i] = std::atan2(y[i], x[i]);
#endif
}

// sum over the 8 vertices q of P_q ln(arg[3q + k]), P_q = s0 s1 s2 the vertex parity, as the
// logarithm of one product: vertices q and q + 2^k share the line along axis k and have
// opposite parity, so the sum is ln of the product of 4 ratios arg(q + 2^k) / arg(q) (or its
// inverse when P(q + 2^k) < 0). One scalar log instead of 8, and no cancellation between large
// logarithms of nearly equal arguments. Ratios that could overflow the product (a point on the
// extension of an edge, where plus_r's floor makes an argument ~1e-300) take a log each.
inline double signed_log_sum(const double* arg, int k) {
  const int bit = 1 << k;
  double prod = 1.0, extra = 0.0;
  for (int q = 0; q < 8; ++q) {
    if (q & bit) continue;
    const int q1 = q | bit;
    const bool plus = (((q1 & 1) ? 1 : 0) + ((q1 & 2) ? 1 : 0) + ((q1 & 4) ? 1 : 0)) % 2 == 1;  // P(q1) = +1
    const double a1 = arg[3 * q1 + k], a0 = arg[3 * q + k];
    const double ratio = plus ? a1 / a0 : a0 / a1;
    if (ratio > 1e-75 && ratio < 1e75) {
      prod *= ratio;
    } else {
      extra += plus ? std::log(a1) - std::log(a0) : std::log(a0) - std::log(a1);
    }
  }
  return std::log(prod) + extra;
}

// ln(a / b) of two positive arguments, one logarithm where the ratio cannot overflow.
inline double log_ratio(double a, double b) {
  const double r = a / b;
  if (r > 1e-75 && r < 1e75) return std::log(r);
  return std::log(a) - std::log(b);
}

// Adds to H (in units of 1 / 4pi, A/m) the field at x (cuboid frame) of the two faces of a
// cuboid (half-edges `half`) normal to axis w, with charge densities -Mw (w = -half[w]) and +Mw
// (w = +half[w]); with `phi`, adds their scalar potential (same units, H = -grad phi). Per face
// rectangle u in [u0,u1], v in [v0,v1] and corner (X, Y, Z) = x - corner, the antiderivatives
// are -ln(Y + R), -ln(X + R), atan(XY / (ZR)) for H_u, H_v, H_w and X ln(Y + R) + Y ln(X + R)
// - Z atan(XY / (ZR)) for phi, summed with the corner signs. Corners that share X (or Y) enter
// as one logarithm of a ratio (4 per face instead of 8, and no cancellation of large nearly
// equal logarithms); the 8 arctangents are taken 4 at a time (libmvec, as cuboid_h_tensor).
void face_pair_h(const Vec3& half, int w, double Mw, const Vec3& x, Vec3& H, double* phi) {
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  const double us[2] = {x[u] + half[u], x[u] - half[u]};
  const double vs[2] = {x[v] + half[v], x[v] - half[v]};
  alignas(32) double at_y[8], at_x[8], at[8];
  double ly[8], lx[8], Zs[2];
  for (int f = 0; f < 2; ++f) {
    const double Z = x[w] - (2 * f - 1) * half[w];
    const double Z2 = Z * Z;
    Zs[f] = Z;
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        const int q = 4 * f + 2 * a + b;
        const double X = us[a], Y = vs[b];
        const double R = std::sqrt(X * X + Y * Y + Z2);
        ly[q] = plus_r(Y, R, X * X + Z2);
        lx[q] = plus_r(X, R, Y * Y + Z2);
        // atan(XY / (Z R)), odd in Z; Z = 0 gives the in-plane limit sign(XY) pi/2 (from Z > 0).
        at_y[q] = Z >= 0.0 ? X * Y : -X * Y;
        at_x[q] = Z >= 0.0 ? Z * R : -Z * R;
      }
    }
  }
  atan2_batch(at_y, at_x, at, 8);
  for (int f = 0; f < 2; ++f) {
    const double sigma = (2 * f - 1) * Mw;
    const int q = 4 * f;
    const double L0 = log_ratio(ly[q], ly[q + 1]), L1 = log_ratio(ly[q + 2], ly[q + 3]);  // ln(Y+R) at X = us[a]
    const double K0 = log_ratio(lx[q], lx[q + 2]), K1 = log_ratio(lx[q + 1], lx[q + 3]);  // ln(X+R) at Y = vs[b]
    const double A = at[q] - at[q + 1] - at[q + 2] + at[q + 3];
    H[u] -= sigma * (L0 - L1);
    H[v] -= sigma * (K0 - K1);
    H[w] += sigma * A;
    // X ln(..) -> 0 where the logarithm diverges (X -> 0 on an edge's extension): the ratio's
    // logarithm stays finite there, so X = 0 gives 0.
    if (phi) *phi += sigma * (us[0] * L0 - us[1] * L1 + vs[0] * K0 - vs[1] * K1 - Zs[f] * A);
  }
}

constexpr double kInv4Pi = 1.0 / (4.0 * std::numbers::pi);

// Gauss–Legendre nodes and weights on [0, 1] for orders 1..8, optionally with the smoothstep
// substitution t -> t²(3 - 2t), which clusters nodes at both ends (log-singular integrands).
struct Rule {
  int n = 0;
  std::array<double, 8> x{}, w{};
};

Rule gauss_rule(int n, bool cluster) {
  static const double kX[8][8] = {
      {0.0},
      {-0.5773502691896257, 0.5773502691896257},
      {-0.7745966692414834, 0.0, 0.7745966692414834},
      {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526},
      {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640},
      {-0.9324695142031521, -0.6612093864662645, -0.2386191860831969, 0.2386191860831969,
       0.6612093864662645, 0.9324695142031521},
      {-0.9491079123427585, -0.7415311855993945, -0.4058451513773972, 0.0, 0.4058451513773972,
       0.7415311855993945, 0.9491079123427585},
      {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
       0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363}};
  static const double kW[8][8] = {
      {2.0},
      {1.0, 1.0},
      {0.5555555555555556, 0.8888888888888888, 0.5555555555555556},
      {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538},
      {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665, 0.2369268850561891},
      {0.1713244923791704, 0.3607615730481386, 0.4679139345726910, 0.4679139345726910,
       0.3607615730481386, 0.1713244923791704},
      {0.1294849661688697, 0.2797053914892766, 0.3818300505051189, 0.4179591836734694,
       0.3818300505051189, 0.2797053914892766, 0.1294849661688697},
      {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
       0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763}};
  Rule r;
  r.n = std::clamp(n, 1, 8);
  for (int j = 0; j < r.n; ++j) {
    const double t = 0.5 * (kX[r.n - 1][j] + 1.0);
    const double w = 0.5 * kW[r.n - 1][j];
    if (cluster) {
      r.x[j] = t * t * (3.0 - 2.0 * t);
      r.w[j] = w * 6.0 * t * (1.0 - t);
    } else {
      r.x[j] = t;
      r.w[j] = w;
    }
  }
  return r;
}

// Insertion sort of a few values (std::sort on a short std::array trips GCC 12's -Warray-bounds).
void sort_small(double* a, int n) {
  for (int i = 1; i < n; ++i) {
    for (int j = i; j > 0 && a[j] < a[j - 1]; --j) std::swap(a[j], a[j - 1]);
  }
}

// Index of the axis of i's frame that unit vector e is parallel to, within ~1.4 mrad (-1 if
// none). Nearly parallel faces are split like parallel ones: the split lines are then off by
// at most 1e-3 of the face, far better than no split, and the rule does not flip between the
// two as resting bodies jitter by 1e-9 rad (that flip moved a snapped pair's energy by 0.2%).
int parallel_axis(const Vec3& e) {
  for (int a = 0; a < 3; ++a) {
    if (std::abs(e[a]) > 1.0 - 1e-6) return a;
  }
  return -1;
}

// A magnetization given in the world, in a cuboid's frame (Rt = the frame's rotation,
// transposed). A magnetization along one of the cuboid's axes comes back with round-off
// components (~1e-16 of it) along the others; they are set to zero, so that the charge-free
// faces are skipped (cuboid_h_and_potential, cuboid_pair: a third of the work per axis; the
// near field of touching cube magnets ran 7x slower with them). Components below 1e-12 of the
// largest are no physical part of any magnet (a tilt of 1e-12 rad).
Vec3 in_frame(const Mat3& Rt, const Vec3& M) {
  Vec3 L = Rt * M;
  const double tiny = 1e-12 * L.cwiseAbs().maxCoeff();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(L[a]) <= tiny) L[a] = 0.0;
  }
  return L;
}

// H (A/m) and, with `phi`, the scalar potential (A) of a cuboid at x (cuboid frame).
// M must come through in_frame() (its zero components skip faces).
Vec3 cuboid_h_and_potential(const Vec3& half, const Vec3& M, const Vec3& x, double* phi) {
  Vec3 H = Vec3::Zero();
  double p = 0.0;
  for (int w = 0; w < 3; ++w) {
    if (M[w] != 0.0) face_pair_h(half, w, M[w], x, H, phi ? &p : nullptr);
  }
  if (phi) *phi = kInv4Pi * p;
  return kInv4Pi * H;
}

}  // namespace

Vec3 cuboid_h_field(const Vec3& half, const Vec3& M, const Vec3& x) {
  return cuboid_h_and_potential(half, in_frame(Mat3::Identity(), M), x, nullptr);
}

double cuboid_potential(const Vec3& half, const Vec3& M, const Vec3& x) {
  double phi = 0.0;
  cuboid_h_and_potential(half, in_frame(Mat3::Identity(), M), x, &phi);
  return phi;
}

Mat3 cuboid_h_tensor(const Vec3& half, const Vec3& x) {
  // Sum over the 8 vertices V (parity P = s0 s1 s2) of the face-corner terms, d = x - V:
  //   N[w][w] = sum P atan(d_u d_v / (d_w R)),  N[u][v] = -sum P ln(d_k + R), k the third axis.
  // The 24 arctangents and 24 logarithms are gathered first and evaluated 4 at a time (the
  // cross-body near-field tensors of the induction solve spend most of their time here).
  alignas(32) double at_y[24], at_x[24], log_arg[24];
  for (int q = 0; q < 8; ++q) {
    const double s[3] = {(q & 1) ? 1.0 : -1.0, (q & 2) ? 1.0 : -1.0, (q & 4) ? 1.0 : -1.0};
    const double d[3] = {x[0] - s[0] * half[0], x[1] - s[1] * half[1], x[2] - s[2] * half[2]};
    const double d2[3] = {d[0] * d[0], d[1] * d[1], d[2] * d[2]};
    const double R = std::sqrt(d2[0] + d2[1] + d2[2]);
    for (int k = 0; k < 3; ++k) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      log_arg[3 * q + k] = plus_r(d[k], R, d2[u] + d2[v]);
      const double num = d[u] * d[v], den = d[k] * R;
      at_y[3 * q + k] = d[k] >= 0.0 ? num : -num;
      at_x[3 * q + k] = d[k] >= 0.0 ? den : -den;
    }
  }
  alignas(32) double at[24];
  atan2_batch(at_y, at_x, at, 24);
  double diag[3] = {0, 0, 0}, logs[3];
  for (int q = 0; q < 8; ++q) {
    const double P = ((q & 1) ? 1.0 : -1.0) * ((q & 2) ? 1.0 : -1.0) * ((q & 4) ? 1.0 : -1.0);
    for (int k = 0; k < 3; ++k) diag[k] += P * at[3 * q + k];
  }
  for (int k = 0; k < 3; ++k) logs[k] = signed_log_sum(log_arg, k);
  Mat3 N;
  N(0, 0) = diag[0], N(1, 1) = diag[1], N(2, 2) = diag[2];
  N(0, 1) = N(1, 0) = -logs[2];
  N(0, 2) = N(2, 0) = -logs[1];
  N(1, 2) = N(2, 1) = -logs[0];
  return kInv4Pi * N;
}

Vec3 cuboid_b_field(const Vec3& half, const Vec3& M, const Vec3& x) {
  Vec3 B = kMu0 * cuboid_h_field(half, M, x);
  if (std::abs(x[0]) < half[0] && std::abs(x[1]) < half[1] && std::abs(x[2]) < half[2]) B += kMu0 * M;
  return B;
}

void cuboid_pair(const Cuboid& k, const Cuboid& i, int order, Vec3& force, Vec3& torque, double* energy) {
  // Work in i's frame: k's centre, axes and magnetization there.
  const Mat3 Rit = i.rotation.transpose();
  const Vec3 ck = Rit * (k.center - i.center);
  const Mat3 Rk = Rit * k.rotation;          // k frame -> i frame
  const Vec3 Mi = in_frame(Rit, i.magnetization);                   // i frame
  const Vec3 Mk_local = in_frame(k.rotation.transpose(), k.magnetization);  // k frame: face charges
  const double scale = std::max({k.half.maxCoeff(), i.half.maxCoeff()});

  Vec3 F = Vec3::Zero(), T = Vec3::Zero();
  double E = 0.0;
  for (int w = 0; w < 3; ++w) {
    if (Mk_local[w] == 0.0) continue;
    const int u = (w + 1) % 3, v = (w + 2) % 3;
    const Vec3 eu = Rk.col(u), ev = Rk.col(v), ew = Rk.col(w);
    const int au = parallel_axis(eu), av = parallel_axis(ev), aw = parallel_axis(ew);
    const bool aligned = au >= 0 && av >= 0 && aw >= 0;
    for (int side = -1; side <= 1; side += 2) {
      const double sigma = side * Mk_local[w];
      // Face centre, nudged into k so that points on a shared plane see i's outside field.
      const Vec3 fc = ck + (side * k.half[w] * (1.0 - 1e-10)) * ew;
      // Split the face where i's face edges cross it (aligned cuboids only), so each piece is
      // either over or beside i's faces and the integrand has no jump inside a piece.
      std::array<double, 4> su{-k.half[u], k.half[u]}, sv{-k.half[v], k.half[v]};
      int nu = 2, nv = 2;
      bool touching = false;
      if (aligned) {
        // Splits and clustered nodes are needed where k's face lies in or near the plane of
        // one of i's faces (contact, or a gap small against the cells: the integrand is nearly
        // log-singular over i's edges there); elsewhere it is smooth over the whole face. The
        // band is wide so that the rule does not switch inside the range where resting bodies
        // jitter (a switch at 1e-6 cell sizes made the energy of snapped cubes jump by 0.2%).
        touching = std::abs(std::abs(fc[aw]) - i.half[aw]) < 0.25 * scale;
        if (touching) {
          auto add_splits = [&](int axis, const Vec3& e, double h, std::array<double, 4>& sp, int& n) {
            for (int sg = -1; sg <= 1; sg += 2) {
              const double t = (sg * i.half[axis] - fc[axis]) / e[axis];
              if (t > -h + 1e-12 * scale && t < h - 1e-12 * scale) sp[n++] = t;
            }
            sort_small(sp.data(), n);
          };
          add_splits(au, eu, k.half[u], su, nu);
          add_splits(av, ev, k.half[v], sv, nv);
        }
      } else {
        // Rotated: only the distance between the face and i tells whether to cluster nodes.
        touching = true;
      }
      const Rule rule = gauss_rule(order, touching);
      for (int a = 0; a + 1 < nu; ++a) {
        for (int b = 0; b + 1 < nv; ++b) {
          const double u0 = su[a], du = su[a + 1] - su[a];
          const double v0 = sv[b], dv = sv[b + 1] - sv[b];
          for (int p = 0; p < rule.n; ++p) {
            for (int q = 0; q < rule.n; ++q) {
              const double s = u0 + du * rule.x[p], t = v0 + dv * rule.x[q];
              const Vec3 x = fc + s * eu + t * ev;
              double phi = 0.0;
              const Vec3 B = kMu0 * cuboid_h_and_potential(i.half, Mi, x, energy ? &phi : nullptr);
              const double wq = sigma * rule.w[p] * rule.w[q] * du * dv;
              const Vec3 dF = wq * B;
              F += dF;
              T += (x - ck).cross(dF);
              E += wq * phi;
            }
          }
        }
      }
    }
  }
  force = i.rotation * F;
  torque = i.rotation * T;
  if (energy) *energy = kMu0 * E;
}

bool cuboid_overlap_shift(const Cuboid& k, const Cuboid& i, Vec3& shift) {
  shift.setZero();
  const Vec3 d = k.center - i.center;
  double best = std::numeric_limits<double>::infinity();
  Vec3 axis = Vec3::Zero();
  auto test = [&](Vec3 L) {
    const double n = L.norm();
    if (n < 1e-9) return true;  // parallel edges: the face axes already cover this direction
    L /= n;
    const double rk = (k.rotation.transpose() * L).cwiseAbs().dot(k.half);
    const double ri = (i.rotation.transpose() * L).cwiseAbs().dot(i.half);
    const double along = L.dot(d);
    const double overlap = rk + ri - std::abs(along);
    if (overlap <= 0.0) return false;  // a separating axis
    if (overlap < best) best = overlap, axis = along >= 0.0 ? L : Vec3(-L);
    return true;
  };
  for (int a = 0; a < 3; ++a) {
    if (!test(k.rotation.col(a)) || !test(i.rotation.col(a))) return false;
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (!test(k.rotation.col(a).cross(i.rotation.col(b)))) return false;
    }
  }
  shift = best * axis;
  return true;
}

Mat3 cuboid_mean_field_tensor(const Cuboid& target, const Cuboid& source, int order) {
  // Source frame: target centre and axes there.
  const Mat3 Rst = source.rotation.transpose();
  const Vec3 ct = Rst * (target.center - source.center);
  const Mat3 Rt = Rst * target.rotation;
  const Vec3& hs = source.half;
  const Vec3& ht = target.half;
  int axis_of[3] = {-1, -1, -1};
  bool aligned = true;
  for (int a = 0; a < 3; ++a) {
    axis_of[a] = parallel_axis(Rt.col(a));
    aligned = aligned && axis_of[a] >= 0;
  }
  // Interval splits along each target axis at the source's face planes.
  std::array<std::array<double, 4>, 3> cut;
  int ncut[3];
  for (int a = 0; a < 3; ++a) {
    cut[a] = {-ht[a], ht[a], 0, 0};
    ncut[a] = 2;
    if (!aligned) continue;
    const int sa = axis_of[a];
    const double dir = Rt(sa, a);
    for (int sg = -1; sg <= 1; sg += 2) {
      const double t = (sg * hs[sa] - ct[sa]) / dir;
      if (t > -ht[a] * (1 - 1e-12) && t < ht[a] * (1 - 1e-12)) cut[a][ncut[a]++] = t;
    }
    sort_small(cut[a].data(), ncut[a]);
  }
  const Rule rule = gauss_rule(order, true);
  Mat3 N = Mat3::Zero();
  for (int i = 0; i + 1 < ncut[0]; ++i) {
    for (int j = 0; j + 1 < ncut[1]; ++j) {
      for (int k = 0; k + 1 < ncut[2]; ++k) {
        const double d0 = cut[0][i + 1] - cut[0][i], d1 = cut[1][j + 1] - cut[1][j], d2 = cut[2][k + 1] - cut[2][k];
        for (int p = 0; p < rule.n; ++p) {
          for (int q = 0; q < rule.n; ++q) {
            for (int r = 0; r < rule.n; ++r) {
              const Vec3 local(cut[0][i] + d0 * rule.x[p], cut[1][j] + d1 * rule.x[q], cut[2][k] + d2 * rule.x[r]);
              const Vec3 x = ct + Rt * local;
              const double w = rule.w[p] * rule.w[q] * rule.w[r] * d0 * d1 * d2;
              N += w * cuboid_h_tensor(hs, x);
            }
          }
        }
      }
    }
  }
  N /= 8.0 * ht.prod();
  return source.rotation * N * Rst;
}

const Mat3& LatticeTensors::get(const Vec3& half, const Eigen::Vector3i& offset) {
  const std::array<std::int64_t, 6> key{std::bit_cast<std::int64_t>(half[0]), std::bit_cast<std::int64_t>(half[1]),
                                        std::bit_cast<std::int64_t>(half[2]), offset[0], offset[1], offset[2]};
  auto it = cache_.find(key);
  if (it == cache_.end()) {
    const Cuboid t{offset.cast<double>().cwiseProduct(2.0 * half), Mat3::Identity(), half, Vec3::Zero()};
    const Cuboid s{Vec3::Zero(), Mat3::Identity(), half, Vec3::Zero()};
    it = cache_.emplace(key, cuboid_mean_field_tensor(t, s, 6)).first;
  }
  return it->second;
}

}  // namespace magbake::magnetics
