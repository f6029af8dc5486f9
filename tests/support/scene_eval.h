// Evaluating a loaded scene's magnetics at its initial poses, for the reference tests.
#pragma once

#include "magnetics/system.h"
#include "scene/scene_magnetics.h"

namespace magbake::testing {

/// The scene's magnetic model evaluated with its own settings at time 0 (kinematic bodies at
/// their first keys): forces and torques (N, N·m, world), moments and the induction report.
inline magnetics::Result evaluate_at_start(const scene::Scene& sc) {
  const magnetics::Model m = scene::build_magnetics_model(sc);
  magnetics::State st;
  st.resize(m);
  scene::set_poses_at(sc, 0.0, st);
  magnetics::Result r;
  magnetics::evaluate(m, scene::magnetics_settings(sc), st, r);
  return r;
}

}  // namespace magbake::testing
