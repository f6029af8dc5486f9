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
  // Frames are lined up by frame number: a bake of frames 10-20 is compared with frames 10-20 of
  // a full bake, and frames that only one cache holds are reported.
  auto steps = [](const CacheReader& c) {
    std::vector<int> out;
    if (c.frame_count() == 0) return out;
    for (double v : h5::read_rows(c.file(), "frames/step", 0, c.frame_count())) out.push_back(static_cast<int>(v));
    return out;
  };
  const std::vector<int> sa = steps(a), sb = steps(b);
  std::vector<std::size_t> ia, ib;  // matched rows
  std::vector<int> only_a, only_b;
  for (std::size_t i = 0, j = 0; i < sa.size() || j < sb.size();) {
    if (j == sb.size() || (i < sa.size() && sa[i] < sb[j])) {
      only_a.push_back(sa[i++]);
    } else if (i == sa.size() || sb[j] < sa[i]) {
      only_b.push_back(sb[j++]);
    } else {
      ia.push_back(i++), ib.push_back(j++);
    }
  }
  // "frames 1-9, 21" from sorted frame numbers.
  auto ranges = [](const std::vector<int>& f) {
    std::string out;
    for (std::size_t k = 0; k < f.size();) {
      std::size_t e = k;
      while (e + 1 < f.size() && f[e + 1] == f[e] + 1) ++e;
      if (!out.empty()) out.append(", ");
      out.append(std::to_string(f[k]));
      if (e > k) out.append("-").append(std::to_string(f[e]));
      k = e + 1;
    }
    return out;
  };
  if (!only_a.empty()) {
    r.same = false;
    r.notes.push_back("frames only in " + a.path() + ": " + ranges(only_a));
  }
  if (!only_b.empty()) {
    r.same = false;
    r.notes.push_back("frames only in " + b.path() + ": " + ranges(only_b));
  }
  const std::size_t frames = ia.size();
  if (frames == 0 && (a.frame_count() > 0 || b.frame_count() > 0)) {
    r.same = false;
    r.notes.push_back("the caches have no frame in common");
  }
  r.frames_compared = static_cast<int>(frames);
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
    const std::vector<double> va = h5::read_rows(a.file(), path, 0, a.frame_count());
    const std::vector<double> vb = h5::read_rows(b.file(), path, 0, b.frame_count());
    if (va.size() != a.frame_count() * groups * comp || vb.size() != b.frame_count() * groups * comp) {
      r.same = false;
      r.notes.push_back(path + " has different shapes");
      return;
    }
    std::map<std::size_t, Deviation> dev;  // by group
    bool nonfinite_noted = false;
    for (std::size_t f = 0; f < frames; ++f) {
      for (std::size_t g = 0; g < groups; ++g) {
        const double* x = va.data() + (ia[f] * groups + g) * comp;
        const double* y = vb.data() + (ib[f] * groups + g) * comp;
        double err = 0;
        bool bad = false;
        bool finite = true;
        for (std::size_t c = 0; c < comp; ++c) finite = finite && std::isfinite(x[c]) && std::isfinite(y[c]);
        if (!finite) {
          // NaN or Inf is never "the same", not even bit for bit: such a cache is broken.
          bad = true;
          err = std::numeric_limits<double>::infinity();
          if (!nonfinite_noted) {
            r.notes.push_back(path + " holds non-finite values (NaN or Inf) at frame " + std::to_string(sa[ia[f]]));
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
          d.first_frame = sa[ia[f]];
        }
        if (err >= d.largest) d.largest = err, d.largest_frame = sa[ia[f]];
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
