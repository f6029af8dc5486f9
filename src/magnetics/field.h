// Magnetic flux density B at arbitrary points from all cells, by a tree code over the body
// hierarchies (Barnes–Hut with grouped targets and the same opening angle theta as forces).
#pragma once

#include <span>
#include <vector>

#include "state.h"

namespace magbake::magnetics {

/// Options of one field evaluation.
struct FieldOptions {
  double theta = 0.5;       ///< opening angle (0 = every cell)
  double near_field = 0.0;  ///< exact cuboid field within this many cell sizes of full cells (0 = off)
  /// Targets inside a cell's cuboid get that cuboid's field with the cell's moment smeared over
  /// it (mu0 (H + M) inside): bounded inside magnets, where a point dipole is singular.
  bool smear_inside = false;
  /// Far and leaf dipoles in single precision (AVX2, 8 targets per instruction); near cells,
  /// sums and everything else in double. (Either way a target that is a cell skips itself.)
  bool single_precision = false;
};

/// B (tesla, world) of `sources` at every target, in target order (B has targets.position.size()
/// entries). Cell world positions come from the state (body poses set, offsets updated).
/// Adds nothing for the applied field. Returns the number of source–target evaluations.
std::int64_t field_at_targets(const Model& model, const State& s, const Sources& sources, const Targets& targets,
                              const FieldOptions& options, std::span<Vec3> B);

}  // namespace magbake::magnetics
