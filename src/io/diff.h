// Comparing two caches: what `magbake diff` reports.
#pragma once

#include <string>
#include <vector>

#include "cache.h"

namespace magbake::io {

/// Tolerances: a value matches when |a - b| <= atol + rtol |b|; orientations when the rotation
/// between them is at most angle_tol (q and -q are the same rotation). exact: every compared
/// value bit for bit.
struct DiffOptions {
  double atol = 1e-9;
  double rtol = 1e-6;
  double angle_tol = 1e-6;
  bool exact = false;
};

/// Where one quantity differs the most, and where it first differs.
struct Deviation {
  std::string quantity;  ///< e.g. "position"
  std::string body;      ///< body name, or "" for per-frame observables
  int first_frame = 0;   ///< scene frame number of the first mismatch
  double largest = 0;    ///< largest |a - b| (radians for orientation)
  int largest_frame = 0;
};

struct DiffReport {
  bool same = true;
  std::vector<std::string> notes;      ///< structural differences (frame counts, names, scenes)
  std::vector<Deviation> deviations;   ///< one per (quantity, body) that differs
  int frames_compared = 0;             ///< frames both caches hold (lined up by frame number)
};

/// Compares everything that matters (body series, induced moments, observables except wall
/// times) over the frames both caches hold, lined up by frame number; frames that only one
/// holds make them differ and are named in a note ("frames only in PATH: 1-9, 21-25"). Throws std::runtime_error if a file cannot be read.
DiffReport diff_caches(const CacheReader& a, const CacheReader& b, const DiffOptions& options);

}  // namespace magbake::io
