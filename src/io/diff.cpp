#include "diff.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace magbake::io {

DiffReport diff_caches(const CacheReader& a, const CacheReader& b, const DiffOptions& o) {
  DiffReport r;
  if (a.body_names() != b.body_names()) {
    r.same = false;
    r.notes.push_back("the caches hold different bodies");
    return r;
  }
  if (a.scene_hash() != b.scene_hash()) r.notes.push_back("baked from different scene files (hashes differ)");
  const int frames = std::min(a.frame_count(), b.frame_count());
  if (a.frame_count() != b.frame_count()) {
    r.same = false;
    r.notes.push_back("frame counts differ: " + std::to_string(a.frame_count()) + " vs " + std::to_string(b.frame_count()) +
                      " (comparing the first " + std::to_string(frames) + ")");
  }
  if (a.first_frame() != b.first_frame()) {
    r.same = false;
    r.notes.push_back("first frames differ");
  }
  r.frames_compared = frames;
  if (frames == 0) return r;
  const auto& names = a.body_names();
  const std::size_t n = names.size();

  // Compares a frame-major dataset [F][groups][comp] group by group.
  auto compare = [&](const std::string& path, const std::string& quantity, std::size_t groups, std::size_t comp,
                     bool orientation, bool per_body) {
    const bool in_a = h5::exists(a.file(), path), in_b = h5::exists(b.file(), path);
    if (!in_a && !in_b) return;
    if (in_a != in_b) {
      r.same = false;
      r.notes.push_back(path + " is in only one cache");
      return;
    }
    const std::vector<double> va = h5::read_rows(a.file(), path, 0, frames);
    const std::vector<double> vb = h5::read_rows(b.file(), path, 0, frames);
    if (va.size() != vb.size() || va.size() != frames * groups * comp) {
      r.same = false;
      r.notes.push_back(path + " has different shapes");
      return;
    }
    std::map<std::size_t, Deviation> dev;  // by group
    bool nonfinite_noted = false;
    for (int f = 0; f < frames; ++f) {
      for (std::size_t g = 0; g < groups; ++g) {
        const double* x = va.data() + (f * groups + g) * comp;
        const double* y = vb.data() + (f * groups + g) * comp;
        double err = 0;
        bool bad = false;
        bool finite = true;
        for (std::size_t c = 0; c < comp; ++c) finite = finite && std::isfinite(x[c]) && std::isfinite(y[c]);
        if (!finite) {
          // NaN or Inf is never "the same", not even bit for bit: such a cache is broken.
          bad = true;
          err = std::numeric_limits<double>::infinity();
          if (!nonfinite_noted) {
            r.notes.push_back(path + " holds non-finite values (NaN or Inf) at frame " + std::to_string(a.first_frame() + f));
            nonfinite_noted = true;
          }
        } else if (o.exact) {
          bad = std::memcmp(x, y, comp * sizeof(double)) != 0;
          for (std::size_t c = 0; c < comp; ++c) err = std::max(err, std::abs(x[c] - y[c]));
        } else if (orientation) {
          // Rotation angle between the quaternions: 2 acos |<qa, qb>|.
          double d = 0;
          for (std::size_t c = 0; c < 4; ++c) d += x[c] * y[c];
          err = 2 * std::acos(std::min(1.0, std::abs(d)));
          bad = !(err <= o.angle_tol);
        } else {
          for (std::size_t c = 0; c < comp; ++c) {
            const double e = std::abs(x[c] - y[c]);
            err = std::max(err, e);
            if (!(e <= o.atol + o.rtol * std::abs(y[c]))) bad = true;
          }
        }
        if (!bad) continue;
        auto [it, fresh] = dev.try_emplace(g);
        Deviation& d = it->second;
        if (fresh) {
          d.quantity = quantity;
          d.body = per_body ? names[g] : (groups > 1 ? "cell " + std::to_string(g) : "");
          d.first_frame = a.first_frame() + f;
        }
        if (err >= d.largest) d.largest = err, d.largest_frame = a.first_frame() + f;
      }
    }
    for (auto& [g, d] : dev) {
      r.same = false;
      r.deviations.push_back(d);
    }
  };

  compare("particles/bodies/position/value", "position", n, 3, false, true);
  compare("particles/bodies/orientation/value", "orientation", n, 4, true, true);
  compare("particles/bodies/velocity/value", "velocity", n, 3, false, true);
  compare("particles/bodies/angular_velocity/value", "angular_velocity", n, 3, false, true);
  compare("particles/bodies/magnetic_force/value", "magnetic_force", n, 3, false, true);
  compare("particles/bodies/magnetic_torque/value", "magnetic_torque", n, 3, false, true);
  if (h5::exists(a.file(), "magnetics/induced_moment/value")) {
    h5::Handle d(H5Dopen2(a.file(), "magnetics/induced_moment/value", H5P_DEFAULT));
    const std::size_t cells = h5::shape(d.id()).at(1);
    compare("magnetics/induced_moment/value", "induced_moment", cells, 3, false, false);
  }
  // Per-frame observables; wall times are never compared, work counters only with --exact.
  for (const char* q : {"kinetic_energy", "gravity_energy", "magnetic_energy"}) {
    compare(std::string("observables/") + q + "/value", q, 1, 1, false, false);
  }
  if (o.exact) {
    for (const char* q : {"cells_visited", "induction_iterations", "substeps"}) {
      compare(std::string("observables/") + q + "/value", q, 1, 1, false, false);
    }
  }
  for (const char* q : {"momentum", "angular_momentum"}) {
    compare(std::string("observables/") + q + "/value", q, 1, 3, false, false);
  }
  compare("frames/time", "time", 1, 1, false, false);
  return r;
}

}  // namespace magbake::io
