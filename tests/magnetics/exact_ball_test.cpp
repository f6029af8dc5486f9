// Permanent balls as one exact cell (BuildSettings::exact_balls): the field of a uniformly
// magnetized ball outside it is its point dipole, inside it 2/3 mu0 M; the force and torque on it
// in a field whose sources are outside are those on the point dipole (physics.md §4).
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "magnetics/dipole.h"
#include "support/closed_forms.h"
#include "support/random.h"
#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

constexpr double kR = 0.005;  // ball radius, m
constexpr double kJ = 1.3;    // N42 polarization, T

double ball_volume(double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r; }

TEST(ExactBall, IsOneCellWithTheExactFieldJustOutsideAndInside) {
  const Vec3 dir = Vec3(0.3, -0.5, 0.8).normalized();
  Rig s;
  s.add(std::make_unique<geometry::SphereShape>(kR), permanent(kJ, dir), Pose{Quat::Identity(), Vec3(0.001, 0, 0)});
  s.build(0.001);
  ASSERT_EQ(s.model.cell_count(), 1);
  EXPECT_TRUE(s.model.cell_ball[0]);
  EXPECT_FALSE(s.model.cell_full[0]);
  EXPECT_EQ(s.model.part_report[0].cells, 1);
  const Vec3 m = dir * kJ / kMu0 * ball_volume(kR);
  EXPECT_LT((s.model.cell_moment[0] - m).norm(), 1e-12 * m.norm());
  EXPECT_EQ(s.model.cell_position[0], Vec3(0.001, 0, 0));

  s.state.body_pose[0] = Pose{Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())), Vec3(0.01, -0.02, 0.03)};
  Settings st;  // default theta, near field on
  Result r;
  evaluate(s.model, st, s.state, r);
  const Vec3 centre = s.state.body_pose[0].apply(Vec3(0.001, 0, 0));
  const Vec3 mw = s.state.body_pose[0].rotation * m;
  std::mt19937 rng(5);
  std::vector<Vec3> pts;
  for (double gap : {0.0001, 0.0005, 0.001, 0.01}) {
    for (int k = 0; k < 20; ++k) pts.push_back(centre + (kR + gap) * random_unit(rng));
  }
  const std::vector<Vec3> B = field_at_points(s.model, st, s.state, pts);
  for (std::size_t q = 0; q < pts.size(); ++q) {
    const Vec3 ref = point_dipole_field(mw, pts[q] - centre);
    EXPECT_LT((B[q] - ref).norm(), 1e-12 * ref.norm()) << "point " << q;
  }
  // Inside: B = 2/3 J along the magnetization (mu0 (H + M), H = -M/3), everywhere in the ball.
  std::vector<Vec3> inside;
  for (int k = 0; k < 20; ++k) inside.push_back(centre + kR * (k + 0.5) / 20.0 * random_unit(rng));
  const std::vector<Vec3> Bi = field_at_points(s.model, st, s.state, inside);
  const Vec3 ref_inside = 2.0 / 3.0 * kJ * (s.state.body_pose[0].rotation * dir);
  for (const Vec3& b : Bi) EXPECT_LT((b - ref_inside).norm(), 1e-12 * kJ);
}

// Two N42 balls touching (and 0.5 mm apart), at random turns: exact dipole-pair forces and
// torques, in both kernel precisions. The lattice of the same balls at the default 1 mm cells is
// several percent off in contact (printed; the reason balls get one exact cell).
TEST(ExactBall, TouchingBallsFeelTheExactDipolePair) {
  std::mt19937 rng(7);
  double worst_lattice = 0;
  for (int t = 0; t < 12; ++t) {
    const Vec3 d0 = random_unit(rng), d1 = random_unit(rng);
    const Vec3 axis = random_unit(rng);
    const double gap = t % 2 ? 0.0005 : 0.0;
    for (bool exact : {true, false}) {
      Rig s;
      s.exact_balls = exact;
      s.add(std::make_unique<geometry::SphereShape>(kR), permanent(kJ, d0));
      s.add(std::make_unique<geometry::SphereShape>(kR), permanent(kJ, d1));
      s.build(0.001);
      s.state.body_pose[1].position = (2 * kR + gap) * axis;
      const Vec3 m0 = d0 * kJ / kMu0 * ball_volume(kR), m1 = d1 * kJ / kMu0 * ball_volume(kR);
      const DipolePair ref = dipole_pair(s.state.body_pose[1].position, m1, m0);
      for (auto prec : {KernelPrecision::kDouble, KernelPrecision::kSingle}) {
        Settings st;
        st.precision = prec;
        Result r;
        evaluate(s.model, st, s.state, r);
        const double err = (r.force[1] - ref.force).norm() / ref.force.norm();
        const double terr = (r.torque[1] - ref.torque).norm() / (ref.torque.norm() + kR * ref.force.norm());
        if (exact) {
          const double tol = prec == KernelPrecision::kSingle ? 2e-6 : 1e-12;
          EXPECT_LT(err, tol) << "turn " << t;
          EXPECT_LT(terr, tol) << "turn " << t;
          EXPECT_LT((r.force[0] + r.force[1]).norm(), 1e-12 * ref.force.norm());
          // Single precision sums the energy in float (relative 1e-7).
          EXPECT_NEAR(r.energy, ref.energy, (prec == KernelPrecision::kSingle ? 1e-6 : 1e-12) * std::abs(ref.energy));
        } else if (prec == KernelPrecision::kDouble) {
          worst_lattice = std::max(worst_lattice, err);
        }
      }
    }
  }
  std::printf("lattice of 1 mm cells, touching or 0.5 mm apart: worst force error %.1f%%\n", 100 * worst_lattice);
  // The reason balls are one exact cell (README: the lattice was up to 9% off; measured 9.1%).
  EXPECT_GT(worst_lattice, 0.03);
}

// A steel cube (lattice cells, induced) under a ball magnet: the ball's field at every steel cell
// is its exact dipole, so the cube's force and moment equal those from a model in which the ball
// is replaced by a tiny ball of the same moment at its centre (a point source either way), with
// every cell pair evaluated exactly (theta 0).
TEST(ExactBall, SoftBodiesSeeTheBallAsItsDipole) {
  auto run = [](double radius) {
    Rig s;
    s.add(std::make_unique<geometry::SphereShape>(radius), permanent(kJ * ball_volume(kR) / ball_volume(radius)));
    s.add(std::make_unique<geometry::BoxShape>(Vec3(0.006, 0.006, 0.006)), linear(700));
    s.build(0.001);
    s.state.body_pose[1].position = Vec3(0.0005, 0.001, -(kR + 0.0005 + 0.003));
    Settings st;
    st.theta = 0;  // every cell pair exact: the small ball's run would otherwise use aggregates
    st.induction_tolerance = 1e-10;
    Result r;
    evaluate(s.model, st, s.state, r);
    return r;
  };
  const Result a = run(kR), b = run(kR / 10);
  EXPECT_LT((a.force[1] - b.force[1]).norm(), 1e-8 * b.force[1].norm());
  EXPECT_LT((a.force[0] + a.force[1]).norm(), 1e-9 * a.force[1].norm());
  EXPECT_GT(a.force[1].z(), 1.0);  // pulled up, newtons
}

}  // namespace
}  // namespace magbake::testing
