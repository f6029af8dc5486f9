// Build-time data of the induction solve: per-cell polarizabilities and the near-field
// corrections inside each body (both rigid, so computed once per model).
#pragma once

#include <vector>

#include "model.h"

namespace magbake::magnetics {

/// Dipole tensor T (T/(A·m²)): B = T m at offset r from a point dipole m.
Mat3 dipole_tensor(const Vec3& r);

/// Fills model.cell_polarizability, part_consistent and the intra-body near rows.
/// The self-field of each induced cell is chosen so that a uniformly magnetized part gets,
/// at every cell, exactly the field its true shape produces (solid->demag_tensor): with that,
/// an ellipsoid in a uniform field is solved exactly at any cell size and boundary cells stop
/// biasing the result (first-order consistency). Solids without demag_tensor fall back to the
/// cells' own cuboid demagnetizing factors.
void build_induction_model(Model& model, const std::vector<const Solid*>& part_solid, const BuildSettings& settings);

}  // namespace magbake::magnetics
