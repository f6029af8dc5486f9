// What a bake of a scene will cost, from a short trial bake of its first steps.
#pragma once

#include "magnetics/model.h"
#include "scene/scene.h"

namespace magbake::sim {

/// Expected work and wall time of baking a whole scene, extrapolated from a trial that runs the
/// real step loop (Simulator: substep splitting, induction solves, contact) over the first
/// nominal steps of the shot. Counts are for the whole shot; seconds are this machine's.
struct CostEstimate {
  long long nominal_steps = 0;        ///< steps of length dt the shot has (frames x ceil(1/(fps dt)))
  int trial_steps = 0;                ///< nominal steps the trial ran
  double trial_seconds = 0;           ///< wall time of the trial, s
  double substeps = 0;                ///< expected Bullet steps (nominal steps and their pieces)
  double evaluations = 0;             ///< expected magnetics evaluations
  double induction_iterations = 0;    ///< expected GMRES iterations, summed
  double cells_visited = 0;           ///< expected cell pairs + node pairs, summed
  double magnetics_seconds = 0;       ///< expected wall time in the magnetics library, s
  double rigid_seconds = 0;           ///< expected wall time in Bullet, s
  /// Expected wall time of the simulation (magnetics + rigid bodies), s.
  double seconds() const { return magnetics_seconds + rigid_seconds; }
};

/// How much longer than its budget a trial may run while its cost per step is still changing.
inline constexpr double kTrialExtension = 4.0;

/// Runs the first nominal steps of `scene` and adds, for the rest of the shot, what the trial's
/// second half cost per step. The trial stops after `max_steps` steps or the step that takes it
/// past `budget_seconds` of wall time once its cost per step has settled (the substeps and cell
/// pairs of its last quarter within 25% of the quarter before), and at the latest at
/// kTrialExtension x either: a shot that starts with magnets snapping and then rests
/// is not extrapolated from the snap. `model` must be built from `scene`. The trial sees the
/// shot's beginning only: a scene whose cost changes later (magnets that snap after the trial)
/// is estimated from its start.
CostEstimate estimate_cost(const scene::Scene& scene, const magnetics::Model& model, double budget_seconds,
                           int max_steps);

}  // namespace magbake::sim
