// Dense kernels over pairs of hierarchy leaves: every cell of one leaf against every cell of
// another. These are the hot loops of the library.
#pragma once

#include "state.h"

namespace magbake::magnetics {

/// Sums over a block of cell pairs, for the target leaf's body.
struct BlockSum {
  Vec3 force = Vec3::Zero();   ///< N, world, on the target cells
  Vec3 torque = Vec3::Zero();  ///< N·m, world, on the target cells about their body origin
  double energy = 0.0;         ///< J
};

/// Interaction of target cells [tb, te) (one body) with source cells [sb, se) (another body).
/// Cell offsets in `s` are relative to each body's origin; delta = origin_target - origin_source.
/// clamp: apply the close-range distance clamp (needed only when the leaves may overlap).
void block_interaction(const State& s, int tb, int te, int sb, int se, const Vec3& delta, bool clamp,
                       KernelPrecision precision, BlockSum& out);

/// Instruction set the single-precision block kernel was compiled for (for reports).
const char* block_kernel_isa();

}  // namespace magbake::magnetics
