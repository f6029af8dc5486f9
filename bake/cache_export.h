// What the cache readers (`magbake field`, `magbake preview`) share: per-frame file patterns,
// the requested frame range, and the output folder check.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "io/cache.h"

namespace magbake::cli {

/// "name.####.ext" (a run of # = the frame zero-padded to that width) or "name.%04d.ext"
/// (printf) with a frame number; a pattern without either gets ".<frame>" before its extension.
std::string expand_pattern(const std::string& pattern, int frame);

/// Opens a cache and resolves `frames` (inclusive; unset = every frame) against the frames it
/// holds. Returns kOk, or kUsage after logging why: unreadable or foreign file, no complete
/// frame, or a range that is reversed or outside the cache.
int open_cache_range(const std::string& path, const std::optional<std::pair<int, int>>& frames,
                     std::optional<io::CacheReader>& cache, int& first, int& last);

/// Creates the folder of the pattern's file for `frame` and checks that it is writable, before
/// any work is done. Returns kOk, or kUsage after logging why (`what` names the outputs).
int prepare_output_folder(const std::string& pattern, int frame, const char* what);

}  // namespace magbake::cli
