// What the cache readers (`magbake field`, `magbake preview`) share: per-frame file patterns,
// the requested frame range, and the output folder check.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "io/cache.h"
#include "scene/scene.h"

namespace magbake::cli {

/// "name.####.ext" (a run of # = the frame zero-padded to that width) or "name.%04d.ext" with a
/// frame number. The pattern must have passed prepare_output_folder (scene/frame_pattern.h: never
/// a printf format; one frame field, exactly).
std::string expand_pattern(const std::string& pattern, int frame);

/// The frames an export writes: those in [first, last] that are a whole number of `every` from
/// the shot's first frame (`shot_first`, the scene's), whatever the range, so split and whole
/// runs write the same frames.
struct FrameSelection {
  int first = 0, last = 0, every = 1, shot_first = 0;
  bool wanted(int frame) const { return frame >= first && frame <= last && (frame - shot_first) % every == 0; }
  int count() const;  ///< frames wanted, at least 1 (a progress total)
  int last_wanted() const;  ///< the last wanted frame (first when none)
};

/// Opens a cache and resolves `frames` (inclusive; unset = every frame) against the frames it
/// holds. Returns kOk, or kUsage after logging why: unreadable or foreign file, no complete
/// frame, or a range that is reversed or outside the cache.
int open_cache_range(const std::string& path, const std::optional<std::pair<int, int>>& frames,
                     std::optional<io::CacheReader>& cache, int& first, int& last);

/// The outputs.field / outputs.preview stored in a cache's scene text. When they do not validate
/// (a pattern or path from a hostile or older scene), they are dropped: with `have_pattern`
/// (the user gave -o) after a warning, else the call logs why and returns kUsage.
int stored_outputs(const io::CacheReader& cache, bool have_pattern, std::optional<scene::FieldOutput>& field,
                   std::optional<scene::PreviewOutput>& preview);

/// kOk, or kUsage after logging why, for an output path or pattern that came from a scene
/// (scene/output_path.h): absolute ones need `allow_absolute` (--allow-absolute-outputs).
int check_scene_output_path(const std::string& path, bool allow_absolute, const char* key);

/// Checks the pattern (scene/frame_pattern.h), creates the folder of its file for `frame` and
/// checks that it is writable, before any work is done. Returns kOk, or kUsage after logging
/// why (`what` names the outputs).
int prepare_output_folder(const std::string& pattern, int frame, const char* what);

}  // namespace magbake::cli
