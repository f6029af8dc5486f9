// Forces and torques between bodies: the adaptive, symmetric traversal of hierarchy pairs.
#pragma once

#include "state.h"

namespace magbake::magnetics {

/// Adds the magnetic forces, torques (about body origins) and pair energies of every body pair
/// to `result` (sized by the caller). Uses s.total; every evaluated interaction is a dipole–dipole
/// term (or an exact cuboid pair in the near field) applied with opposite signs to both bodies,
/// so total force and angular momentum vanish to round-off at any theta.
void accumulate_forces(const Model& model, const Settings& settings, const State& s, Result& result);

}  // namespace magbake::magnetics
