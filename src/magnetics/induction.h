// Induced magnetization of linear and superconducting cells (physics-notes §4).
#pragma once

#include "field.h"

namespace magbake::magnetics {

/// Computes the induced moment of every induced cell for the current poses and writes it to
/// s.induced_moment (world, A·m², in Model::induced_cells order). Needs s.permanent aggregated.
/// Paper mode: m = V chi_eff (B_perm + B_applied)/mu0 at each cell. Coupled mode: the same with
/// the field of all other induced cells added, solved matrix-free by restarted GMRES (right-
/// preconditioned by the model's factored intra-body blocks), warm-started from the moments
/// already in s.induced_moment.
InductionReport solve_induction(const Model& model, const Settings& settings, State& s, EvalStats& stats);

}  // namespace magbake::magnetics
