// The second-order local expansion of a dipole's field (local_expansion.h) against the closed
// form and finite differences, and its re-centring.
#include <gtest/gtest.h>

#include <random>

#include "magnetics/dipole.h"
#include "magnetics/local_expansion.h"
#include "support/random.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

TEST(LocalExpansion, DerivativesMatchTheDipoleAndFiniteDifferences) {
  std::mt19937 rng(17);
  for (int t = 0; t < 100; ++t) {
    const Vec3 r = 0.02 * random_unit(rng), m = 0.3 * random_unit(rng);
    LocalExpansion L;
    L.add_dipole(r, m);
    Vec3 B;
    Mat3 G;
    dipole_field_gradient(r, m, B, G);
    EXPECT_LT((L.b - B).norm(), 1e-13 * B.norm()) << t;
    EXPECT_LT((L.gradient() - G).norm(), 1e-12 * G.norm()) << t;
    EXPECT_LT(std::abs(L.gradient().trace()), 1e-12 * G.norm()) << t;  // divergence-free
    // h[i](k, l) = dG(i, k)/dx_l by a fourth-order central difference of the closed-form gradient.
    const double step = 1e-4 * r.norm();
    double hnorm = 0, herr = 0;
    for (int l = 0; l < 3; ++l) {
      auto grad = [&](double s) {
        Vec3 b;
        Mat3 g;
        dipole_field_gradient(r + s * step * Vec3::Unit(l), m, b, g);
        return g;
      };
      const Mat3 dG = (-grad(2) + 8 * grad(1) - 8 * grad(-1) + grad(-2)) / (12 * step);
      for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) {
          herr = std::max(herr, std::abs(L.hessian(i, k, l) - dG(i, k)));
          hnorm = std::max(hnorm, std::abs(dG(i, k)));
        }
      }
    }
    EXPECT_LT(herr, 1e-7 * hnorm) << t;  // the closed-form gradient is symmetric in (i, k): so is h
    double trace = 0;
    for (int i = 0; i < 3; ++i) trace += std::abs(L.hessian(i, 0, 0) + L.hessian(i, 1, 1) + L.hessian(i, 2, 2));
    EXPECT_LT(trace, 1e-10 * hnorm) << t;  // harmonic
  }
}

// The truncation error falls as the cube of the offset (third order), and re-centring is exact.
TEST(LocalExpansion, ErrorIsThirdOrderAndShiftingIsExact) {
  std::mt19937 rng(5);
  for (int t = 0; t < 20; ++t) {
    const Vec3 r = 0.05 * random_unit(rng), m = random_unit(rng), dir = random_unit(rng);
    LocalExpansion L;
    L.add_dipole(r, m);
    auto error = [&](double x) { return (L.at(x * dir) - dipole_field(r + x * dir, m)).norm(); };
    const double e1 = error(0.004), e2 = error(0.002);
    EXPECT_NEAR(e1 / e2, 8.0, 1.0) << t;
    EXPECT_LT(e1, 20.0 * std::pow(0.004 / 0.05, 3) * dipole_field(r, m).norm()) << t;
    const Vec3 delta = 0.003 * random_unit(rng), x = 0.002 * random_unit(rng);
    LocalExpansion S;
    L.shift_into(delta, S);
    EXPECT_LT((S.at(x) - L.at(delta + x)).norm(), 1e-12 * L.b.norm()) << t;
  }
}

// The field walk adds four dipoles' terms at a time in SIMD lanes (field.cpp): bit for bit what
// one at a time adds, so results do not depend on how pairs fall into batches.
TEST(LocalExpansion, VectorLanesComputeExactlyTheScalarTerms) {
  using v4d = double __attribute__((vector_size(32)));
  std::mt19937 rng(9);
  for (int t = 0; t < 50; ++t) {
    v4d r[3], m[3];
    double rs[4][3], ms[4][3];
    for (int j = 0; j < 4; ++j) {
      const Vec3 a = 0.01 * (1 + j) * random_unit(rng), b = random_unit(rng);
      for (int c = 0; c < 3; ++c) r[c][j] = rs[j][c] = a[c], m[c][j] = ms[j][c] = b[c];
    }
    v4d vt[LocalExpansion::kTerms];
    LocalExpansion::dipole_terms(
        r, m,
        [](v4d d2) {
          v4d out;
          for (int j = 0; j < 4; ++j) out[j] = 1.0 / std::sqrt(d2[j]);
          return out;
        },
        vt);
    for (int j = 0; j < 4; ++j) {
      double st[LocalExpansion::kTerms];
      LocalExpansion::dipole_terms(rs[j], ms[j], [](double d2) { return 1.0 / std::sqrt(d2); }, st);
      for (int q = 0; q < LocalExpansion::kTerms; ++q) EXPECT_EQ(vt[q][j], st[q]) << t << " " << j << " " << q;
    }
  }
}

}  // namespace
}  // namespace magbake::testing
