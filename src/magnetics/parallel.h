// The one parallel primitive of the library: a parallel loop over fixed blocks.
// Each index writes only its own outputs, and every reduction happens afterwards in index order,
// so results are bit-identical whatever the number of threads (STYLE.md, Determinism).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

namespace magbake::magnetics {

/// Calls fn(i) for every i in [0, n), in parallel blocks of `grain` indices.
template <class Fn>
void parallel_for_each(int n, int grain, Fn&& fn) {
  if (n <= 0) return;
  if (n <= grain) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  tbb::parallel_for(
      tbb::blocked_range<int>(0, n, grain),
      [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i != r.end(); ++i) fn(i);
      },
      tbb::simple_partitioner());
}

}  // namespace magbake::magnetics
