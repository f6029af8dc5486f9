// Helpers shared by the cache readers; see cache_export.h.
#include "cache_export.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"

namespace magbake::cli {
namespace fs = std::filesystem;

std::string expand_pattern(const std::string& pattern, int frame) {
  const auto h = pattern.find('#');
  if (h != std::string::npos) {
    std::size_t n = 0;
    while (h + n < pattern.size() && pattern[h + n] == '#') ++n;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%0*d", static_cast<int>(n), frame);
    return pattern.substr(0, h) + buf + pattern.substr(h + n);
  }
  if (pattern.find('%') != std::string::npos) {
    char buf[4096];
    std::snprintf(buf, sizeof buf, pattern.c_str(), frame);
    return buf;
  }
  const fs::path p(pattern);
  return (p.parent_path() / (p.stem().string() + "." + std::to_string(frame) + p.extension().string())).string();
}

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

int prepare_output_folder(const std::string& pattern, int frame, const char* what) {
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
