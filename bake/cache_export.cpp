// Helpers shared by the cache readers; see cache_export.h.
#include "cache_export.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>

#include "cli.h"
#include "scene/frame_pattern.h"
#include "scene/load.h"
#include "scene/output_path.h"

namespace magbake::cli {
namespace fs = std::filesystem;

std::string expand_pattern(const std::string& pattern, int frame) { return scene::expand_frame_pattern(pattern, frame); }

int open_cache_range(const std::string& path, const std::optional<std::pair<int, int>>& frames,
                     std::optional<io::CacheReader>& cache, int& first, int& last) {
  try {
    cache.emplace(path);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kUsage;
  }
  if (cache->frame_count() == 0) {
    spdlog::error("{} holds no complete frame", path);
    return kUsage;
  }
  const int lo = cache->frame(0).frame, hi = cache->frame(cache->frame_count() - 1).frame;
  first = lo, last = hi;
  if (frames) {
    first = frames->first, last = frames->second;
    if (first > last || first < lo || last > hi) {
      spdlog::error("--frames {}-{} is outside the cache's frames {}-{}", first, last, lo, hi);
      return kUsage;
    }
  }
  return kOk;
}

int stored_outputs(const io::CacheReader& cache, bool have_pattern, std::optional<scene::FieldOutput>& field,
                   std::optional<scene::PreviewOutput>& preview) {
  const std::string problems = scene::outputs_of_text(cache.scene_text(), field, preview);
  if (problems.empty()) return kOk;
  if (have_pattern) {
    spdlog::warn("{}: the outputs stored with its scene do not validate and are ignored:\n{}", cache.path(), problems);
    return kOk;
  }
  spdlog::error("{}: the outputs stored with its scene do not validate (give -o):\n{}", cache.path(), problems);
  return kUsage;
}

int check_scene_output_path(const std::string& path, bool allow_absolute, const char* key) {
  if (const auto e = scene::output_path_error(path, allow_absolute)) {
    spdlog::error("{}: {}", key, *e);
    return kUsage;
  }
  return kOk;
}

int FrameSelection::count() const {
  int n = 0;
  for (int f = first; f <= last; ++f) n += wanted(f);
  return std::max(n, 1);
}

int FrameSelection::last_wanted() const {
  for (int f = last; f > first; --f) {
    if (wanted(f)) return f;
  }
  return first;
}

int prepare_output_folder(const std::string& pattern, int frame, const char* what) {
  if (const auto error = scene::frame_pattern_error(pattern)) {
    spdlog::error("output pattern '{}' for {}: {}", pattern, what, *error);
    return kUsage;
  }
  const fs::path out_dir = fs::path(expand_pattern(pattern, frame)).parent_path();
  const fs::path dir = out_dir.empty() ? fs::path(".") : out_dir;
  std::error_code ec;
  if (!out_dir.empty()) fs::create_directories(out_dir, ec);
  const fs::path probe = dir / ".magbake_write_test";
  std::ofstream test(probe);
  if (ec || !test) {
    spdlog::error("cannot write {} to '{}': the folder is not writable", what, dir.string());
    return kUsage;
  }
  test.close();
  fs::remove(probe, ec);
  return kOk;
}

}  // namespace magbake::cli
