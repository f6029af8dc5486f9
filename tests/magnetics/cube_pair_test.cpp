// The paper's validation (Fig. 6): two 1 cm cubes, J = 1 T, coaxial, against Akoun–Yonnet.
#include <gtest/gtest.h>

#include <cmath>

#include "support/closed_forms.h"
#include "support/scenes.h"

namespace magbake::testing {
namespace {

using magnetics::Settings;
using magnetics::Vec3;

// Force on the upper cube for a face gap g (m) with the given cell size and settings.
double cube_pair_force(double gap, double cell, const Settings& st) {
  Rig s;
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.01, 0.01)), permanent(1.0));
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.01, 0.01)), permanent(1.0));
  s.build(cell);
  s.state.body_pose[1].position = Vec3(0, 0, 0.01 + gap);
  magnetics::Result r;
  magnetics::evaluate(s.model, st, s.state, r);
  EXPECT_LT((r.force[0] + r.force[1]).norm(), 1e-12 * r.force[1].norm());
  return r.force[1][2];
}

double exact(double gap) {
  const Vec3 h(0.005, 0.005, 0.005);
  return akoun_yonnet_force(1, 1, h, h, Vec3(0, 0, 0.01 + gap))[2];
}

// Default settings (cell 2.5 mm, theta 0.5, near field on): within 1% at 5 mm and beyond.
TEST(CubePair, DefaultSettingsWithinOnePercentFromFiveMillimetres) {
  Settings st;
  for (double gap : {0.020, 0.010, 0.005}) {
    const double f = cube_pair_force(gap, 0.0025, st), e = exact(gap);
    std::printf("default, gap %g m: %.2e\n", gap, std::abs(f / e - 1));
    // Measured 2026-12-03: 0.62% at 20 mm (theta's aggregate error, physics.md §5), 0.097% at
    // 10 mm, 0.073% at 5 mm (README: 0.06%).
    EXPECT_NEAR(f, e, (gap > 0.015 ? 0.01 : 2e-3) * std::abs(e)) << "gap " << gap;
  }
}

// Finest settings offered (the `high` preset: 1.25 mm cells, theta 0.3, near-field order 6):
// within 1% down to contact.
TEST(CubePair, HighSettingsWithinOnePercentDownToContact) {
  Settings st;
  st.theta = 0.3;
  st.near_field_order = 6;
  for (double gap : {0.020, 0.005, 0.002, 0.001, 0.0005, 0.0}) {
    const double f = cube_pair_force(gap, 0.00125, st), e = exact(gap);
    std::printf("high, gap %g m: %.2e\n", gap, std::abs(f / e - 1));
    // Measured 2026-12-03: at most 0.19% (1 mm gap), 0.11% at contact.
    EXPECT_NEAR(f, e, 3e-3 * std::abs(e)) << "gap " << gap;
  }
}

// Without the near-field correction the point-dipole method converges to a wrong answer at
// contact (about +40%): the reason the correction exists. Asserted so a regression is noticed.
TEST(CubePair, PurePointDipolesOverestimateContactForce) {
  Settings st;
  st.near_field = 0.0;
  st.theta = 0.0;
  const double f = cube_pair_force(0.0, 0.00125, st), e = exact(0.0);
  EXPECT_GT(f / e, 1.3);
}

// The paper's Fig. 6 convergence: pure dipoles at a 1 mm gap get closer as cells shrink.
TEST(CubePair, PointDipolesConvergeWithCellSizeAtOneMillimetre) {
  Settings st;
  st.near_field = 0.0;
  st.theta = 0.0;
  st.precision = magnetics::KernelPrecision::kDouble;
  const double e = exact(0.001);
  double previous = 1e9;
  for (double cell : {0.005, 0.0025, 0.00125}) {
    const double err = std::abs(cube_pair_force(0.001, cell, st) / e - 1.0);
    EXPECT_LT(err, previous);
    previous = err;
  }
  EXPECT_LT(previous, 0.01);
}

}  // namespace
}  // namespace magbake::testing
