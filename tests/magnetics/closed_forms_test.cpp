// The test suite's own closed forms, checked against published values and brute-force integrals.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "support/closed_forms.h"

namespace magbake::testing {
namespace {

constexpr double kMu0 = 4e-7 * std::numbers::pi;

TEST(AkounYonnet, CubePairAtFiveMillimetresMatchesPublishedValue) {
  // physics-notes §7: two 1 cm cubes, J = 1 T, coaxial, 5 mm gap: F_z = -6.5683 N.
  const Vec3 h(0.005, 0.005, 0.005);
  const Vec3 F = akoun_yonnet_force(1.0, 1.0, h, h, Vec3(0, 0, 0.015));
  EXPECT_NEAR(F[2], -6.5683, 5e-5);
  EXPECT_NEAR(F[0], 0.0, 1e-12);
  EXPECT_NEAR(F[1], 0.0, 1e-12);
}

TEST(AkounYonnet, ContactIsTheLimitOfVanishingGap) {
  const Vec3 h(0.005, 0.005, 0.005);
  const double f0 = akoun_yonnet_force(1, 1, h, h, Vec3(0, 0, 0.01))[2];
  const double f1 = akoun_yonnet_force(1, 1, h, h, Vec3(0, 0, 0.01 + 1e-9))[2];
  EXPECT_TRUE(std::isfinite(f0));
  EXPECT_NEAR(f0, f1, 1e-5 * std::abs(f0));
}

TEST(AkounYonnet, FarApartIsTwoDipoles) {
  const Vec3 h(0.005, 0.005, 0.005);
  const double d = 0.3;
  const double m = 1.0 / kMu0 * 1e-6;  // M V
  const double dipole = -3.0 * kMu0 * m * m / (2.0 * std::numbers::pi * std::pow(d, 4));
  EXPECT_NEAR(akoun_yonnet_force(1, 1, h, h, Vec3(0, 0, d))[2], dipole, 2e-3 * std::abs(dipole));
}

TEST(AkounYonnet, LateralOffsetGivesNewtonsThirdLaw) {
  const Vec3 h1(0.005, 0.003, 0.004), h2(0.002, 0.006, 0.003);
  const Vec3 d(0.004, -0.002, 0.009);
  const Vec3 F12 = akoun_yonnet_force(1.2, 0.8, h1, h2, d);
  const Vec3 F21 = akoun_yonnet_force(0.8, 1.2, h2, h1, -d);
  EXPECT_LT((F12 + F21).norm(), 1e-9 * F12.norm());
}

// Brute-force field of the two charged faces (sigma = +-J/mu0) by a fine midpoint rule.
Vec3 brute_force_cuboid_field(double J, const Vec3& h, const Vec3& x, int n) {
  Vec3 H = Vec3::Zero();
  const double sigma = J / kMu0;
  const double du = 2 * h[0] / n, dv = 2 * h[1] / n;
  for (int side = -1; side <= 1; side += 2) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Vec3 q(-h[0] + (i + 0.5) * du, -h[1] + (j + 0.5) * dv, side * h[2]);
        const Vec3 r = x - q;
        H += side * sigma * du * dv * r / std::pow(r.norm(), 3);
      }
    }
  }
  return kMu0 * H / (4.0 * std::numbers::pi);
}

TEST(Furlani, MatchesBruteForceSurfaceIntegral) {
  const Vec3 h(0.005, 0.004, 0.003);
  for (const Vec3& x : {Vec3(0.001, 0.002, 0.02), Vec3(0.012, -0.003, 0.001), Vec3(-0.004, 0.011, -0.009),
                        Vec3(0.0, 0.0, -0.05)}) {
    const Vec3 ref = brute_force_cuboid_field(1.3, h, x, 800);
    const Vec3 B = furlani_cuboid_field(1.3, h, x);
    EXPECT_LT((B - ref).norm(), 1e-4 * ref.norm()) << x.transpose() << " : " << B.transpose() << " vs "
                                                    << ref.transpose();
  }
}

TEST(Furlani, FarFieldIsADipole) {
  const Vec3 h(0.005, 0.005, 0.005);
  const Vec3 m(0, 0, 1.0 / kMu0 * 1e-6);
  const Vec3 x(0.3, 0.2, 0.4);
  const Vec3 ref = point_dipole_field(m, x);
  EXPECT_LT((furlani_cuboid_field(1.0, h, x) - ref).norm(), 1e-3 * ref.norm());
}

}  // namespace
}  // namespace magbake::testing
