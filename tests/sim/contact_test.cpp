// Magnets meeting: snapping pairs keep their energy and stay together, overlapping starts are
// separated without a kick, and blow-ups are reported (issue 11; physics.md §6, §8).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "bake_fixture.h"
#include "sim/health.h"
#include "sim/simulator.h"

namespace magbake::sim {
namespace {


// Two 1 cm N42 cubes, magnetized along the line joining them, 2 cm apart (centres), on a table
// or floating; they snap within ~40 ms. `frames` frames at 1 kHz (or 1/dt when dt is longer).
// With `balls`, two N42 balls of 5 mm radius (one exact cell each, physics.md §4), centres 15 mm
// apart.
std::string snap_scene(double dt, bool table, int frames, bool balls = false, const char* mb = "[1, 0, 0]") {
  const int fps = std::min(1000, static_cast<int>(std::lround(1.0 / dt)));
  std::string s = "magbake: 1\nunits: {length: mm, angle: deg}\n";
  s += "time: {fps: " + std::to_string(fps) + ", frames: [1, " + std::to_string(frames + 1) + "], dt: " + std::to_string(dt) + "}\n";
  s += table ? "gravity: [0, 0, -9810]\n" : "gravity: [0, 0, 0]\n";
  s += "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n  wood: {kind: none, density: 700}\n";
  s += "bodies:\n";
  if (table) s += "  - {name: table, shape: {box: [200, 200, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n";
  const std::string shape = balls ? "{sphere: {radius: 5}}" : "{box: [10, 10, 10]}";
  const std::string x = balls ? "7.5" : "10";
  s += "  - {name: a, shape: " + shape + ", material: N42, magnetization: [1, 0, 0], position: [-" + x + ", 0, 5], friction: 0.5}\n";
  s += "  - {name: b, shape: " + shape + ", material: N42, magnetization: " + mb + ", position: [" + x + ", 0, 5], friction: 0.5}\n";
  return s;
}

struct SnapRun {
  double binding = 0;      // energy at first contact minus initial energy (> 0), J
  double worst_rise = 0;   // largest rise of the total energy above its lowest value after contact, J
  double final_gap = 0;    // centre distance at the end minus 10 mm, m
  // Centres at t = 0.3 s, m (NaN if the run never passed that instant: then every comparison fails).
  Vec3 at_a = Vec3::Constant(std::numeric_limits<double>::quiet_NaN()), at_b = at_a;
};

SnapRun snap(double dt, bool table, int frames, bool balls = false, const char* mb = "[1, 0, 0]") {
  Bake r(snap_scene(dt, table, frames, balls, mb));
  const int a = table ? 1 : 0, b = a + 1;
  const double e0 = r.sim->measure().total_energy();
  SnapRun out;
  bool met = false;
  double lowest = 0;
  for (int f = 0; f < frames; ++f) {
    const FrameDiagnostics d = r.sim->advance_frame();
    const SimState& s = r.sim->state();
    const double gap = (s.com_position[a] - s.com_position[b]).norm() - 0.01;
    const double e = d.total_energy();
    if (!met && gap < 1e-4) met = true, lowest = e, out.binding = e0 - e;
    if (met) {
      lowest = std::min(lowest, e);
      out.worst_rise = std::max(out.worst_rise, e - lowest);
    }
    out.final_gap = gap;
    if (std::abs(s.time - 0.3) < 1e-9) out.at_a = s.com_position[a], out.at_b = s.com_position[b];
  }
  EXPECT_TRUE(met) << "the magnets never met";
  EXPECT_TRUE(out.at_a.allFinite() || r.sim->state().time < 0.3 - 1e-9) << "no frame at t = 0.3 s";
  return out;
}

// The bounds the docs claim (physics.md §8), issue 11's targets: after contact the total energy
// never rises above its lowest value by more than 2% of the binding energy, at every dt from 0.1
// to 5 ms (measured 0.00-0.55% across the six cases), and positions after 0.3 s converge in dt
// to within 0.5 mm of the dt 0.1 ms run for dt <= 1 ms (measured 0.001 mm at 0.15 s).
constexpr double kSnapEnergyBound = 0.02;
constexpr double kConvergenceBound = 5e-4;  // m

TEST(Contact, SnappedCubesStayTogetherAndGainNoEnergy) {
  std::vector<SnapRun> finals;  // on the table, dt 0.1, 1, 5 ms
  for (bool table : {true, false}) {
    for (double dt : {1e-4, 1e-3, 5e-3}) {
      // 0.3 s of shot (0.15 s at dt 0.1 ms in zero gravity, to keep the suite short).
      const double span = dt < 5e-4 && !table ? 0.15 : 0.3;
      const SnapRun run = snap(dt, table, static_cast<int>(std::lround(span / std::max(dt, 1e-3))));
      std::printf("%s dt %.1f ms: binding %.4f J, largest energy rise after contact %.2e J (%.2f%%), gap %.3f mm\n",
                  table ? "table" : "space", 1e3 * dt, run.binding, run.worst_rise,
                  100 * run.worst_rise / run.binding, 1e3 * run.final_gap);
      EXPECT_GT(run.binding, 0.1);
      EXPECT_LT(run.worst_rise, kSnapEnergyBound * run.binding) << (table ? "table" : "space") << " dt " << dt;
      EXPECT_LT(std::abs(run.final_gap), 5e-4) << (table ? "table" : "space") << " dt " << dt;
      if (table) finals.push_back(run);
    }
  }
  // Convergence in dt on the table: centres at t = 0.3 s against the dt 0.1 ms run, for dt 0.5
  // and 1 ms.
  const SnapRun half = snap(5e-4, true, 300);
  for (const SnapRun* r : std::vector<const SnapRun*>{&finals[1], &half}) {
    const double da = (r->at_a - finals[0].at_a).norm(), db = (r->at_b - finals[0].at_b).norm();
    std::printf("positions at 0.3 s against dt 0.1 ms: %.3f mm, %.3f mm\n", 1e3 * da, 1e3 * db);
    EXPECT_LT(std::max(da, db), kConvergenceBound);
  }
}

// The same for two ball magnets (curved surfaces touching at a point; each ball one exact
// cell): on the table and floating, dt 0.1, 1 and 5 ms; b magnetized along the line joining them
// or turned 53 degrees from it (it turns and rolls while it snaps).
TEST(Contact, SnappedBallsStayTogetherAndGainNoEnergy) {
  for (const char* mb : {"[1, 0, 0]", "[0.6, 0.8, 0]"}) {
    std::vector<SnapRun> finals;
    for (bool table : {true, false}) {
      for (double dt : {1e-4, 1e-3, 5e-3}) {
        const SnapRun run = snap(dt, table, static_cast<int>(std::lround(0.3 / std::max(dt, 1e-3))), true, mb);
        std::printf("balls, b %s, %s dt %.1f ms: binding %.4f J, largest energy rise after contact %.2e J (%.2f%%), gap %.3f mm\n",
                    mb, table ? "table" : "space", 1e3 * dt, run.binding, run.worst_rise,
                    100 * run.worst_rise / run.binding, 1e3 * run.final_gap);
        EXPECT_GT(run.binding, 0.02);
        EXPECT_LT(run.worst_rise, kSnapEnergyBound * run.binding) << mb << (table ? " table" : " space") << " dt " << dt;
        EXPECT_LT(std::abs(run.final_gap), 5e-4) << mb << (table ? " table" : " space") << " dt " << dt;
        if (table) finals.push_back(run);
      }
    }
    for (int k : {1, 2}) {
      const double da = (finals[k].at_a - finals[0].at_a).norm(), db = (finals[k].at_b - finals[0].at_b).norm();
      std::printf("balls, b %s, positions at 0.3 s, dt %s ms against dt 0.1 ms: %.3f mm, %.3f mm\n", mb, k == 1 ? "1" : "5",
                  1e3 * da, 1e3 * db);
      if (k == 1) {
        EXPECT_LT(std::max(da, db), kConvergenceBound) << mb;
      }
    }
  }
}

// A cylinder magnet tumbling in contact with a box magnet in zero gravity (the golden scene
// tests/golden/magnets_in_space.yaml at the default preset): curved against flat, rocking and
// rolling on its side at hundreds of rad/s. The contact must not feed it: after they meet, the
// total energy never rises above its lowest value by more than 2% of their binding energy, at
// dt 0.1, 1 and 5 ms. Before the cylinder became a polyhedral hull clipped along SAT's axis
// (physics.md §8 item 10) its rim sank 0.1-0.16 mm unseen and the late push-out gained 7-20% of
// the binding energy, at every dt down to 10 us.
TEST(Contact, CylinderTumblingOnABoxMagnetGainsNoEnergy) {
  for (double dt : {1e-4, 1e-3, 5e-3}) {
    const int fps = dt < 5e-3 ? 1000 : 200;
    const int frames = static_cast<int>(std::lround(0.3 * fps));
    Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: " + std::to_string(fps) + ", frames: [1, " +
           std::to_string(frames + 1) + "], dt: " + std::to_string(dt) + "}\n"
           "gravity: [0, 0, 0]\nmaterials: {N42: {kind: permanent, remanence: 1.3, density: 7500}}\n"
           "bodies:\n"
           "  - {name: a, shape: {box: [6, 6, 3]}, material: N42, magnetization: [0, 0, 1], position: [0, 0, 0]}\n"
           "  - {name: b, shape: {cylinder: {radius: 3, height: 4}}, material: N42, magnetization: [1, 0, 0],"
           " position: [14, 3, 2], orientation: {axis: [1, 1, 0], angle: 40}}\n");
    bool met = false;
    double lowest = 0, worst_rise = 0, binding = 0, deepest = 0;
    for (int f = 0; f < frames; ++f) {
      const FrameDiagnostics d = r.sim->advance_frame();
      const double e = d.total_energy();
      // Met: their magnetic energy is past 60% of the binding energy (0.0164 J at rest), which it
      // reaches only within about a millimetre of contact.
      if (!met && d.magnetic_energy < -0.01) met = true, lowest = e;
      if (met) {
        lowest = std::min(lowest, e);
        worst_rise = std::max(worst_rise, e - lowest);
        binding = std::max(binding, -d.magnetic_energy);
        deepest = std::max(deepest, d.max_penetration);
      }
    }
    std::printf("cylinder on box, dt %.1f ms: binding %.4f J, largest energy rise after contact %.2e J (%.2f%%), "
                "deepest penetration %.3f mm\n", 1e3 * dt, binding, worst_rise, 100 * worst_rise / binding, 1e3 * deepest);
    ASSERT_TRUE(met) << "dt " << dt;
    EXPECT_GT(binding, 0.015);
    EXPECT_LT(worst_rise, kSnapEnergyBound * binding) << "dt " << dt;
    // Still together at the end: centres within the sum of the bodies' reaches (3.6 + 3.6 mm).
    const SimState& s = r.sim->state();
    EXPECT_LT((s.com_position[0] - s.com_position[1]).norm(), 0.0072) << "dt " << dt;
  }
}

// Two magnets placed 6 mm inside each other (repelling faces, like poles): separated before
// time starts, named in initial_overlaps(), and not blown apart.
TEST(Contact, OverlappingStartIsSeparatedWithoutAKick) {
  Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 11], dt: 0.001}\n"
         "gravity: [0, 0, 0]\nmaterials: {N42: {kind: permanent, remanence: 1.3, density: 7500}}\n"
         "bodies:\n"
         "  - {name: a, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], position: [-2, 0, 0]}\n"
         "  - {name: b, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], position: [2, 0, 0]}\n");
  ASSERT_EQ(r.sim->initial_overlaps().size(), 1u);
  EXPECT_NEAR(r.sim->initial_overlaps()[0].depth, 0.006, 5e-4);
  const SimState& s0 = r.sim->state();
  EXPECT_GT((s0.com_position[0] - s0.com_position[1]).norm(), 0.0099);
  EXPECT_LT(s0.velocity[0].norm() + s0.velocity[1].norm(), 1e-12);
  // Attracting (N-S along x), touching after the separation: they stay together, slowly.
  for (int f = 0; f < 10; ++f) r.sim->advance_frame();
  const SimState& s = r.sim->state();
  EXPECT_LT(std::abs((s.com_position[0] - s.com_position[1]).norm() - 0.01), 5e-4);
  EXPECT_LT(s.velocity[0].norm(), 0.05);
  EXPECT_LT(s.velocity[1].norm(), 0.05);
}

// Two touching 1 cm N42 cubes (pulled together with 55 N) spinning at 10 rad/s as one rigid
// dumbbell in zero gravity, friction 0.5: nothing slips, so the pair must keep its angular
// momentum (issue 11: under 5% per second; before the contact fixes of physics.md §8 it lost
// all of it within 0.1 s) and each cube must keep turning with the pair.
TEST(Contact, SpinningSnappedDumbbellKeepsItsAngularMomentum) {
  Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 26], dt: 0.001}\n"
         "gravity: [0, 0, 0]\nmaterials: {N42: {kind: permanent, remanence: 1.3, density: 7500}}\n"
         "bodies:\n"
         "  - {name: a, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], position: [-5, 0, 0],"
         " friction: 0.5, velocity: [0, -50, 0], angular_velocity: [0, 0, 572.9578]}\n"
         "  - {name: b, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], position: [5, 0, 0],"
         " friction: 0.5, velocity: [0, 50, 0], angular_velocity: [0, 0, 572.9578]}\n");
  const Vec3 l0 = r.sim->measure().angular_momentum;
  ASSERT_NEAR(l0.z(), 6.25e-6, 1e-8);  // 2 (m r v + I w) = 2 (7.5e-3 0.005 0.05 + 1.25e-7 10)
  double worst_spin = 0, worst_gap = 0;
  int substeps = 0;
  for (int f = 0; f < 25; ++f) {
    substeps += r.sim->advance_frame().substeps;
    const SimState& s = r.sim->state();
    for (int b = 0; b < 2; ++b) worst_spin = std::max(worst_spin, std::abs(s.angular_velocity[b].z() - 10.0));
    worst_gap = std::max(worst_gap, std::abs((s.com_position[0] - s.com_position[1]).norm() - 0.01));
  }
  const Vec3 l1 = r.sim->measure().angular_momentum;
  const double loss = 1.0 - l1.norm() / l0.norm();
  std::printf("dumbbell: angular momentum %.6e -> %.6e kg m^2/s in 0.25 s (%.3f%% per second), spins off the "
              "pair's by up to %.3f rad/s, centres off 10 mm by up to %.2e mm; %d Bullet steps for 250 nominal\n",
              l0.norm(), l1.norm(), 100 * loss / 0.25, worst_spin, 1e3 * worst_gap, substeps);
  // The issue asked for under 5% per second. The pair sticks (StuckContacts) and turns as one
  // body held by a joint, whose position correction lets the centres breathe by a few um
  // (measured: 1.7e-5 of the angular momentum over 0.25 s, spins within 3e-3 rad/s, centres
  // within 2.5 um; before sticking, held by the contact alone in 3 pieces per step: 1e-7, 1e-3
  // rad/s, 1e-8 m).
  EXPECT_LT(std::abs(loss), 1e-4);
  EXPECT_LT(worst_spin, 1e-2);                // each cube turns with the pair
  EXPECT_LT(worst_gap, 5e-6);                 // and they stay snapped
  // Held, the pair's pull is the joints' (resolved implicitly) and its load from outside is zero:
  // no pieces (the force guard cut each 1 ms into 3 before the pair could stick).
  EXPECT_LE(substeps, 250 + 5);
}

// A magnet on the side of a fixed bar magnet ("on the fridge"), gravity along the contact face: a
// stuck contact (StuckContacts, physics.md §8 item 11) holds it while friction can, mu F_n > m g,
// and lets it slide when friction cannot. The weaker magnet's remanence sets the pull F_n
// (measured by magbake itself at the first frame); friction 1 x 0.5 (Bullet multiplies them).
TEST(Contact, StuckMagnetHoldsWhileFrictionCanAndSlidesWhenItCannot) {
  for (const double remanence : {0.01, 0.0015}) {
    Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 11], dt: 0.001}\n"
           "gravity: [0, 0, -9810]\nmaterials: {N42: {kind: permanent, remanence: 1.3, density: 7500},"
           " weak: {kind: permanent, remanence: " + std::to_string(remanence) + ", density: 7500}}\n"
           "bodies:\n"
           "  - {name: wall, shape: {box: [10, 10, 200]}, material: N42, magnetization: [1, 0, 0], motion: static,"
           " position: [0, 0, -50],"
           " friction: 1}\n"
           "  - {name: b, shape: {box: [10, 10, 10]}, material: weak, magnetization: [1, 0, 0], position: [10, 0, 0],"
           " friction: 0.5}\n");
    const double pull = -r.sim->state().magnetic_force[1].x();  // N, towards the wall
    const double weight = 7500 * 1e-6 * 9.81, mu = 0.5;
    ASSERT_GT(pull, 0);
    const Vec3 p0 = r.sim->state().com_position[1];
    for (int f = 0; f < 10; ++f) r.sim->advance_frame();
    const SimState& s = r.sim->state();
    const double drop = p0.z() - s.com_position[1].z();  // m, after 0.1 s
    const double expected = 0.5 * (9.81 - mu * pull / 7.5e-3) * 0.1 * 0.1;  // sliding with kinetic friction
    std::printf("on the fridge, remanence %.4f T: pull %.4f N, mu F_n %.4f N against weight %.4f N: dropped %.4f mm "
                "in 0.1 s (sliding would drop %.2f mm), off the wall by %.4f mm\n",
                remanence, pull, mu * pull, weight, 1e3 * drop, 1e3 * expected, 1e3 * (s.com_position[1].x() - 0.01));
    if (mu * pull > weight) {
      EXPECT_LT(std::abs(drop), 2e-6);  // held
    } else {
      EXPECT_NEAR(drop, expected, 0.05 * expected);  // slides as kinetic friction says
    }
    EXPECT_LT(std::abs(s.com_position[1].x() - 0.01), 5e-5);  // on the wall all the while
  }
}

// A steel ball (radius 5 mm, chi 700) resting on top of a cylinder magnet, dt 1 ms: the pull that
// presses it into the contact is the contact's, and a soft sphere has no magnetic torque, so
// resting needs no substeps (issue 11, outcome 2; physics.md §8). The same ball 2 mm above the
// magnet, snapping onto it, does get them: the force guard still holds off approaching bodies.
TEST(Contact, SteelBallRestingOnAMagnetNeedsNoSubsteps) {
  auto scene = [](double z) {
    return "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 31], dt: 0.001}\n"
           "gravity: [0, 0, -9810]\nmaterials: {N42: {kind: permanent, remanence: 1.3, density: 7500},"
           " steel: {kind: soft, chi: 700, density: 7850}}\n"
           "magnetics: {induction: coupled}\n"
           "bodies:\n"
           "  - {name: magnet, shape: {cylinder: {radius: 6, height: 10}}, material: N42, magnetization: [0, 0, 1],"
           " motion: static}\n"
           "  - {name: ball, shape: {sphere: {radius: 5}}, material: steel, friction: 0.5, position: [0, 0, " +
           std::to_string(z) + "]}\n";
  };
  Bake rest(scene(10.0));
  const Vec3 start = rest.sim->state().com_position[1];
  int late_substeps = 0;
  double lowest = 1e300, worst_rise = 0;
  for (int f = 0; f < 30; ++f) {
    const FrameDiagnostics d = rest.sim->advance_frame();
    if (f >= 10) late_substeps += d.substeps;
    if (f >= 2) {
      lowest = std::min(lowest, d.total_energy());
      worst_rise = std::max(worst_rise, d.total_energy() - lowest);
    }
  }
  const double moved = (rest.sim->state().com_position[1] - start).norm();
  Bake snap(scene(12.0));
  int snap_substeps = 0;
  for (int f = 0; f < 5; ++f) snap_substeps += snap.sim->advance_frame().substeps;
  std::printf("steel ball on a magnet: %d substeps in the last 20 frames (nominal 200), moved %.4f mm, energy rise "
              "%.2e J; snapping from 2 mm above: %d substeps in 5 frames (nominal 50)\n",
              late_substeps, 1e3 * moved, worst_rise, snap_substeps);
  EXPECT_EQ(late_substeps, 200);
  EXPECT_LT(moved, 1e-5);
  EXPECT_LT(worst_rise, 1e-6);
  EXPECT_GT(snap_substeps, 50);
}

// A steel ball beside a magnet (physics.md §8 item 8): a soft sphere's cells stay aligned with
// the world, so its forces, the magnet's and the energy do not depend on how the ball has turned
// (bit for bit), as a sphere's do not; its torque is zero.
TEST(Contact, SteelBallForcesDoNotDependOnItsOrientation) {
  const scene::Scene sc = scene::load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\n"
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}, steel: {kind: soft, chi: 700, density: 7850}}\n"
      "magnetics: {induction: coupled}\n"
      "bodies:\n"
      "  - {name: magnet, shape: {box: [10, 10, 10]}, material: N42, magnetization: [0, 0, 1]}\n"
      "  - {name: ball, shape: {sphere: {radius: 4}}, material: steel, position: [3, 9.2, 4]}\n",
      "ball.yaml");
  const magnetics::Model model = scene::build_magnetics_model(sc);
  const magnetics::Settings st = scene::magnetics_settings(sc);
  auto eval = [&](const magnetics::Quat& turn) {
    magnetics::State s;
    s.resize(model);
    scene::set_poses_at(sc, 0.0, s);
    s.body_pose[1].rotation = turn * s.body_pose[1].rotation;
    magnetics::Result r;
    magnetics::evaluate(model, st, s, r);
    return r;
  };
  const magnetics::Result a = eval(magnetics::Quat::Identity());
  const magnetics::Result b = eval(magnetics::Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())));
  ASSERT_GT(a.force[1].norm(), 0.1);  // the ball is pulled (N)
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(a.force[i], b.force[i]) << i;
    EXPECT_EQ(a.torque[i], b.torque[i]) << i;
  }
  EXPECT_EQ(a.energy, b.energy);
  EXPECT_EQ(a.torque[1], Vec3::Zero());
}

// A cylinder rolling on its rim over a table stays on it: Bullet's SAT clipping returned points
// 0.6-1.6 mm above the table for a rim 0.17 mm into it (10-34 degrees of tilt), so the rim sank
// 0.84 mm over 16 ms and was then thrown out (63% of the motion's energy gained); the hull's
// vertices inside a box are now contacts too (rigid_world.cpp, add_hull_vertices_in_box). The
// cylinder's lowest point, from its pose, is never deeper than the split impulse lets a contact
// sink (0.2 mm), and its energy never rises by more than 1% of the kinetic energy it starts with.
TEST(Contact, CylinderRollingOnItsRimDoesNotSinkIntoATable) {
  for (const double tilt : {20.0, 30.0, 40.0}) {
    Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 1000, frames: [1, 61], dt: 0.001}\n"
           "gravity: [0, 0, -9810]\nmaterials: {wood: {kind: none, density: 700}}\nbodies:\n"
           "  - {name: table, shape: {box: [200, 200, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n"
           "  - {name: can, shape: {cylinder: {radius: 5, height: 10}}, material: wood, friction: 0.5,"
           " position: [0, 0, " + std::to_string(5 * std::cos(tilt * std::numbers::pi / 180) + 5 * std::sin(tilt * std::numbers::pi / 180) + 0.3) +
           "], orientation: {axis: [1, 0, 0], angle: " + std::to_string(tilt) + "}, angular_velocity: [1000, 0, 0]}\n");
    const FrameDiagnostics d0 = r.sim->measure();
    const double e0 = d0.total_energy(), scale = d0.kinetic_energy;  // J: the spin it starts with
    double deepest = 0, rise = 0;
    for (int f = 0; f < 60; ++f) {
      const FrameDiagnostics d = r.sim->advance_frame();
      const Vec3 axis = r.sim->state().orientation[1] * Vec3::UnitZ();
      const double low = r.sim->state().com_position[1].z() - 0.005 * std::abs(axis.z()) -
                         0.005 * std::sqrt(std::max(0.0, 1 - axis.z() * axis.z()));
      deepest = std::min(deepest, low);
      rise = std::max(rise, d.total_energy() - e0);
    }
    std::printf("cylinder tilted %.0f deg rolling on its rim: deepest %.3f mm, energy rise %.2f%%\n", tilt, 1e3 * deepest,
                100 * rise / scale);
    EXPECT_GT(deepest, -2e-4) << tilt;
    EXPECT_LT(rise, 0.01 * scale) << tilt;
  }
}

// Steel balls snapping onto a magnet on a table and rolling to rest beside it, dt 1 ms: after
// they meet, the total energy never rises above its lowest value by more than 3% of the binding
// energy, and the ball has come to rest (bench/results/steel_ball_snap_2026-12-05). With the
// ball's cells turning with it, its force changed as it rolled while its (zeroed) torque did no
// work: the first two gained 182% and 95% of their binding energy and still ran at 2.4 and
// 2.3 m/s after 0.5 s. With a rolling ball's pull left out of the force guard the last two
// gained 73% and 8% (4 and 8 mm balls).
TEST(Contact, SteelBallSnappingOntoAMagnetSettles) {
  struct Case {
    const char* magnet;
    double radius;
    Vec3 at;  // mm
  };
  for (const Case& c : {Case{"{box: [10, 10, 10]}", 6, Vec3(0, 12, 17)},            // over the top edge
                        Case{"{cylinder: {radius: 5, height: 10}}", 4, Vec3(1.5, 1, 16)},  // above the top
                        Case{"{box: [10, 10, 10]}", 2, Vec3(1.5, 1, 14)},             // above the top
                        Case{"{box: [10, 10, 10]}", 4, Vec3(0, 10, 15)}}) {           // over the top edge
    const std::string yaml =
        "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 51], dt: 0.001}\n"
        "gravity: [0, 0, -9810]\n"
        "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}, wood: {kind: none, density: 700},"
        " steel: {kind: soft, chi: 700, density: 7850}}\n"
        "bodies:\n"
        "  - {name: table, shape: {box: [200, 200, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n"
        "  - {name: magnet, shape: " + std::string(c.magnet) + ", material: N42, magnetization: [0, 0, 1],"
        " position: [0, 0, 5], friction: 0.5}\n"
        "  - {name: ball, shape: {sphere: {radius: " + std::to_string(c.radius) + "}}, material: steel, friction: 0.5,"
        " position: [" + std::to_string(c.at[0]) + ", " + std::to_string(c.at[1]) + ", " + std::to_string(c.at[2]) + "]}\n";
    Bake r(yaml);
    const double e0 = r.sim->measure().total_energy();
    double lowest = e0, worst_rise = 0, late_speed = 0, binding = 0;
    for (int f = 0; f < 50; ++f) {
      const FrameDiagnostics d = r.sim->advance_frame();
      const double e = d.total_energy();
      lowest = std::min(lowest, e);
      worst_rise = std::max(worst_rise, e - lowest);
      binding = std::max(binding, -d.magnetic_energy);
      if (f >= 40) late_speed = std::max(late_speed, d.max_speed);
    }
    std::printf("steel ball r %.0f mm on %s: binding %.1f mJ, worst rise %.2f%% of it, speed in the last 0.1 s %.3f m/s\n",
                c.radius, c.magnet, 1e3 * binding, 100 * worst_rise / binding, late_speed);
    EXPECT_LT(worst_rise, 0.03 * binding) << c.magnet;
    EXPECT_LT(late_speed, 0.2) << c.magnet;
  }
}

// Two cube magnets resting face to face on a table, dt 1 ms (issue 11, outcome 2; physics.md §8
// item 11): the face contact sticks (a joint in Bullet's solver holds the pull), so the pair takes
// each substep in one piece (7 pieces with the whole pull in the force guard, 3 with the pressed
// pull at the pair's shear stiffness), and stays where it is without gaining energy.
TEST(Contact, CubesRestingFaceToFaceTakeFewPieces) {
  std::string s = snap_scene(1e-3, true, 30);
  for (const char* from : {"position: [-10, 0, 5]", "position: [10, 0, 5]"}) {
    const std::size_t at = s.find(from);
    ASSERT_NE(at, std::string::npos);
    s.replace(at, std::string(from).size(), from[11] == '-' ? "position: [-5.001, 0, 5.001]" : "position: [5.001, 0, 5.001]");
  }
  Bake r(s);
  const Vec3 a0 = r.sim->state().com_position[1], b0 = r.sim->state().com_position[2];
  int substeps = 0, nominal = 0;
  double lowest = 1e300, worst_rise = 0;
  for (int f = 0; f < 30; ++f) {
    const FrameDiagnostics d = r.sim->advance_frame();
    substeps += d.substeps, nominal += r.scene.steps_per_frame();
    lowest = std::min(lowest, d.total_energy());
    worst_rise = std::max(worst_rise, d.total_energy() - lowest);
  }
  const double moved = std::max((r.sim->state().com_position[1] - a0).norm(), (r.sim->state().com_position[2] - b0).norm());
  std::printf("cubes resting face to face: %d Bullet steps for %d nominal (%.2f per substep), moved %.4f mm, "
              "energy rise %.2e J\n", substeps, nominal, double(substeps) / nominal, 1e3 * moved, worst_rise);
  EXPECT_LE(substeps, nominal + 3);  // the first steps, before the pair sticks, may take pieces
  EXPECT_LT(moved, 5e-5);
  EXPECT_LT(worst_rise, 1e-4);  // of a binding energy of 0.16 J
}

// A chain of four cube magnets resting face to face on a table, a smaller one held at its end
// (physics.md §8 item 11): every
// contact sticks, and the middle ones stay stuck, since each joint is tested against the load
// of the whole chain on one side of it (testing a middle joint against half of its cube's own
// load released it after every step, and the chain took 2 pieces per step).
TEST(Contact, ChainOfCubesRestingTakesNoPieces) {
  std::string s = snap_scene(1e-3, true, 30);
  s = s.substr(0, s.find("  - {name: a,"));
  for (int k = 0; k < 4; ++k) {
    s += "  - {name: c" + std::to_string(k) + ", shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], "
         "position: [" + std::to_string(-15.0015 + 10.001 * k) + ", 0, 5.001], friction: 0.5}\n";
  }
  // and a smaller magnet at one end, on the chain's face but off the table (held by the chain)
  s += "  - {name: end, shape: {box: [6, 6, 6]}, material: N42, magnetization: [1, 0, 0], position: [23.0025, 0, 5.001], "
       "friction: 0.5}\n";
  Bake r(s);
  std::vector<Vec3> p0(r.sim->state().com_position);
  int substeps = 0, nominal = 0;
  double lowest = 1e300, worst_rise = 0;
  for (int f = 0; f < 30; ++f) {
    const FrameDiagnostics d = r.sim->advance_frame();
    substeps += d.substeps, nominal += r.scene.steps_per_frame();
    lowest = std::min(lowest, d.total_energy());
    worst_rise = std::max(worst_rise, d.total_energy() - lowest);
  }
  double moved = 0;
  for (int i = 1; i <= 5; ++i) moved = std::max(moved, (r.sim->state().com_position[i] - p0[i]).norm());
  std::printf("chain of four cubes resting: %d Bullet steps for %d nominal, moved %.4f mm, energy rise %.2e J\n",
              substeps, nominal, 1e3 * moved, worst_rise);
  EXPECT_LE(substeps, nominal + 3);
  EXPECT_LT(moved, 5e-5);
  EXPECT_LT(worst_rise, 1e-4);
}

// Ball magnets resting in point contacts (issue 11, outcome 2; physics.md §8 item 11): a 3 x 3 x 3
// block of 5 mm N42 balls on a table, chains along x magnetized +x and -x in a checkerboard (the
// Zen lattice of bench/run_zen_bench.sh, smaller), dt 1 ms, 0.4 s. Once the block has settled
// (balanced as well as still) its ball-ball contacts are held by joints: in the last 0.2 s it
// takes 2 pieces per 1 ms (before: 13, 2600 Bullet steps for 200 nominal), creeps by 0.06 mm
// (before: 4.5 mm), and gains no energy. The 2 pieces come from the balls' point contacts with the
// table, where the force guard still counts their whole pull.
TEST(Contact, BallMagnetsRestingInPointContactsTakeNoPieces) {
  std::string s = "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 41], dt: 0.001}\n"
                  "gravity: [0, 0, -9810]\n"
                  "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n  wood: {kind: none, density: 700}\n"
                  "bodies:\n"
                  "  - {name: table, shape: {box: [200, 200, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n";
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        const int sign = (j + k) % 2 == 0 ? 1 : -1;
        s += "  - {name: b" + std::to_string(i) + std::to_string(j) + std::to_string(k) +
             ", shape: {sphere: {radius: 2.5}}, material: N42, magnetization: [" + std::to_string(sign) +
             ", 0, 0], position: [" + std::to_string(5.0 * (i - 1)) + ", " + std::to_string(5.0 * (j - 1)) + ", " +
             std::to_string(2.5 + 5.0 * k) + "], friction: 0.5}\n";
      }
    }
  }
  Bake r(s);
  int late = 0, late_nominal = 0;
  double lowest = 1e300, worst_rise = 0;
  std::vector<Vec3> p20;
  for (int f = 0; f < 40; ++f) {
    const FrameDiagnostics d = r.sim->advance_frame();
    if (f >= 20) late += d.substeps, late_nominal += r.scene.steps_per_frame();
    if (f == 19) p20 = r.sim->state().com_position;
    if (f >= 2) {
      lowest = std::min(lowest, d.total_energy());
      worst_rise = std::max(worst_rise, d.total_energy() - lowest);
    }
  }
  double moved = 0;
  for (std::size_t i = 1; i < p20.size(); ++i) moved = std::max(moved, (r.sim->state().com_position[i] - p20[i]).norm());
  std::printf("ball magnets resting: %d Bullet steps in the last 20 frames for %d nominal, moved %.4f mm, energy rise "
              "%.2e J\n", late, late_nominal, 1e3 * moved, worst_rise);
  EXPECT_LE(late, 3 * late_nominal);
  EXPECT_LT(moved, 2e-4);
  EXPECT_LT(worst_rise, 1e-5);
}

// Per-island substeps (issue 11, outcome 2; physics.md §8): two cube magnets snapping on a table
// need short pieces; six wooden blocks resting on the same table 6-10 cm away, and a lone magnet
// 12 cm away, do not, and are not refined with them. The snapping pair moves exactly as it does
// without the blocks, and the blocks exactly as they do without the magnets (Bullet solves each
// island on its own, and the held islands are not touched).
TEST(Contact, OnlyTheIslandThatNeedsPiecesIsRefined) {
  auto scene = [](bool pair, bool blocks, bool lone) {
    std::string s = snap_scene(1e-3, true, 60);
    if (!pair) s = s.substr(0, s.find("  - {name: a,"));
    if (blocks) {
      for (int k = 0; k < 6; ++k) {
        const double x = -20.0 + 20.0 * (k % 3), y = k < 3 ? 60.0 : -60.0 - 40.0 * (k == 4);
        s += "  - {name: block" + std::to_string(k) + ", shape: {box: [10, 10, 10]}, material: wood, position: [" +
             std::to_string(x) + ", " + std::to_string(y) + ", 5.01], friction: 0.5}\n";
      }
    }
    if (lone) s += "  - {name: lone, shape: {box: [10, 10, 10]}, material: N42, magnetization: [0, 0, 1], position: [120, 0, 5.01]}\n";
    return s;
  };
  // All; without the blocks; the blocks alone (wood: no magnetic force, whatever is near).
  Bake all(scene(true, true, true)), magnets(scene(true, false, true)), blocks(scene(false, true, false));
  long long steps_all = 0, steps_magnets = 0, body_steps_all = 0, body_steps_magnets = 0, body_steps_blocks = 0;
  int nominal = 0;
  double pair_diff = 0, block_diff = 0;
  for (int f = 0; f < 60; ++f) {
    const FrameDiagnostics da = all.sim->advance_frame(), dm = magnets.sim->advance_frame(), db = blocks.sim->advance_frame();
    steps_all += da.substeps, body_steps_all += da.body_steps;
    steps_magnets += dm.substeps, body_steps_magnets += dm.body_steps, body_steps_blocks += db.body_steps;
    nominal += all.scene.steps_per_frame();
    for (int i : {1, 2}) pair_diff = std::max(pair_diff, (all.sim->state().com_position[i] - magnets.sim->state().com_position[i]).norm());
    for (int i = 0; i < 6; ++i) {
      block_diff = std::max(block_diff, (all.sim->state().com_position[3 + i] - blocks.sim->state().com_position[1 + i]).norm());
    }
  }
  std::printf("snapping pair beside 7 resting bodies: %lld Bullet steps for %d nominal; body steps %lld (without the "
              "blocks %lld, blocks alone %lld); pair off its run without the blocks by %.2e m, blocks off theirs by %.2e m\n",
              steps_all, nominal, body_steps_all, body_steps_magnets, body_steps_blocks, pair_diff, block_diff);
  EXPECT_GT(steps_all, nominal + 20);                                // the snap was refined
  EXPECT_EQ(body_steps_all, body_steps_magnets + 6LL * nominal);    // the blocks were not
  EXPECT_EQ(body_steps_blocks, 6LL * nominal);
  EXPECT_LT(body_steps_magnets, 3 * steps_magnets);  // nor was the lone magnet (3 bodies)
  EXPECT_EQ(pair_diff, 0.0);  // bit-identical to the lone runs (README, physics.md §8 item 9)
  EXPECT_EQ(block_diff, 0.0);
}

// The health summary names an energy rise without a source and a body that left the region.
TEST(Health, NamesEnergyGrowthAndLostBodies) {
  const scene::Scene sc = scene::load_scene_text(
      "magbake: 1\nunits: {length: m, angle: deg}\ntime: {fps: 10, frames: [1, 11], dt: 0.001}\n"
      "gravity: [0, 0, -9.81]\nmaterials: {m: {kind: none, density: 1000}}\n"
      "bodies:\n  - {name: ball, shape: {sphere: {radius: 0.01}}, material: m}\n"
      "  - {name: rock, shape: {sphere: {radius: 0.01}}, material: m, position: [0.1, 0, 0]}\n",
      "test.yaml");
  SimState s;
  s.resize(2);
  s.com_position[1] = Vec3(0.1, 0, 0);
  HealthMonitor quiet(sc, s), loud(sc, s);
  for (int f = 1; f <= 5; ++f) {
    FrameDiagnostics d;
    d.kinetic_energy = 1.0;
    d.magnetic_energy = -1.0;
    quiet.observe(f, s, d);
    d.kinetic_energy = 1.0 + 0.1 * f;  // rising: 0.5 J over a scale of 2.5 J
    d.max_speed = f;
    d.max_speed_body = 1;
    SimState far = s;
    if (f >= 4) far.com_position[0] = Vec3(0, 0, -5);
    loud.observe(f, far, d);
  }
  EXPECT_TRUE(quiet.warnings().empty());
  const auto w = loud.warnings();
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("energy grew without a source"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("'rock'"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("frame 1 to frame 5"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("'ball' at frame 4"), std::string::npos) << w[1];
}

}  // namespace
}  // namespace magbake::sim
