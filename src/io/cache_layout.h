// The structural check of a cache at open: every dataset and attribute the readers use exists
// with the shape the format gives it (docs/cache-format.md), every index read from the file
// points inside the array it indexes, and every constant is finite. After it, no reader of a
// CacheReader can index out of bounds, whatever the file holds. Internal to src/io.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace magbake::io {

/// Doubles per row of /contacts/stuck (sim::StuckJoint::kValues).
inline constexpr std::size_t kStuckValues = 37;

/// What the layout check learned (counts the readers need).
struct CacheLayout {
  std::size_t bodies = 0;     ///< rows of /bodies/name
  std::size_t cells = 0;      ///< magnetic cells
  std::size_t parts = 0;      ///< magnetic parts
  std::size_t induced = 0;    ///< induced cells (rows of /magnetics/induced_cells)
  bool sleep = false;         ///< the optional sleep series are present (with the right shapes)
  /// Optional stuck joints (/contacts): frame k's records are rows [stuck_begin[k],
  /// stuck_begin[k + 1]) of /contacts/stuck (frames + 1 entries; empty when absent).
  std::vector<std::int64_t> stuck_begin;
  int frames = 0;             ///< complete frames readable in every per-frame series
};

/// Checks the file's layout; throws std::runtime_error naming the first problem (dataset path,
/// what was expected, what is there). `frames_done` is the writer's completed-frame count.
CacheLayout check_cache_layout(hid_t file, std::int64_t frames_done);

}  // namespace magbake::io
