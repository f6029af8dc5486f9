#include <cmath>
#include <limits>

#include "field_export.h"

namespace magbake::cli {

void evaluate_field_grid(const magnetics::Model& m, const magnetics::State& s, const magnetics::FieldOptions& opt,
                         double threshold, io::FieldSamples& out) {
  using magnetics::Vec3;
  const std::size_t n = std::size_t(out.dims[0]) * out.dims[1] * out.dims[2];
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.bx.assign(n, nan), out.by.assign(n, nan), out.bz.assign(n, nan);
  // Per body: bounding sphere of its cells and the sum of |m| (an upper bound on its field).
  struct Bound {
    Vec3 c;
    double r, sum;
  };
  std::vector<Bound> bounds;
  for (int b = 0; b < m.body_count; ++b) {
    const int root = m.body_root[b];
    if (root < 0) continue;
    double sum = 0;
    for (int c = m.body_cell_begin[b]; c < m.body_cell_begin[b + 1]; ++c) sum += s.total.cell[c].norm();
    bounds.push_back({s.body_pose[b].position + s.node_offset[root], m.node_radius[root], sum});
  }
  auto keep = [&](const Vec3& lo, const Vec3& hi) {
    double bound = 0;
    for (const Bound& bd : bounds) {
      const Vec3 nearest = bd.c.cwiseMax(lo).cwiseMin(hi);
      const double d = (bd.c - nearest).norm() - bd.r;
      if (d <= 0) return true;
      bound += 2.0 * magnetics::kMu0Over4Pi * bd.sum / (d * d * d);
    }
    return bound >= threshold;
  };
  // Slabs of 16 voxels along z bound the memory (targets and double results of one slab); each
  // slab's blocks of 4³ voxels walk the source trees together.
  constexpr int kBlock = 4, kSlab = 16;
  std::vector<Vec3> B;
  for (int z0 = 0; z0 < out.dims[2]; z0 += kSlab) {
    const Eigen::Vector3i dims(out.dims[0], out.dims[1], std::min(kSlab, out.dims[2] - z0));
    const Vec3 origin = out.origin + Vec3(0, 0, z0 * out.voxel);
    const magnetics::Targets t = magnetics::Targets::from_grid(origin, out.voxel, dims, kBlock, keep);
    B.resize(t.position.size());
    magnetics::field_at_targets(m, s, s.total, t, opt, B);
    const std::size_t offset = std::size_t(z0) * out.dims[0] * out.dims[1];
    for (std::size_t q = 0; q < B.size(); ++q) {
      const Vec3& v = B[q];
      const std::size_t idx = offset + t.original[q];
      out.bx[idx] = float(v[0]), out.by[idx] = float(v[1]), out.bz[idx] = float(v[2]);
    }
  }
}

}  // namespace magbake::cli
