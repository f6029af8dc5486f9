// The simulator's state and the cache's frames, converted both ways: the one place where
// sim::SimState meets io::CacheWriter / io::CacheReader (src/io knows nothing of src/sim).
#pragma once

#include <vector>

#include "io/cache.h"
#include "scene/scene.h"
#include "sim/sim_state.h"

namespace magbake::cli {

/// The frame the cache stores for `s` at `frame` (time in s since the first frame): poses at the
/// body origin (sim::body_origin, the rounding Simulator::restart applies too), sleep state.
io::CacheFrame cache_frame(int frame, double time, const sim::SimState& s, const scene::Scene& scene);

/// The observables the cache stores for a frame's diagnostics.
io::FrameObservables cache_observables(const sim::FrameDiagnostics& d);

/// The stuck joints of `s` as cache rows (a, b, then the members in declaration order,
/// matrices row-major; sim::StuckJoint::kValues doubles).
std::vector<io::StuckRow> cache_stuck_rows(const sim::SimState& s);

/// Appends the frame of `s` (cache_frame, cache_observables, cache_stuck_rows) to `writer`.
inline void append_frame(io::CacheWriter& writer, int frame, double time, const sim::SimState& s,
                         const sim::FrameDiagnostics& d, const scene::Scene& scene) {
  io::FrameObservables o = cache_observables(d);
  o.applied_field = scene.applied_field(s.time);
  writer.append(cache_frame(frame, time, s, scene), o, cache_stuck_rows(s));
}

/// The simulation state a bake resumes from: frame `index` of `cache` (poses, velocities, the
/// stored forces, induced moments and magnetic energy, sleep state, stuck joints), given the
/// scene's bodies. Throws std::runtime_error for a frame that does not fit the scene or holds
/// an invalid sleep state.
sim::SimState resume_state(const io::CacheReader& cache, int index, const scene::Scene& scene);

}  // namespace magbake::cli
