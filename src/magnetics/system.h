// The library's entry points: one evaluation of all magnetic forces for given body poses, and
// the field at arbitrary points. Include this header to use the library.
#pragma once

#include <span>
#include <vector>

#include "field.h"
#include "model.h"
#include "settings.h"
#include "state.h"

namespace magbake::magnetics {

/// Computes induced moments (per settings.induction), then the magnetic force, torque (about
/// each body-frame origin, world frame) and total moment of every body for the poses in
/// s.body_pose. A uniform applied field adds torque m x B (no force). Work that is not needed
/// is skipped: no cells -> nothing; no induced cells -> no solve; non-magnetized pairs -> skipped.
void evaluate(const Model& model, const Settings& settings, State& s, Result& result);

/// Places the model at s.body_pose with given induced moments (Model::induced_cells order,
/// world) instead of solving for them: what field export from a cache needs. After it,
/// field_at_points() and field_at_targets() with s.total work as after evaluate().
void place(const Model& model, State& s, const std::vector<Vec3>& induced_moments);

/// Flux density B (tesla, world) at world points (m) from every cell's total moment after
/// evaluate(), plus the applied field. Cells within settings.near_field cell sizes of a point
/// contribute their exact cuboid field (so points inside magnets get mu0 (H + M)).
std::vector<Vec3> field_at_points(const Model& model, const Settings& settings, const State& s,
                                  std::span<const Vec3> points, EvalStats* stats = nullptr);

}  // namespace magbake::magnetics
