// Joints (scene format 1.1, issue 17 outcome 1): hinge, ball, fixed and slider through Bullet's
// constraints, checked against closed forms: a compass needle on a vertical pivot turns to the
// applied field, a magnetic pendulum swings with the small-angle period, limits hold, a slider
// slides as the incline says and a fixed pair falls as one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "bake_fixture.h"

namespace magbake::sim {
namespace {

using magnetics::kMu0;
using magnetics::Quat;
using magnetics::Vec3;
constexpr double kPi = std::numbers::pi;

// Angle (rad) of a body about z from its initial orientation (it turns about z only).
double yaw(const Quat& q) { return 2 * std::atan2(q.z(), q.w()); }

// A compass: an N42 needle 30 x 2 x 1 mm on a vertical hinge through its middle, 1 mm above a
// table it never touches, gravity on, in the Earth's horizontal field (50 µT) at 60 degrees to
// it. With angular damping 0.9 it turns to the field and settles there: within 0.2 degrees after
// 6 s (e^(-γ t / 2) leaves 0.1% of the swing; after 4 s, 1%: 0.6 degrees), its centre held on
// the pivot to 0.01 mm.
TEST(Joint, ACompassNeedleOnAVerticalPivotTurnsToTheField) {
  const std::string yaml =
      "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 25, frames: [1, 151], dt: 0.001}\n"
      "gravity: [0, 0, -9810]\n"
      "magnetics: {external_field: [2.5e-5, 4.330127e-5, 0]}\n"  // 50 µT at 60 degrees from x
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500, damping: {angular: 0.9}}}\n"
      "bodies:\n"
      "  - {name: needle, shape: {box: [30, 2, 1]}, material: N42, magnetization: [1, 0, 0], position: [0, 0, 10]}\n"
      "joints:\n"
      "  - {name: pivot, type: hinge, bodies: [needle], pivot: [0, 0, 10], axis: [0, 0, 1]}\n";
  Bake r(yaml);
  double drift = 0, angle = 0;
  for (int f = 0; f < 150; ++f) {
    r.sim->advance_frame();
    drift = std::max(drift, (r.sim->state().com_position[0] - Vec3(0, 0, 0.010)).norm());
    angle = yaw(r.sim->state().orientation[0]);
  }
  const Vec3 x = r.sim->state().orientation[0] * Vec3::UnitX();
  std::printf("compass: after 6 s at %.3f deg (field at 60), centre moved %.2e m, needle tilt %.2e\n", angle * 180 / kPi,
              drift, std::abs(x.z()));
  EXPECT_NEAR(angle * 180 / kPi, 60, 0.2);
  EXPECT_LT(drift, 1e-5);
  EXPECT_LT(std::abs(x.z()), 1e-4);  // still horizontal: the hinge holds it against gravity
}

// A magnetic pendulum: a 4 mm N42 ball magnetized along its rod (-z) hangs 30 mm below a
// horizontal hinge (x), in a uniform 10 mT field along -z; gravity and the field both pull it
// back (on a hinge along x, and on a ball joint, where it swings in the same plane):
// I_pivot θ'' = -(M g L + m B) sin θ, I_pivot = 2/5 M r² + M L², small-angle period
// T = 2π sqrt(I_pivot / (M g L + m B)). Swung 3 degrees, the period from its zero crossings over
// 1.5 s is within 0.3% of T (Bullet's semi-implicit step: (ω h)^2 / 24 ~ 1e-5 here).
TEST(Joint, AMagneticPendulumSwingsWithTheSmallAnglePeriod) {
  const double r = 0.002, L = 0.030, B = 0.010, J = 1.3, rho = 7500, g = 9.81;
  const double M = rho * 4.0 / 3 * kPi * r * r * r, m = J * (4.0 / 3 * kPi * r * r * r) / kMu0;
  const double I = 0.4 * M * r * r + M * L * L;
  const double T = 2 * kPi * std::sqrt(I / (M * g * L + m * B));
  const double theta0 = 3 * kPi / 180;
  for (const char* joint : {"hinge", "ball"}) {
    const std::string yaml =
        "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 200, frames: [1, 301], dt: 0.0005, sleep: 0}\n"
        "gravity: [0, 0, -9810]\n"
        "magnetics: {external_field: [0, 0, -0.010]}\n"
        "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}}\n"
        "bodies:\n"
        "  - {name: bob, shape: {sphere: {radius: 2}}, material: N42, magnetization: [0, 0, -1],"
        " position: [0, " + std::to_string(30 * std::sin(theta0)) + ", " + std::to_string(30 - 30 * std::cos(theta0)) +
        "], orientation: {axis: [1, 0, 0], angle: 3}}\n"
        "joints:\n" +
        std::string(joint == std::string("hinge") ? "  - {type: hinge, bodies: [bob, world], pivot: [0, 0, 30], axis: [1, 0, 0]}\n"
                                        : "  - {type: ball, bodies: [bob], pivot: [0, 0, 30]}\n");
    Bake rb(yaml);
    // Zero crossings of the bob's y (linear interpolation between frames).
    std::vector<double> crossings;
    double prev_y = rb.sim->state().com_position[0].y(), prev_t = 0, amplitude = 0;
    for (int f = 1; f <= 300; ++f) {
      rb.sim->advance_frame();
      const double y = rb.sim->state().com_position[0].y(), t = f / 200.0;
      amplitude = std::max(amplitude, std::abs(y));
      if ((prev_y > 0) != (y > 0)) crossings.push_back(prev_t + (t - prev_t) * prev_y / (prev_y - y));
      prev_y = y, prev_t = t;
    }
    ASSERT_GE(crossings.size(), 4u);
    const double period = 2 * (crossings.back() - crossings.front()) / double(crossings.size() - 1);
    std::printf("magnetic pendulum on a %s joint: period %.5f s, small-angle formula %.5f s (%+.3f%%), %zu crossings, swing %.3f mm "
                "(started at %.3f)\n",
                joint, period, T, 100 * (period / T - 1), crossings.size(), 1e3 * amplitude, 1e3 * L * std::sin(theta0));
    EXPECT_NEAR(period / T, 1, 0.003) << joint;
    EXPECT_NEAR(amplitude, L * std::sin(theta0), 0.02 * L * std::sin(theta0));  // no energy gained or lost
  }
}

// Limits: a needle on a hinge limited to [-20, 20] degrees, the field at 90 degrees: it rests on
// its upper limit (Bullet's limit is soft by its error reduction: within 1 degree).
TEST(Joint, AHingeStopsAtItsLimit) {
  const std::string yaml =
      "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 25, frames: [1, 51], dt: 0.001}\n"
      "gravity: [0, 0, 0]\n"
      "magnetics: {external_field: [0, 1.0e-3, 0]}\n"
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500, damping: {angular: 0.9}}}\n"
      "bodies:\n"
      "  - {name: needle, shape: {box: [30, 2, 1]}, material: N42, magnetization: [1, 0, 0]}\n"
      "joints:\n"
      "  - {type: hinge, bodies: [needle], pivot: [0, 0, 0], axis: [0, 0, 1], limits: [-20, 20]}\n";
  Bake r(yaml);
  double most = 0;
  for (int f = 0; f < 50; ++f) {
    r.sim->advance_frame();
    most = std::max(most, yaw(r.sim->state().orientation[0]));
  }
  const double last = yaw(r.sim->state().orientation[0]) * 180 / kPi;
  std::printf("limited hinge: rests at %.3f deg (limit 20), at most %.3f\n", last, most * 180 / kPi);
  EXPECT_NEAR(last, 20, 1.0);
  EXPECT_LT(most * 180 / kPi, 22);
}

// A slider on a 30-degree incline (axis in the x-z plane), no friction in a joint: the body
// slides down with a = g sin 30° (x = a t² / 2, as Bullet's step takes it: to 1 µm) until it
// meets its lower limit, -20 mm, and stays.
// A fixed joint holds two boxes together as they fall (their distance stays 10 mm to 1 µm).
TEST(Joint, ASliderSlidesAsTheInclineSaysAndAFixedPairFallsAsOne) {
  const std::string yaml =
      "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 51], dt: 0.001, sleep: 0}\n"
      "gravity: [0, 0, -9810]\n"
      "materials: {wood: {kind: none, density: 700}}\n"
      "bodies:\n"
      "  - {name: cart, shape: {box: [4, 4, 4]}, material: wood}\n"
      "  - {name: a, shape: {box: [4, 4, 4]}, material: wood, position: [100, 0, 0]}\n"
      "  - {name: b, shape: {box: [4, 4, 4]}, material: wood, position: [110, 0, 0], angular_velocity: [0, 0, 0]}\n"
      "joints:\n"
      "  - {type: slider, bodies: [cart], axis: [0.8660254, 0, 0.5], limits: [-20, 50]}\n"
      "  - {type: fixed, bodies: [a, b]}\n";
  Bake r(yaml);
  const Vec3 axis(0.8660254037844386, 0, 0.5);
  double worst = 0, worst_gap = 0;
  for (int f = 1; f <= 50; ++f) {
    r.sim->advance_frame();
    const double t = f / 100.0, s = r.sim->state().com_position[0].dot(axis);
    const double free = -0.5 * 9.81 * 0.5 * t * t;
    // Bullet's semi-implicit Euler step h gives exactly a (t² + h t) / 2: the continuous
    // formula plus a h t / 2 (0.2 mm at 0.09 s).
    const double stepped = free - 0.5 * 9.81 * 0.5 * 0.001 * t;
    if (stepped > -0.020) worst = std::max(worst, std::abs(s - stepped));
    const Vec3 off = r.sim->state().com_position[0] - s * axis;  // off the axis
    worst = std::max(worst, off.norm());
    worst_gap = std::max(worst_gap, std::abs((r.sim->state().com_position[2] - r.sim->state().com_position[1]).norm() - 0.010));
  }
  const double s_end = r.sim->state().com_position[0].dot(axis);
  std::printf("slider: within %.2e m of g sin(30) (t^2 + h t) / 2 and on its axis, rests at %.3f mm (limit -20); fixed pair gap "
              "within %.2e m, fell %.1f mm\n",
              worst, 1e3 * s_end, worst_gap, -1e3 * r.sim->state().com_position[1].z());
  EXPECT_LT(worst, 1e-6);
  EXPECT_NEAR(s_end, -0.020, 5e-5);
  EXPECT_LT(worst_gap, 1e-6);
  EXPECT_NEAR(r.sim->state().com_position[1].z(), -0.5 * 9.81 * 0.25, 0.003);  // free fall, 0.5 s
}

}  // namespace
}  // namespace magbake::sim

namespace magbake::sim {
namespace {

// A joint to a kinematic body follows it: a wooden bob on a ball joint 50 mm below a carriage
// keyed to move off at 50 mm/s swings about it as a pendulum whose pivot starts moving at v:
// x_bob - x_carriage = -(v / ω) sin(ω t), ω = sqrt(g / L) for a point bob (plus its own
// rotational inertia: ω² = g L / (L² + 2/5 r²)). Measured within 0.095 mm over 1 s, bounded at
// 3 v h = 0.15 mm: Bullet derives the kinematic carriage's velocity from its pose change over each
// step, and the joint's error reduction (0.2 per step) closes the drift of v h this leaves over a
// few steps.
TEST(Joint, AJointToAKinematicBodyFollowsIt) {
  const std::string yaml =
      "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 30, frames: [1, 31], dt: 0.001, sleep: 0}\n"
      "gravity: [0, 0, -9810]\n"
      "materials: {wood: {kind: none, density: 700}}\n"
      "bodies:\n"
      "  - {name: carriage, shape: {box: [10, 10, 10]}, material: wood, motion: kinematic, position: [0, 0, 100],\n"
      "     keys: [{t: 0, position: [0, 0, 100]}, {t: 1, position: [50, 0, 100]}]}\n"
      "  - {name: bob, shape: {sphere: {radius: 5}}, material: wood, position: [0, 0, 50]}\n"
      "joints:\n"
      "  - {type: ball, bodies: [bob, carriage], pivot: [0, 0, 100]}\n";
  Bake r(yaml);
  const double L = 0.050, rad = 0.005, v = 0.050;
  const double omega = std::sqrt(9.81 * L / (L * L + 0.4 * rad * rad));
  double worst = 0, most = 0;
  for (int f = 1; f <= 30; ++f) {
    r.sim->advance_frame();
    const double t = f / 30.0;
    const double rel = r.sim->state().com_position[1].x() - v * t;
    worst = std::max(worst, std::abs(rel + v / omega * std::sin(omega * t)));
    most = std::max(most, std::abs(rel));
  }
  std::printf("bob under a moving carriage: swings %.2f mm about it, within %.3f mm of -(v/w) sin(w t)\n", 1e3 * most,
              1e3 * worst);
  EXPECT_GT(most, 0.8 * v / omega);
  EXPECT_LT(worst, 3 * v * 1e-3);
}

}  // namespace
}  // namespace magbake::sim
