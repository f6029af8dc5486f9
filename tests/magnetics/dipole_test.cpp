// Point-dipole kernels and the whole pipeline on single-cell bodies against the closed forms.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "magnetics/dipole.h"
#include "support/random.h"
#include "support/closed_forms.h"
#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

// F_k = grad (m_k . B_i) by a 4th-order central difference of the field formula.
Vec3 numerical_force(const Vec3& r, const Vec3& mk, const Vec3& mi) {
  Vec3 F;
  const double h = 1e-4 * r.norm();
  for (int a = 0; a < 3; ++a) {
    Vec3 e = Vec3::Zero();
    e[a] = h;
    auto U = [&](const Vec3& x) { return mk.dot(point_dipole_field(mi, x)); };
    F[a] = (-U(r + 2 * e) + 8 * U(r + e) - 8 * U(r - e) + U(r - 2 * e)) / (12 * h);
  }
  return F;
}

TEST(DipoleKernel, MatchesClosedFormsForRandomConfigurations) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> dist(0.001, 0.5), mag(1e-4, 10);
  for (int t = 0; t < 500; ++t) {
    const Vec3 r = dist(rng) * random_unit(rng);
    const Vec3 mk = mag(rng) * random_unit(rng), mi = mag(rng) * random_unit(rng);
    const DipolePair p = dipole_pair(r, mk, mi);
    const Vec3 B = point_dipole_field(mi, r);
    EXPECT_LT((dipole_field(r, mi) - B).norm(), 1e-13 * B.norm());
    EXPECT_LT((p.torque - mk.cross(B)).norm(), 1e-12 * mk.norm() * B.norm());
    EXPECT_NEAR(p.energy, -mk.dot(B), 1e-12 * mk.norm() * B.norm());
    const Vec3 Fn = numerical_force(r, mk, mi);
    EXPECT_LT((p.force - Fn).norm(), 1e-7 * Fn.norm() + 1e-12 * p.force.norm()) << t;
    // Newton's third law and the torque balance of one pair (physics-notes §2).
    const DipolePair q = dipole_pair(-r, mi, mk);
    EXPECT_LT((p.force + q.force).norm(), 1e-13 * p.force.norm());
    EXPECT_LT((r.cross(p.force) + p.torque + q.torque).norm(), 1e-12 * (r.norm() * p.force.norm() + p.torque.norm()));
  }
}

TEST(DipoleKernel, GradientMatchesFiniteDifferences) {
  std::mt19937 rng(3);
  for (int t = 0; t < 50; ++t) {
    const Vec3 r = 0.05 * random_unit(rng), m = random_unit(rng);
    Vec3 B;
    Mat3 G;
    dipole_field_gradient(r, m, B, G);
    const double h = 1e-6;
    for (int b = 0; b < 3; ++b) {
      Vec3 e = Vec3::Zero();
      e[b] = h;
      const Vec3 dB = (dipole_field(r + e, m) - dipole_field(r - e, m)) / (2 * h);
      EXPECT_LT((G.col(b) - dB).norm(), 1e-6 * G.norm());
    }
  }
}


// The two-sided kernel of the walk over bodies equals two one-sided evaluations to rounding, and
// the forces it implies balance (G_a^T m_a = -G_b^T m_b: the gradient is odd in r).
TEST(DipoleKernel, MutualFieldsMatchTwoOneSidedEvaluations) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> dist(0.001, 0.5), mag(1e-4, 10);
  for (int t = 0; t < 200; ++t) {
    const Vec3 r = dist(rng) * random_unit(rng);
    const Vec3 ma = mag(rng) * random_unit(rng), mb = mag(rng) * random_unit(rng);
    Vec3 Ba, Bb, Ba1, Bb1;
    Mat3 Ga, Gb, Ga1, Gb1;
    dipole_mutual_fields(r, ma, mb, Ba, Ga, Bb, Gb);
    dipole_field_gradient(r, mb, Ba1, Ga1);
    dipole_field_gradient(-r, ma, Bb1, Gb1);
    EXPECT_LT((Ba - Ba1).norm(), 1e-14 * Ba1.norm()) << t;
    EXPECT_LT((Bb - Bb1).norm(), 1e-14 * Bb1.norm()) << t;
    EXPECT_LT((Ga - Ga1).norm(), 1e-14 * Ga1.norm()) << t;
    EXPECT_LT((Gb - Gb1).norm(), 1e-14 * Gb1.norm()) << t;
    const Vec3 Fa = Ga.transpose() * ma, Fb = Gb.transpose() * mb;
    EXPECT_LT((Fa + Fb).norm(), 1e-13 * Fa.norm()) << t;
  }
}
TEST(DipoleKernel, ClampKeepsDirectionAndBoundsTheForce) {
  const Vec3 mk(0, 0, 1), mi(0, 0, 1);
  const DipolePair near = dipole_pair(Vec3(0, 0, 1e-6), mk, mi, 1e-3);
  const DipolePair at = dipole_pair(Vec3(0, 0, 1e-3), mk, mi);
  EXPECT_LT((near.force - at.force).norm(), 1e-12 * at.force.norm());
}

// Inside the clamp the energy is continued linearly along r (physics.md §8): it is continuous at
// the clamp distance and its radial derivative is the (constant) radial force, for random
// moments and directions; the double-precision block kernel agrees with the pair function.
TEST(DipoleKernel, ClampedEnergyIsThePotentialOfTheRadialForce) {
  std::mt19937 rng(5);
  const double dmin = 1e-3;
  for (int t = 0; t < 50; ++t) {
    const Vec3 u = random_unit(rng), mk = random_unit(rng), mi = random_unit(rng);
    const DipolePair edge = dipole_pair(dmin * u, mk, mi);
    EXPECT_NEAR(dipole_pair(dmin * (1 - 1e-12) * u, mk, mi, dmin).energy, edge.energy, 1e-9 * std::abs(edge.energy) + 1e-18);
    for (double d : {0.2e-3, 0.5e-3, 0.9e-3}) {
      const double h = 1e-7;
      const double dE = (dipole_pair((d + h) * u, mk, mi, dmin).energy - dipole_pair((d - h) * u, mk, mi, dmin).energy) / (2 * h);
      const double Fr = dipole_pair(d * u, mk, mi, dmin).force.dot(u);
      EXPECT_NEAR(-dE, Fr, 1e-6 * edge.force.norm());
    }
  }
}

// Two sphere magnets (curved: their boundary cells are clamped point dipoles) pressed 0.2 mm into
// each other, as a contact solver leaves them: the reported energy's derivative along the line
// of centres is the force on it, in both kernel precisions (the clamp's energy continuation).
TEST(DipolePipeline, ClampedSpheresInContactKeepEnergyAndForceConsistent) {
  for (KernelPrecision precision : {KernelPrecision::kDouble, KernelPrecision::kSingle}) {
    Rig s;
    s.exact_balls = false;  // lattice cells, so that boundary cells are clamped
    s.add(std::make_unique<geometry::SphereShape>(0.005), permanent(1.3));
    s.add(std::make_unique<geometry::SphereShape>(0.005), permanent(1.3));
    s.build(0.0015);
    Settings st;
    st.theta = 0;
    st.precision = precision;
    auto run = [&](double z) {
      s.state.body_pose[1].position = Vec3(0, 0, z);
      Result r;
      evaluate(s.model, st, s.state, r);
      return r;
    };
    const double z = 0.0098, h = 2e-6;
    const Result r = run(z);
    const double dE = -(run(z + h).energy - run(z - h).energy) / (2 * h);
    EXPECT_NEAR(dE, r.force[1].z(), 0.01 * std::abs(r.force[1].z()))
        << (precision == KernelPrecision::kDouble ? "double" : "float") << ": -dE/dz " << dE << " F_z "
        << r.force[1].z();
  }
}

// Uniformly magnetized spheres are exact dipoles: bodies of one cell each, through the library,
// in both kernel precisions and any theta.
TEST(DipolePipeline, SingleCellSpheresGiveExactDipoleForcesAndTorques) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 40; ++t) {
    Rig s;
    s.add(std::make_unique<geometry::SphereShape>(0.002), permanent(1.2, random_unit(rng)));
    s.add(std::make_unique<geometry::SphereShape>(0.003), permanent(0.8, random_unit(rng)));
    s.build(0.01);  // one cell per sphere
    ASSERT_EQ(s.model.cell_count(), 2);
    s.state.body_pose[0].position = Vec3(u(rng), u(rng), u(rng)) * 0.01;
    s.state.body_pose[0].rotation = Quat(Eigen::AngleAxisd(3 * u(rng), random_unit(rng)));
    s.state.body_pose[1].position = s.state.body_pose[0].position + (0.006 + 0.05 * (u(rng) + 1)) * random_unit(rng);
    s.state.body_pose[1].rotation = Quat(Eigen::AngleAxisd(3 * u(rng), random_unit(rng)));
    const Vec3 m0 = s.state.body_pose[0].rotation * s.model.cell_moment[0];
    const Vec3 m1 = s.state.body_pose[1].rotation * s.model.cell_moment[1];
    // Cell moment = M V of the true sphere volume.
    EXPECT_NEAR(m0.norm(), 1.2 / kMu0 * 4.0 / 3.0 * std::numbers::pi * 8e-9, 1e-12 * m0.norm());
    const Vec3 r = s.state.body_pose[1].position - s.state.body_pose[0].position;
    // The dipole pair from the textbook formulas (not the library's dipole_pair, which the
    // aggregated node pairs at theta > 0 call themselves): on m1 at r from m0,
    // F = 3 mu0 / (4 pi r^4) [(m0.u) m1 + (m1.u) m0 + (m0.m1) u - 5 (m0.u)(m1.u) u], T = m1 x B0,
    // E = -m1.B0, with B0 the test support's own point-dipole field.
    DipolePair ref;
    {
      const double d = r.norm();
      const Vec3 u = r / d;
      const Vec3 B0 = point_dipole_field(m0, r);
      ref.force = 3.0 * kMu0Over4Pi / std::pow(d, 4) *
                  (m0.dot(u) * m1 + m1.dot(u) * m0 + m0.dot(m1) * u - 5.0 * m0.dot(u) * m1.dot(u) * u);
      ref.torque = m1.cross(B0);
      ref.energy = -m1.dot(B0);
    }
    for (auto prec : {KernelPrecision::kSingle, KernelPrecision::kDouble}) {
      for (double theta : {0.0, 0.5, 1.0}) {
        Settings st;
        st.precision = prec;
        st.theta = theta;
        st.near_field = 0.0;
        Result res;
        evaluate(s.model, st, s.state, res);
        const double tol = prec == KernelPrecision::kSingle ? 2e-6 : 1e-12;
        EXPECT_LT((res.force[1] - ref.force).norm(), tol * ref.force.norm());
        EXPECT_LT((res.torque[1] - ref.torque).norm(), tol * (ref.torque.norm() + r.norm() * ref.force.norm()));
        EXPECT_LT((res.force[0] + ref.force).norm(), tol * ref.force.norm());
        // Body 0's torque about its own centre: -(T_1 + r x F_1).
        const Vec3 t0 = -(ref.torque + r.cross(ref.force));
        EXPECT_LT((res.torque[0] - t0).norm(), tol * (t0.norm() + r.norm() * ref.force.norm()));
        // Energy -m.B can be small by cancellation: compare against |m1| |B| instead.
        EXPECT_NEAR(res.energy, ref.energy, tol * 10 * m1.norm() * dipole_field(r, m0).norm());
      }
    }
    // Field of body 0 at points outside it: the exact dipole field plus body 1's (theta 0: at
    // any other theta, points far from both see the two bodies as one aggregate dipole).
    Settings st;
    st.theta = 0.0;
    Result res;
    evaluate(s.model, st, s.state, res);
    for (int q = 0; q < 10; ++q) {
      const Vec3 x = s.state.body_pose[0].position + (0.0025 + 0.1 * (u(rng) + 1)) * random_unit(rng);
      if ((x - s.state.body_pose[1].position).norm() < 0.0035) continue;
      const Vec3 B = field_at_points(s.model, st, s.state, std::span<const Vec3>(&x, 1))[0];
      const Vec3 ref_b = point_dipole_field(m0, x - s.state.body_pose[0].position) +
                         point_dipole_field(m1, x - s.state.body_pose[1].position);
      EXPECT_LT((B - ref_b).norm(), 1e-9 * ref_b.norm());
    }
  }
}

TEST(DipolePipeline, UniformAppliedFieldTurnsAMagnetWithoutForce) {
  Rig s;
  s.add(std::make_unique<geometry::SphereShape>(0.002), permanent(1.0, Vec3::UnitX()));
  s.build(0.01);
  Settings st;
  st.external_field = Vec3(0, 0, 0.05);
  Result r;
  evaluate(s.model, st, s.state, r);
  const Vec3 m = s.model.cell_moment[0];
  EXPECT_EQ(r.force[0], Vec3::Zero());
  EXPECT_LT((r.torque[0] - m.cross(st.external_field)).norm(), 1e-15);
  EXPECT_NEAR(r.energy, -m.dot(st.external_field), 1e-18);
}

}  // namespace
}  // namespace magbake::testing
