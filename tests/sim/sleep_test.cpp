// Sleeping (issue 13, outcome 2): magnetic bodies at rest fall asleep (not stepped, their mutual
// forces cached), wake when a contact or a change of their magnetic force says so, and bake what
// a bake without sleeping bakes, within the tolerance the docs state (docs/architecture.md,
// "Sleeping").
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bake_fixture.h"

namespace magbake::sim {
namespace {

// Position tolerance the docs claim between a bake with sleeping and one without, for bodies
// that slept and were woken: 0.1 mm (sleep speeds are at most 5 mm/s or a tenth of a body per
// second; a sleeping body wakes at a force change of 1% of its weight).
constexpr double kSleepPositionTolerance = 1e-4;  // m

// A chain of four 5 mm ball magnets (magnetized along the chain, x) resting on a table;
// optionally a kinematic 10 mm cube magnet (magnetized along x) that stays 10 m away on the
// chain's axis until t = 1.0 s, then comes to 15 mm from the chain's end at t = 1.3 s and stays
// there. 50 fps, dt 1 ms. (Any magnet nearer at the start would already roll or turn the chain.)
std::string resting_scene(double sleep, bool visitor, int frames) {
  std::string s = "magbake: 1\nunits: {length: mm, angle: deg}\n";
  s += "time: {fps: 50, frames: [1, " + std::to_string(frames + 1) + "], dt: 0.001, sleep: " + std::to_string(sleep) + "}\n";
  s += "gravity: [0, 0, -9810]\n";
  s += "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n  wood: {kind: none, density: 700}\n";
  s += "bodies:\n";
  s += "  - {name: table, shape: {box: [300, 300, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n";
  for (int k = 0; k < 4; ++k) {
    s += "  - {name: ball_" + std::to_string(k) + ", shape: {sphere: {radius: 2.5}}, material: N42, magnetization: [1, 0, 0], "
         "position: [" + std::to_string(-7.5 + 5.0 * k) + ", 0, 2.5], friction: 0.5}\n";
  }
  if (visitor) {
    s += "  - {name: visitor, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 0, 0], motion: kinematic, "
         "keys: [{t: 0, position: [10000, 0, 5.5]}, {t: 1.0, position: [10000, 0, 5.5]}, {t: 1.3, position: [30, 0, 5.5]}]}\n";
  }
  return s;
}

struct Shot {
  std::vector<SimState> states;          // per frame, after advance_frame
  std::vector<FrameDiagnostics> frames;  // per frame
};

Shot run(const std::string& yaml, int frames) {
  Bake b(yaml);
  Shot r;
  for (int f = 0; f < frames; ++f) {
    r.frames.push_back(b.sim->advance_frame());
    r.states.push_back(b.sim->state());
  }
  return r;
}

double largest_position_difference(const SimState& a, const SimState& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.com_position.size(); ++i) worst = std::max(worst, (a.com_position[i] - b.com_position[i]).norm());
  return worst;
}

TEST(Sleep, RestingMagnetsFallAsleepAndCostNoMagneticsOrSubsteps) {
  const int frames = 50;  // 1 s
  const Shot on = run(resting_scene(0.5, false, frames), frames);
  const Shot off = run(resting_scene(0, false, frames), frames);
  // Asleep after about the sleep time (0.5 s at rest; the pairs settle within a few frames).
  const FrameDiagnostics& last = on.frames.back();
  EXPECT_EQ(last.sleeping, 4);
  int first_asleep = -1;
  for (int f = 0; f < frames && first_asleep < 0; ++f) {
    if (on.frames[f].sleeping == 4) first_asleep = f;
  }
  ASSERT_GE(first_asleep, 0);
  EXPECT_GE(first_asleep, 24) << "asleep before the sleep time";  // frame 25 is t = 0.5 s
  EXPECT_LE(first_asleep, 40);
  // Asleep: the nominal 20 substeps per frame, and the sleeping magnets' mutual forces
  // evaluated once per frame (the fixed-pairs cache, made afresh at every frame: physics.md §8
  // item 12), not at every substep. Awake, the chain is held by stuck point contacts (item 11),
  // so it takes the nominal substeps too, but its magnetics is evaluated at every one.
  const long long once = on.frames[first_asleep + 1].cells_visited;
  for (int f = first_asleep + 1; f < frames; ++f) {
    EXPECT_EQ(on.frames[f].substeps, 20) << "frame " << f;
    EXPECT_EQ(on.frames[f].cells_visited, once) << "frame " << f;
  }
  EXPECT_GT(once, 0);
  EXPECT_LE(once * 20, off.frames.back().cells_visited) << "asleep: the pairs once per frame, awake at every substep";
  EXPECT_EQ(off.frames.back().substeps, 20);
  EXPECT_GT(off.frames.back().cells_visited, 0);
  // The same shot as without sleeping, and no energy from falling asleep.
  const double diff = largest_position_difference(on.states.back(), off.states.back());
  std::printf("resting pairs: asleep from frame %d; %d vs %d substeps in the last frame; positions %.3g m apart\n",
              first_asleep + 1, on.frames.back().substeps, off.frames.back().substeps, diff);
  EXPECT_LT(diff, kSleepPositionTolerance);
  for (int f = first_asleep; f < frames; ++f) EXPECT_LE(on.frames[f].energy_drift, 1e-9) << "frame " << f;
}

TEST(Sleep, ASleepingPairWakesWhenAMagnetComesNearAndMovesAsWithoutSleeping) {
  const int frames = 80;  // 1.6 s: asleep from ~0.5 s, the visitor arrives at 1.0-1.3 s
  const Shot on = run(resting_scene(0.5, true, frames), frames);
  const Shot off = run(resting_scene(0, true, frames), frames);
  EXPECT_EQ(on.frames[45].sleeping, 4) << "asleep before the visitor moves";
  int wake_ups = 0;
  for (const auto& d : on.frames) wake_ups += d.wake_ups;
  EXPECT_GE(wake_ups, 1);
  // The near pair (bodies 1, 2) is pulled towards the visitor (it moves), as without sleeping.
  const SimState& end_on = on.states.back();
  const SimState& end_off = off.states.back();
  const double moved = (end_off.com_position[1] - off.states[45].com_position[1]).norm();
  const double diff = largest_position_difference(end_on, end_off);
  std::printf("visitor: %d wake-ups; the near pair moved %.3g m; positions %.3g m apart from the bake without sleeping\n",
              wake_ups, moved, diff);
  EXPECT_GT(moved, 1e-3) << "the visitor should move the near pair";
  EXPECT_LT(diff, kSleepPositionTolerance);
  EXPECT_EQ(end_on.sleep[1], kAwake);
}

TEST(Sleep, ARestoredStateSleepsAndWakesAsTheUninterruptedBake) {
  const int frames = 70, cut = 40;  // cut while asleep, before the visitor arrives
  const std::string yaml = resting_scene(0.5, true, frames);
  const Shot full = run(yaml, frames);
  ASSERT_EQ(full.frames[cut - 1].sleeping, 4);
  Bake b(yaml);
  b.sim->restore(full.states[cut - 1], b.scene.first_frame + cut);
  // Bit for bit, asleep, through the wake-up and after it (every frame starts from its state).
  bool woken = false;
  for (int f = cut; f < frames; ++f) {
    const FrameDiagnostics d = b.sim->advance_frame();
    const SimState& s = b.sim->state();
    EXPECT_EQ(d.sleeping, full.frames[f].sleeping) << "frame " << f;
    EXPECT_EQ(d.wake_ups, full.frames[f].wake_ups) << "frame " << f;
    woken = woken || d.wake_ups > 0;
    EXPECT_EQ(s.sleep, full.states[f].sleep) << "frame " << f;
    EXPECT_EQ(largest_position_difference(s, full.states[f]), 0.0) << "frame " << f;
    EXPECT_EQ(s.velocity, full.states[f].velocity) << "frame " << f;
  }
  EXPECT_TRUE(woken);
}

}  // namespace
}  // namespace magbake::sim
