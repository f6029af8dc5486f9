// libFuzzer target: the cache reader on arbitrary files. Every input must open as a cache or be
// refused with std::runtime_error; after a successful open, every reader (frames, geometry,
// model, observables, diff) must run without a crash or sanitizer report. Run: fuzz/README.md.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "io/cache.h"
#include "io/diff.h"

namespace {
// One scratch file per fuzzing process, in memory when /dev/shm exists.
const std::string& scratch() {
  static const std::string path = (access("/dev/shm", W_OK) == 0 ? std::string("/dev/shm") : std::string("/tmp")) +
                                  "/magbake_cache_fuzz_" + std::to_string(getpid()) + ".h5";
  return path;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (4u << 20)) return -1;
  {
    std::FILE* f = std::fopen(scratch().c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  try {
    const magbake::io::CacheReader c(scratch());
    for (int i = 0; i < c.frame_count() && i < 64; ++i) {
      try {
        (void)c.frame(i);
      } catch (const std::runtime_error&) {
      }
    }
    (void)c.geometry();
    (void)c.centers_of_mass();
    (void)c.observable("magnetics_seconds");
    std::vector<int> order;
    (void)c.model(&order);
    (void)magbake::io::diff_caches(c, c, magbake::io::DiffOptions{});
  } catch (const std::runtime_error&) {
    // refused: the expected outcome for almost every input
  }
  return 0;
}
