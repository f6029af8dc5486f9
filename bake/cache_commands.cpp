// magbake diff and magbake info CACHE.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

#include "cli.h"
#include "io/cache.h"
#include "io/diff.h"

namespace magbake::cli {

int cmd_diff(const std::string& a_path, const std::string& b_path, const io::DiffOptions& o, const Global&) {
  try {
    const io::CacheReader a(a_path), b(b_path);
    const io::DiffReport r = io::diff_caches(a, b, o);
    for (const std::string& n : r.notes) std::printf("note: %s\n", n.c_str());
    if (r.same) {
      std::printf("same: %d frames, %zu bodies (%s)\n", r.frames_compared, a.body_names().size(),
                  o.exact ? "bit for bit" : "within tolerances");
      return kOk;
    }
    if (r.deviations.empty()) {
      std::printf("the %d frames both hold are the same (%s)\n", r.frames_compared, o.exact ? "bit for bit" : "within tolerances");
    } else {
      std::printf("%-20s %-18s %12s %14s %12s\n", "body", "quantity", "first frame", "largest diff", "at frame");
    }
    for (const io::Deviation& d : r.deviations) {
      std::printf("%-20s %-18s %12d %14.6g %12d\n", d.body.empty() ? "-" : d.body.c_str(), d.quantity.c_str(),
                  d.first_frame, d.largest, d.largest_frame);
    }
    std::printf("differ (%s)\n", o.exact ? "--exact" : "atol/rtol/angle-tol");
    return kFailure;
  } catch (const std::exception& e) {
    std::cerr << "magbake diff: " << e.what() << "\n";
    return kUsage;
  }
}

int cmd_info_cache(const std::string& path, bool all_bodies) {
  try {
    const io::CacheReader c(path);
    std::printf("cache    %s\n", path.c_str());
    std::printf("scene    %s (sha256 %s)\n", c.attribute("scene_name").c_str(), c.scene_hash().substr(0, 12).c_str());
    std::printf("versions magbake %s, HDF5 %s\n", c.attribute("magbake_version").c_str(),
                c.attribute("hdf5_version").c_str());
    std::printf("status   %s, %d frames", io::status_name(c.status()), c.frame_count());
    if (c.frame_count() > 0) {
      const io::CacheFrame a = c.frame(0), b = c.frame(c.frame_count() - 1);
      std::printf(" (%d-%d, t = %g-%g s, %g fps)\n", a.frame, b.frame, a.time, b.time, c.fps());
      std::printf("bodies   %zu\n  %-18s %32s %32s\n", c.body_names().size(), "name", "first position (m)",
                  "last position (m)");
      const std::size_t n = c.body_names().size();
      const std::size_t shown = all_bodies || n <= kSummaryBodies ? n : kSummaryBodies - 4;
      for (std::size_t i = 0; i < shown; ++i) {
        std::printf("  %-18s %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g\n", c.body_names()[i].c_str(), a.position[i][0],
                    a.position[i][1], a.position[i][2], b.position[i][0], b.position[i][1], b.position[i][2]);
      }
      if (shown < n) std::printf("  ... and %zu more (--verbose lists every body)\n", n - shown);
      const auto mag = c.observable("magnetics_seconds");
      const auto rig = c.observable("rigid_seconds");
      double tm = 0, tr = 0;
      for (double x : mag) tm += x;
      for (double x : rig) tr += x;
      std::printf("time     magnetics %.3g s, rigid bodies %.3g s\n", tm, tr);
    } else {
      std::printf("\n");
    }
    return kOk;
  } catch (const std::exception& e) {
    std::cerr << "magbake info: " << e.what() << "\n";
    return kUsage;
  }
}

}  // namespace magbake::cli
