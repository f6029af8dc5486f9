// Field of magnetized bodies against closed forms: sphere (exact dipole outside) and cuboid
// (Furlani), and the tree code against direct summation.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "support/closed_forms.h"
#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

// Largest relative error of B over points at distance `dist` from the body's surface along a few
// directions, for a model of the given cell size.
template <class MakeShape, class Exact>
double max_error(MakeShape make, Exact exact, double cell, const Settings& st, const std::vector<Vec3>& pts) {
  Rig s;
  s.exact_balls = false;  // the lattice, on shapes with closed-form fields
  s.add(make(), permanent(1.0));
  s.build(cell);
  Result r;
  evaluate(s.model, st, s.state, r);
  const std::vector<Vec3> B = field_at_points(s.model, st, s.state, pts);
  double err = 0;
  for (std::size_t q = 0; q < pts.size(); ++q) {
    const Vec3 ref = exact(pts[q]);
    err = std::max(err, (B[q] - ref).norm() / ref.norm());
  }
  return err;
}

std::vector<Vec3> directions() {
  return {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(1, 1, 1).normalized(), Vec3(0.3, -0.8, 0.5).normalized(),
          Vec3(0, -0.6, -0.8)};
}

TEST(SphereField, CellModelConvergesToTheExactDipoleOutside) {
  const double R = 0.005;
  const Vec3 m(0, 0, 1.0 / kMu0 * 4.0 / 3.0 * std::numbers::pi * R * R * R);
  auto make = [&] { return std::make_unique<geometry::SphereShape>(R); };
  auto exact = [&](const Vec3& x) { return point_dipole_field(m, x); };
  Settings st;
  st.theta = 0.0;
  st.near_field = 0.0;
  for (double factor : {1.5, 2.0, 5.0, 40.0}) {
    std::vector<Vec3> pts;
    for (const Vec3& d : directions()) pts.push_back(factor * R * d);
    double previous = 1e9;
    for (double cell : {0.004, 0.002, 0.001}) {
      const double err = max_error(make, exact, cell, st, pts);
      if (factor >= 2.0) {
        EXPECT_LT(err, previous * 1.05) << "at " << factor << " R, cell " << cell;
      }
      previous = err;
    }
    // Finest: within 1% from 1.5 R out, and exact far away (the total moment is exact).
    EXPECT_LT(previous, factor >= 5 ? 1e-4 : 0.01) << "at " << factor << " R";
  }
}

TEST(CuboidField, PointDipolesConvergeAndTheNearFieldIsExact) {
  const Vec3 size(0.01, 0.006, 0.004);
  const Vec3 h = 0.5 * size;
  auto make = [&] { return std::make_unique<geometry::BoxShape>(size); };
  auto exact = [&](const Vec3& x) { return furlani_cuboid_field(1.0, h, x); };
  for (double gap : {0.0005, 0.001, 0.005, 0.02, 0.2}) {
    std::vector<Vec3> pts;
    for (const Vec3& d : directions()) {
      // Point at `gap` from the surface along d (distance to the box along the ray).
      const double t = (h.array() / d.array().abs().max(1e-12)).minCoeff();
      pts.push_back((t + gap) * d);
    }
    Settings dip;
    dip.theta = 0.0;
    dip.near_field = 0.0;
    double previous = 1e9;
    for (double cell : {0.002, 0.001, 0.0005}) {
      const double err = max_error(make, exact, cell, dip, pts);
      EXPECT_LT(err, previous) << "gap " << gap << " cell " << cell;
      previous = err;
    }
    // 0.5 mm cells: better than 10% at 0.5 mm and 1% from 2 mm.
    EXPECT_LT(previous, gap < 0.002 ? 0.1 : 0.01) << "gap " << gap;
    // With the near field every cell within its radius is the cuboid it is: with a radius that
    // covers the whole box the field is exact; the default radius (2.5 cells) is within 0.1%.
    Settings exact_near;
    exact_near.theta = 0.0;
    exact_near.near_field = 100.0;
    EXPECT_LT(max_error(make, exact, 0.002, exact_near, pts), 1e-8) << "gap " << gap;
    Settings default_near;
    EXPECT_LT(max_error(make, exact, 0.002, default_near, pts), 1e-3) << "gap " << gap;
  }
}

TEST(FieldTree, AdaptiveTraversalMatchesDirectSummation) {
  Rig s;
  s.add(std::make_unique<geometry::TorusShape>(0.02, 0.006), permanent(1.2, Vec3(0.2, 0.1, 1)));
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.02, 0.005)), permanent(1.0, Vec3(1, 0, 0)));
  s.build(0.001);
  s.state.body_pose[1].position = Vec3(0.05, 0.01, 0.02);
  // Voxel-like targets: a 24^3 lattice over 16 cm, outside the magnets.
  std::vector<Vec3> pts;
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j)
      for (int k = 0; k < 24; ++k) {
        const Vec3 x = Vec3(i, j, k) * (0.16 / 23) - Vec3::Constant(0.08);
        if (x.norm() > 0.03 && (x - s.state.body_pose[1].position).norm() > 0.015) pts.push_back(x);
      }
  Settings direct;
  direct.theta = 0.0;
  Result r;
  evaluate(s.model, direct, s.state, r);
  const auto B0 = field_at_points(s.model, direct, s.state, pts);
  for (double theta : {0.3, 0.5}) {
    Settings st = direct;
    st.theta = theta;
    EvalStats stats0, stats;
    field_at_points(s.model, direct, s.state, pts, &stats0);
    const auto B = field_at_points(s.model, st, s.state, pts, &stats);
    double num = 0, den = 0;
    for (std::size_t q = 0; q < pts.size(); ++q) num += (B[q] - B0[q]).squaredNorm(), den += B0[q].squaredNorm();
    EXPECT_LT(std::sqrt(num / den), theta < 0.4 ? 1e-3 : 2e-2) << theta;
    EXPECT_LT(stats.field_pairs, stats0.field_pairs / (theta < 0.4 ? 2 : 5)) << theta;
    std::printf("theta %.1f: %.2e of %.2e pair evaluations, rms error %.1e\n", theta, double(stats.field_pairs),
                double(stats0.field_pairs), std::sqrt(num / den));
  }
}

TEST(FieldTree, AppliedFieldIsAddedEverywhere) {
  Rig s;
  s.add(std::make_unique<geometry::SphereShape>(0.002), linear(0.0));  // not magnetic
  s.build(0.001);
  Settings st;
  st.external_field = Vec3(1e-3, 0, 5e-5);
  Result r;
  evaluate(s.model, st, s.state, r);
  const Vec3 x(0.1, 0.2, 0.3);
  EXPECT_EQ(field_at_points(s.model, st, s.state, std::span<const Vec3>(&x, 1))[0], st.external_field);
}

}  // namespace
}  // namespace magbake::testing
