// The library's exact cuboid field and cuboid–cuboid interaction (near field) against the test
// suite's independent closed forms.
#include <gtest/gtest.h>

#include <random>

#include "magnetics/cuboid.h"
#include "magnetics/dipole.h"
#include "support/closed_forms.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

TEST(CuboidField, MatchesFurlaniOutside) {
  const Vec3 h(0.005, 0.003, 0.004);
  const double J = 1.2;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  int n = 0;
  while (n < 200) {
    const Vec3 x(u(rng), u(rng), u(rng));
    if ((x.cwiseAbs() - h).maxCoeff() < 1e-4) continue;  // outside only
    const Vec3 ref = furlani_cuboid_field(J, h, x);
    const Vec3 B = cuboid_b_field(h, Vec3(0, 0, J / kMu0), x);
    EXPECT_LT((B - ref).norm(), 1e-9 * ref.norm() + 1e-15) << x.transpose();
    ++n;
  }
}

TEST(CuboidField, InsideIsMu0TimesHPlusM) {
  // Centre of a long bar along its magnetization: B -> J (demagnetizing field vanishes).
  const Vec3 h(0.001, 0.001, 0.5);
  const Vec3 B = cuboid_b_field(h, Vec3(0, 0, 1.0 / kMu0), Vec3::Zero());
  EXPECT_NEAR(B[2], 1.0, 2e-5);
  // Centre of a cube: B = J (1 - N_z) with N_z = 1/3.
  const Vec3 Bc = cuboid_b_field(Vec3(1, 1, 1), Vec3(0, 0, 1.0 / kMu0), Vec3::Zero());
  EXPECT_NEAR(Bc[2], 2.0 / 3.0, 1e-12);
}

TEST(CuboidField, FarFieldIsTheDipoleOfTheSameMoment) {
  const Vec3 h(0.002, 0.003, 0.001);
  const Vec3 M(1e5, -2e5, 3e5);
  const Vec3 x(0.5, 0.3, -0.4);
  const Vec3 ref = dipole_field(x, M * 8.0 * h.prod());
  EXPECT_LT((cuboid_b_field(h, M, x) - ref).norm(), 1e-4 * ref.norm());
}

TEST(CuboidPair, MatchesAkounYonnetForAlignedCubes) {
  const double a = 0.5e-3;  // 1 mm cells
  const Vec3 h(a, a, a);
  const double J = 1.0;
  const Mat3 I = Mat3::Identity();
  for (const Vec3& off : {Vec3(0, 0, 2 * a), Vec3(2 * a, 0, 2 * a), Vec3(2 * a, 2 * a, 2 * a), Vec3(0, 0, 4 * a),
                          Vec3(0.6 * a, 0.4 * a, 2 * a), Vec3(4 * a, 0, 2 * a)}) {
    const Vec3 ref = akoun_yonnet_force(J, J, h, h, off);
    Vec3 F, T;
    cuboid_pair(Cuboid{off, I, h, Vec3(0, 0, J / kMu0)}, Cuboid{Vec3::Zero(), I, h, Vec3(0, 0, J / kMu0)}, 8, F, T);
    EXPECT_LT((F - ref).norm(), 3e-3 * ref.norm()) << off.transpose() / a;
  }
}

TEST(CuboidField, PotentialIsTheFieldsAntiGradient) {
  // H = -grad phi at points outside, near and on the extension of edges; central differences.
  const Vec3 h(0.002, 0.003, 0.001);
  const Vec3 M(1e5, -2e5, 3e5);
  const double d = 1e-7;
  for (const Vec3& x : {Vec3(0.004, 0.001, 0.0005), Vec3(0.0021, 0.0031, 0.0011), Vec3(0.0, 0.0, 0.0015),
                        Vec3(0.002, 0.0035, 0.0), Vec3(-0.01, 0.02, 0.005)}) {
    Vec3 g;
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = Vec3::Unit(a) * d;
      g[a] = -(cuboid_potential(h, M, x + e) - cuboid_potential(h, M, x - e)) / (2 * d);
    }
    const Vec3 H = cuboid_h_field(h, M, x);
    EXPECT_LT((g - H).norm(), 1e-6 * H.norm()) << x.transpose();
  }
  // Far away: the potential of a point dipole, m.r / (4 pi r^3).
  const Vec3 x(0.3, -0.2, 0.5);
  const double ref = (M * 8.0 * h.prod()).dot(x) / (4 * std::numbers::pi * std::pow(x.norm(), 3));
  EXPECT_NEAR(cuboid_potential(h, M, x), ref, 1e-4 * std::abs(ref));
}

TEST(CuboidPair, EnergyIsTheForcesPotentialDownToContact) {
  // Aligned unit cubes (as at magnet contact) and a rotated pair: F = -dE/dx along every axis
  // by central differences of the quadrature energy, and -m.B far away.
  const double a = 0.5e-3;
  const Vec3 h(a, a, a);
  const Mat3 I = Mat3::Identity();
  const Vec3 Mz(0, 0, 1.0 / kMu0);
  const Mat3 R = Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 0.5).normalized())).toRotationMatrix();
  struct Case {
    Vec3 off;
    Mat3 rot;
    double tol;
  };
  for (const Case& c : {Case{Vec3(0, 0, 2.05 * a), I, 2e-3}, Case{Vec3(0.6 * a, 0.4 * a, 2.2 * a), I, 2e-3},
                        Case{Vec3(2.2 * a, 0, 2.2 * a), I, 2e-3}, Case{Vec3(0.5 * a, -0.3 * a, 3.2 * a), R, 5e-3}}) {
    auto energy = [&](const Vec3& off) {
      Vec3 F, T;
      double E = 0;
      cuboid_pair(Cuboid{off, c.rot, h, c.rot * Mz}, Cuboid{Vec3::Zero(), I, h, Mz}, 8, F, T, &E);
      return E;
    };
    Vec3 F, T;
    double E = 0;
    cuboid_pair(Cuboid{c.off, c.rot, h, c.rot * Mz}, Cuboid{Vec3::Zero(), I, h, Mz}, 8, F, T, &E);
    const double d = 1e-4 * a;
    Vec3 g;
    for (int k = 0; k < 3; ++k) g[k] = -(energy(c.off + d * Vec3::Unit(k)) - energy(c.off - d * Vec3::Unit(k))) / (2 * d);
    EXPECT_LT((g - F).norm(), c.tol * F.norm()) << c.off.transpose() / a;
  }
  const Vec3 far(0.01, 0.004, 0.02);
  Vec3 F, T;
  double E = 0;
  cuboid_pair(Cuboid{far, I, h, Mz}, Cuboid{Vec3::Zero(), I, h, Mz}, 4, F, T, &E);
  const double m = 8 * h.prod() / kMu0;
  const double ref = -Vec3(0, 0, m).dot(dipole_field(far, Vec3(0, 0, m)));
  EXPECT_NEAR(E, ref, 1e-4 * std::abs(ref));
}

TEST(CuboidPair, OverlapShiftSeparatesToTouching) {
  const Vec3 h(0.001, 0.001, 0.001);
  const Mat3 I = Mat3::Identity();
  Vec3 shift;
  // Aligned, 0.1 mm deep along z (offset 0.3 mm in x): pushed out along +z by the depth.
  ASSERT_TRUE(cuboid_overlap_shift(Cuboid{Vec3(0.0003, 0, 0.0019), I, h, Vec3::Zero()},
                                   Cuboid{Vec3::Zero(), I, h, Vec3::Zero()}, shift));
  EXPECT_LT((shift - Vec3(0, 0, 0.0001)).norm(), 1e-12);
  // Apart or exactly touching: no shift.
  EXPECT_FALSE(cuboid_overlap_shift(Cuboid{Vec3(0, 0, 0.0021), I, h, Vec3::Zero()},
                                    Cuboid{Vec3::Zero(), I, h, Vec3::Zero()}, shift));
  EXPECT_FALSE(cuboid_overlap_shift(Cuboid{Vec3(0, 0, 0.002), I, h, Vec3::Zero()},
                                    Cuboid{Vec3::Zero(), I, h, Vec3::Zero()}, shift));
  // Rotated: after the shift the two touch (a second test finds no overlap beyond round-off).
  const Mat3 R = Quat(Eigen::AngleAxisd(0.5, Vec3(1, 1, 0).normalized())).toRotationMatrix();
  Cuboid k{Vec3(0.0005, 0.0002, 0.0018), R, Vec3(0.0008, 0.0012, 0.0006), Vec3::Zero()};
  const Cuboid i{Vec3::Zero(), I, h, Vec3::Zero()};
  ASSERT_TRUE(cuboid_overlap_shift(k, i, shift));
  k.center += shift * (1 + 1e-9);
  EXPECT_FALSE(cuboid_overlap_shift(k, i, shift));
}

TEST(CuboidPair, ConservesMomentumAndIsFrameIndependent) {
  // Rotated, non-cubic, differently magnetized cuboids: F_ki = -F_ik and the torques balance
  // (to the quadrature error), and rotating the whole configuration rotates the answer.
  const Quat q1(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  const Quat q2(Eigen::AngleAxisd(-0.7, Vec3(0, 1, 1).normalized()));
  Cuboid k{Vec3(0.004, 0.001, 0.006), q1.toRotationMatrix(), Vec3(0.001, 0.0015, 0.002), Vec3(2e5, 5e5, 1e5)};
  Cuboid i{Vec3::Zero(), q2.toRotationMatrix(), Vec3(0.002, 0.001, 0.0012), Vec3(-3e5, 1e5, 6e5)};
  Vec3 Fk, Tk, Fi, Ti;
  cuboid_pair(k, i, 8, Fk, Tk);
  cuboid_pair(i, k, 8, Fi, Ti);
  EXPECT_LT((Fk + Fi).norm(), 1e-4 * Fk.norm());
  const Vec3 L = k.center.cross(Fk) + Tk + i.center.cross(Fi) + Ti;
  EXPECT_LT(L.norm(), 1e-4 * (k.center.norm() * Fk.norm() + Tk.norm()));
  const Mat3 R = Quat(Eigen::AngleAxisd(1.1, Vec3(1, -1, 0.5).normalized())).toRotationMatrix();
  Cuboid kr{R * k.center, R * k.rotation, k.half, R * k.magnetization};
  Cuboid ir{R * i.center, R * i.rotation, i.half, R * i.magnetization};
  Vec3 Fr, Tr;
  cuboid_pair(kr, ir, 8, Fr, Tr);
  EXPECT_LT((Fr - R * Fk).norm(), 1e-10 * Fk.norm());
  EXPECT_LT((Tr - R * Tk).norm(), 1e-10 * Tk.norm());
}

}  // namespace
}  // namespace magbake::testing

namespace magbake::testing {
namespace {

TEST(CuboidField, TensorMatchesTheFieldOfEachMagnetization) {
  const magnetics::Vec3 h(0.003, 0.001, 0.002);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  for (int t = 0; t < 100; ++t) {
    const magnetics::Vec3 x(u(rng), u(rng), u(rng));
    const magnetics::Mat3 N = magnetics::cuboid_h_tensor(h, x);
    for (int c = 0; c < 3; ++c) {
      const magnetics::Vec3 ref = magnetics::cuboid_h_field(h, magnetics::Vec3::Unit(c), x);
      EXPECT_LT((N.col(c) - ref).norm(), 1e-12 * (ref.norm() + 1)) << x.transpose();
    }
    EXPECT_LT((N - N.transpose()).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace magbake::testing

namespace magbake::testing {
namespace {

// Graded cells (physics.md §7) pair cuboids of different sizes. The field of a source cuboid is
// the sum of the fields of its 8 halves, so its mean over a target must be the sum of the
// halves' means: the unequal-size tensor checked against equal-size ones, touching and apart.
TEST(CuboidField, MeanTensorOfUnequalCuboidsIsTheSumOverTheSourcesHalves) {
  using magnetics::Cuboid;
  using magnetics::Mat3;
  using magnetics::Vec3;
  const Vec3 H(0.002, 0.002, 0.002), h = 0.5 * H;
  for (const Vec3& target_center : {Vec3(0.003, 0.001, -0.001), Vec3(0.003, 0.003, 0.003), Vec3(0.001, 0.001, 0.003),
                                    Vec3(0.009, -0.001, 0.001)}) {
    const Cuboid target{target_center, Mat3::Identity(), h, Vec3::Zero()};
    const Mat3 whole = magnetics::cuboid_mean_field_tensor(target, Cuboid{Vec3::Zero(), Mat3::Identity(), H, Vec3::Zero()}, 6);
    Mat3 halves = Mat3::Zero();
    for (int q = 0; q < 8; ++q) {
      const Vec3 c((q & 1) ? h[0] : -h[0], (q & 2) ? h[1] : -h[1], (q & 4) ? h[2] : -h[2]);
      halves += magnetics::cuboid_mean_field_tensor(target, Cuboid{c, Mat3::Identity(), h, Vec3::Zero()}, 6);
    }
    EXPECT_LT((whole - halves).norm(), 1e-9 * halves.norm() + 1e-12) << target_center.transpose();
  }
}

}  // namespace
}  // namespace magbake::testing
