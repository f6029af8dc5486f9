// The step loop against closed forms: free fall, a sliding box, momentum of interacting magnets.
#include <gtest/gtest.h>

#include <cmath>

#include "bake_fixture.h"
#include "sim/simulator.h"

namespace magbake::sim {
namespace {


// Semi-implicit Euler (Bullet): v_n = v0 + g n h, z_n = z0 + v0 t + g h² n(n+1)/2.
TEST(Simulator, FreeFallMatchesTheClosedForm) {
  Bake r("magbake: 1\nunits: {length: m, angle: deg}\ntime: {fps: 10, frames: [1, 11], dt: 0.001}\n"
        "gravity: [0, 0, -9.81]\nmaterials: {m: {kind: none, density: 1000}}\n"
        "bodies:\n  - {name: ball, shape: {sphere: {radius: 0.01}}, material: m, position: [0, 0, 10], velocity: [1, 0, 2]}\n");
  for (int f = 0; f < 10; ++f) r.sim->advance_frame();
  const double t = 1.0, h = 0.001, n = 1000;
  const SimState& s = r.sim->state();
  EXPECT_NEAR(s.time, t, 1e-12);
  EXPECT_NEAR(s.velocity[0][2], 2 - 9.81 * t, 1e-9);
  EXPECT_NEAR(s.com_position[0][2], 10 + 2 * t - 9.81 * h * h * n * (n + 1) / 2, 1e-9);
  EXPECT_NEAR(s.com_position[0][0], 1.0 * t, 1e-9);
  // Exact to O(h): within g h t / 2 of the continuous parabola.
  EXPECT_NEAR(s.com_position[0][2], 10 + 2 * t - 0.5 * 9.81 * t * t, 0.5 * 9.81 * h * t + 1e-9);
}

// A box sliding on a static floor decelerates at mu g until it stops at v0²/(2 mu g).
TEST(Simulator, SlidingBoxStopsWhereFrictionSays) {
  const double mu = 0.3, v0 = 0.5;
  Bake r("magbake: 1\nunits: {length: m, angle: deg}\ntime: {fps: 50, frames: [1, 26], dt: 0.001}\n"
        "materials: {m: {kind: none, density: 1000}}\n"
        "bodies:\n"
        "  - {name: floor, shape: {box: [1, 1, 0.02]}, material: m, position: [0, 0, -0.01], motion: static, friction: 1}\n"
        "  - {name: box, shape: {box: [0.02, 0.02, 0.02]}, material: m, position: [0, 0, 0.01], velocity: [0.5, 0, 0],"
        " friction: 0.3, restitution: 0}\n");
  // Bullet combines friction as the product of the two bodies' coefficients: 0.3 x 1.
  const double t_stop = v0 / (mu * 9.81);
  double x_at_half = 0, t_half = -1;
  for (int f = 0; f < 25; ++f) {
    r.sim->advance_frame();
    if (t_half < 0 && std::abs(r.sim->state().time - 0.5 * t_stop) < 0.011) {
      t_half = r.sim->state().time;
      x_at_half = r.sim->state().com_position[1][0];
    }
  }
  // Halfway, on the constant deceleration mu g: x = v0 t - mu g t^2 / 2.
  ASSERT_GT(t_half, 0);
  EXPECT_NEAR(x_at_half, v0 * t_half - 0.5 * mu * 9.81 * t_half * t_half, 0.03 * v0 * v0 / (2 * mu * 9.81));
  const SimState& s = r.sim->state();
  EXPECT_NEAR(s.com_position[1][0], v0 * v0 / (2 * mu * 9.81), 0.03 * v0 * v0 / (2 * mu * 9.81));
  EXPECT_LT(s.velocity[1].norm(), 1e-3);
  EXPECT_NEAR(s.com_position[1][2], 0.01, 5e-4);  // stays on the floor
}

}  // namespace
}  // namespace magbake::sim

namespace magbake::sim {
namespace {

// Two weak magnets in zero gravity, released at rest 4 cm apart, tilted: they attract and start to
// turn, without touching within 2000 substeps. Total momentum and angular momentum stay at
// their initial zero, and the energy at its start, up to the bounds below.
TEST(Simulator, InteractingMagnetsConserveMomentumAndAngularMomentum) {
  Bake r("magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 50, frames: [1, 21], dt: 0.0002}\n"
         "gravity: [0, 0, 0]\nmagnetics: {quality: default}\n"
         "materials: {N42: {kind: permanent, remanence: 0.05, density: 7500}}\n"
         "bodies:\n"
         "  - {name: a, shape: {box: [6, 4, 3]}, material: N42, magnetization: [0, 0, 1],"
         " orientation: {axis: [1, 2, 0], angle: 35}}\n"
         "  - {name: b, shape: {cylinder: {radius: 2.5, height: 5}}, material: N42, magnetization: [1, 0, 0],"
         " position: [40, 7, -5], orientation: {axis: [0, 1, 1], angle: 70}}\n");
  const double E0 = r.sim->measure().kinetic_energy + r.sim->measure().magnetic_energy;
  double p_scale = 0, l_scale = 0, p_err = 0, l_err = 0, e_drift = 0, ke_max = 0;
  int steps = 0;
  for (int f = 0; f < 20; ++f) {
    const FrameDiagnostics d = r.sim->advance_frame();
    steps += d.substeps;
    const SimState& s = r.sim->state();
    for (int i = 0; i < 2; ++i) {
      const auto& b = r.scene.bodies[i];
      p_scale = std::max(p_scale, b.mass * s.velocity[i].norm());
      const Mat3 R = s.orientation[i].toRotationMatrix();
      l_scale = std::max({l_scale, (s.com_position[i].cross(b.mass * s.velocity[i])).norm(),
                          (R * b.inertia * R.transpose() * s.angular_velocity[i]).norm()});
    }
    p_err = std::max(p_err, d.momentum.norm());
    l_err = std::max(l_err, d.angular_momentum.norm());
    e_drift = std::max(e_drift, std::abs(d.kinetic_energy + d.magnetic_energy - E0));
    ke_max = std::max(ke_max, d.kinetic_energy);
  }
  const double gap = (r.sim->state().com_position[1] - r.sim->state().com_position[0]).norm();
  ASSERT_GT(gap, 0.012) << "the magnets must not touch";
  ASSERT_GT(p_scale, 1e-8) << "they must move";
  EXPECT_GE(steps, 2000);
  // Every interaction is applied with opposite signs, so momentum is conserved to round-off.
  // Angular momentum also depends on Bullet's first-order rotation update (explicit gyroscopic
  // term): measured 2.9e-5 of the largest term after 2000 substeps; bound 1e-4.
  EXPECT_LT(p_err, 1e-12 * p_scale);
  EXPECT_LT(l_err, 1e-4 * l_scale);
  // The energy the magnets turn into motion is kept to a small fraction (measured 2.2e-12 J of
  // 6.0e-9 J kinetic, 3.6e-4, with the symplectic Euler step at 0.2 ms).
  EXPECT_LT(e_drift, 2e-3 * ke_max);
  std::printf("%d substeps: |P| <= %.2e of max |p_i| %.2e, |L| <= %.2e of %.2e, energy drift %.2e J (E_kin max %.2e)\n",
              steps, p_err / p_scale, p_scale, l_err / l_scale, l_scale, e_drift, ke_max);
}

// A magnet is lowered slowly towards a steel ball resting on a plate; the ball stays until the
// pull exceeds its weight, then jumps. The height of the magnet at lift-off must agree with the
// force balance (found with the same magnetics the way `magbake eval` computes it) within one
// keyframe interval of the magnet's descent.
TEST(Simulator, LiftOffHeightMatchesTheForceBalance) {
  const std::string text =
      "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 100, frames: [1, 401], dt: 0.0005}\n"
      "gravity: [0, 0, -9810]\nmagnetics: {quality: default}\n"
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}, steel: {kind: soft, chi: 700, density: 7850},"
      " plate: {kind: none, density: 2700}}\n"
      "bodies:\n"
      "  - {name: plate, shape: {box: [40, 40, 4]}, material: plate, position: [0, 0, -2], motion: static}\n"
      "  - {name: ball, shape: {sphere: {radius: 3}}, material: steel, position: [0, 0, 3], restitution: 0}\n"
      "  - name: magnet\n    shape: {cylinder: {radius: 4, height: 6}}\n    material: N42\n"
      "    magnetization: [0, 0, 1]\n    motion: kinematic\n    position: [0, 0, 40]\n"
      "    keys: [{t: 0, position: [0, 0, 40]}, {t: 4, position: [0, 0, 12]}]\n";
  Bake r(text);
  const double speed = 28.0 / 4.0 * 1e-3;  // m/s; keys every 0.1 s in the descent's frame grid
  const double key_interval = 0.1 * speed;  // magnet height change per 0.1 s: 0.7 mm
  double lift_height = 0;
  for (int f = 0; f < 400; ++f) {
    r.sim->advance_frame();
    if (r.sim->state().com_position[1][2] > 0.003 + 2e-4) {  // the ball left the plate
      lift_height = r.scene.bodies[2].pose_at(r.sim->state().time).position[2];
      break;
    }
  }
  ASSERT_GT(lift_height, 0) << "the ball never lifted";
  // Force balance: the magnet height where the pull on the resting ball equals its weight.
  const double weight = r.scene.bodies[1].mass * 9.81;
  auto pull = [&](double h) {
    magnetics::State st;
    st.resize(r.model);
    scene::set_poses_at(r.scene, 0, st);
    st.body_pose[2].position = Vec3(0, 0, h);
    magnetics::Result res;
    magnetics::evaluate(r.model, scene::magnetics_settings(r.scene), st, res);
    return res.force[1][2];
  };
  double lo = 0.012, hi = 0.040;  // pull(lo) > weight > pull(hi)
  ASSERT_GT(pull(lo), weight);
  ASSERT_LT(pull(hi), weight);
  for (int k = 0; k < 40; ++k) {
    const double mid = 0.5 * (lo + hi);
    (pull(mid) > weight ? lo : hi) = mid;
  }
  std::printf("lift-off at magnet height %.3f mm, force balance at %.3f mm (key interval %.2f mm)\n",
              lift_height * 1e3, lo * 1e3, key_interval * 1e3);
  EXPECT_LE(lift_height, lo + 1e-9);  // it cannot lift before the pull exceeds the weight
  EXPECT_NEAR(lift_height, lo, key_interval);
}

}  // namespace
}  // namespace magbake::sim
