// Saturating soft materials (Fröhlich–Kennelly law, physics.md §13) against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "support/closed_forms.h"
#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

Material saturating(double chi, double Js) {
  Material m = linear(chi);
  m.saturation = Js;
  return m;
}

// A uniformly magnetized sphere in a uniform field H0 has the uniform inside field H0 - M/3, so
// a sphere of a saturating material is uniformly magnetized with the M that solves
// M = F(H0 - M/3), F the Fröhlich–Kennelly law; F is increasing, so bisection on [0, min(3 H0, Ms)].
double exact_saturating_sphere_magnetization(double chi, double ms, double H0) {
  double lo = 0, hi = std::min(3.0 * H0, ms);
  for (int k = 0; k < 200; ++k) {
    const double M = 0.5 * (lo + hi);
    const double H = H0 - M / 3.0;
    const double F = chi * H / (1.0 + chi * std::abs(H) / ms);
    (F > M ? lo : hi) = M;
  }
  return 0.5 * (lo + hi);
}

// A steel sphere (radius 5 mm, J_s = 2 T) in a uniform field from 1 mT (linear) to 5 T (deep
// saturation): the coupled solve with Newton's method gives the exact moment, and the law holds.
TEST(Saturation, SphereInAUniformFieldHasTheClosedFormMomentFromLinearToDeepSaturation) {
  const double R = 0.005, Js = 2.0, V = 4.0 / 3.0 * std::numbers::pi * R * R * R;
  for (double chi : {10.0, 700.0, 2e4}) {
    Rig s;
    s.add(std::make_unique<geometry::SphereShape>(R), saturating(chi, Js));
    s.build(0.001);
    for (double B0 : {1e-3, 0.1, 0.5, 0.667, 0.8, 1.5, 5.0}) {
      Settings st;
      st.external_field = Vec3(0, 0, B0);
      st.induction_tolerance = 1e-9;
      s.state.induced_moment.clear();  // cold start: Newton from the linear law
      Result r;
      evaluate(s.model, st, s.state, r);
      const double exact = V * exact_saturating_sphere_magnetization(chi, Js / kMu0, B0 / kMu0);
      std::printf("chi %-6g B0 %-5g T: moment/exact %.7f  M/Ms %.4f  Newton %d  GMRES %d  law mismatch %.1e\n", chi,
                  B0, r.moment[0][2] / exact, exact / V / (Js / kMu0), r.induction.nonlinear_iterations,
                  r.induction.iterations, r.induction.nonlinear_residual);
      EXPECT_TRUE(r.induction.converged) << "chi " << chi << " B0 " << B0;
      EXPECT_NEAR(r.moment[0][2], exact, 1e-5 * exact) << "chi " << chi << " B0 " << B0;
      EXPECT_LT(r.moment[0].head<2>().norm(), 1e-6 * exact);
    }
  }
}

// Without a saturation the law is linear and nothing changes: no Newton steps, and a saturation
// far above the field's reach gives the linear moment.
TEST(Saturation, AHighSaturationGivesTheLinearMoment) {
  for (double Js : {0.0, 1e6}) {
    Rig s;
    s.add(std::make_unique<geometry::SphereShape>(0.005), saturating(700, Js));
    s.build(0.001);
    Settings st;
    st.external_field = Vec3(0, 0, 0.01);
    st.induction_tolerance = 1e-9;
    Result r;
    evaluate(s.model, st, s.state, r);
    const double H0 = 0.01 / kMu0, exact = 4.0 * std::numbers::pi * 125e-9 * 700.0 / 703.0 * H0;
    EXPECT_NEAR(r.moment[0][2], exact, 2e-5 * exact) << "Js " << Js;
    if (Js == 0) EXPECT_EQ(r.induction.nonlinear_iterations, 0);
    else EXPECT_GE(r.induction.nonlinear_iterations, 1);
  }
}

// A steel ball touching a strong magnet (a 12 mm N52 cube, a 1/2-inch ball 10 um above it). With
// the force on the ball F = integral (M . grad) B_magnet dV and |M| <= M_s, saturation bounds it
// by M_s sum_cells V |grad B_magnet| (spectral norm; the cube's closed-form field, gradient by
// central differences): the saturating force stays within that bound at every cell size and
// saturation polarization, and it is reported beside the linear law's.
TEST(Saturation, SteelBallOnAStrongMagnetHasABoundedForce) {
  const double J = 1.45, a = 0.006, r = 0.00635;
  const Vec3 ball(0, 0, a + r + 1e-5);
  auto run = [&](double saturation, double cell, Result& res, Rig& s) {
    s.add(std::make_unique<geometry::BoxShape>(Vec3(2 * a, 2 * a, 2 * a)), permanent(J));
    s.add(std::make_unique<geometry::SphereShape>(r), saturating(700, saturation));
    s.build(cell);
    s.state.body_pose[1].position = ball;
    Settings st;
    st.induction_tolerance = 1e-7;
    evaluate(s.model, st, s.state, res);
  };
  for (double cell : {0.0016, 0.0008}) {
    Rig lin_rig;
    Result lin;
    run(0.0, cell, lin, lin_rig);
    for (double Js : {2.0, 0.6}) {
      const double ms = Js / kMu0;
      Rig s;
      Result sat;
      run(Js, cell, sat, s);
      double mmax = 0, bound = 0;
      for (std::size_t q = 0; q < s.model.induced_cells.size(); ++q) {
        const int c = s.model.induced_cells[q];
        mmax = std::max(mmax, s.state.induced_moment[q].norm() / s.model.cell_volume[c]);
        const Vec3 x = ball + s.model.cell_position[c];
        Mat3 G;
        const double h = 1e-7;
        for (int k = 0; k < 3; ++k) {
          G.col(k) = (furlani_cuboid_field(J, Vec3(a, a, a), x + h * Vec3::Unit(k)) -
                      furlani_cuboid_field(J, Vec3(a, a, a), x - h * Vec3::Unit(k))) / (2 * h);
        }
        bound += ms * s.model.cell_volume[c] * Eigen::JacobiSVD<Mat3>(G).singularValues()[0];
      }
      std::printf("cell %.1f mm: linear %.3f N | Js %.1f T: %.3f N (bound %.3f N), largest cell |M| %.3f Ms, "
                  "Newton %d, GMRES %d\n",
                  cell * 1e3, -lin.force[1][2], Js, -sat.force[1][2], bound, mmax / ms,
                  sat.induction.nonlinear_iterations, sat.induction.iterations);
      EXPECT_TRUE(sat.induction.converged) << "Js " << Js;
      EXPECT_LT(mmax, ms);
      EXPECT_LT(sat.force[1][2], 0.0);  // attracted
      EXPECT_LT(sat.force[1].norm(), bound) << "Js " << Js;
      EXPECT_LT(sat.force[1].norm(), lin.force[1].norm()) << "Js " << Js;
    }
  }
}

// The reported energy of saturating matter (physics.md §13: -1/2 m.B0 plus the law's stored
// energy less mu0 M.H / 2 per cell) is the potential of the force, by central differences: a
// steel sphere (J_s 0.6 T) beside a magnet, from nearly linear to nearly saturated (measured:
// within 1e-5 of the force; a per-cell charging estimate, -g(a) m.B0, was 5-42% off).
TEST(Saturation, ReportedEnergyIsThePotentialOfTheForce) {
  for (double gap : {0.012, 0.004, 0.0005}) {
    Rig s;
    s.add(std::make_unique<geometry::CylinderShape>(0.005, 0.01), permanent(1.3));
    s.add(std::make_unique<geometry::SphereShape>(0.004), saturating(700, 0.6));
    s.build(0.001);
    Settings st;
    st.theta = 0;
    st.induction_tolerance = 1e-12;
    const Vec3 at(0.0005, 0.0003, 0.005 + 0.004 + gap);
    auto run = [&](const Vec3& x) {
      s.state.body_pose[1].position = x;
      s.state.induced_moment.clear();
      Result r;
      evaluate(s.model, st, s.state, r);
      return r;
    };
    const Result r = run(at);
    const double d = 2e-6;
    Vec3 g;
    for (int k = 0; k < 3; ++k) g[k] = -(run(at + d * Vec3::Unit(k)).energy - run(at - d * Vec3::Unit(k)).energy) / (2 * d);
    double mmax = 0;
    for (std::size_t q = 0; q < s.model.induced_cells.size(); ++q) {
      mmax = std::max(mmax, s.state.induced_moment[q].norm() / s.model.cell_volume[s.model.induced_cells[q]]);
    }
    std::printf("gap %.1f mm: |M|max %.3f Ms, F %.5f N, -dE/dz %.5f N, |difference| / |F| %.1e\n", gap * 1e3,
                mmax * kMu0 / 0.6, r.force[1][2], g[2], (g - r.force[1]).norm() / r.force[1].norm());
    EXPECT_TRUE(r.induction.converged);
    EXPECT_LT((g - r.force[1]).norm(), 1e-3 * r.force[1].norm()) << "gap " << gap;
  }
}

}  // namespace
}  // namespace magbake::testing
