#include "field.h"

#include <algorithm>
#include <cassert>
#include <numeric>

#include "cuboid.h"
#include "dipole.h"
#include "parallel.h"
#include "simd_rsqrt.h"

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

namespace magbake::magnetics {

void Sources::aggregate(const Model& m) {
  node.assign(m.node_count(), Vec3::Zero());
  node_active.assign(m.node_count(), 0);
  // Children are created after their parents, so a reverse sweep sums bottom-up.
  for (int n = m.node_count() - 1; n >= 0; --n) {
    const int ch = m.node_child[n];
    if (ch < 0) {
      Vec3 sum = Vec3::Zero();
      bool any = false;
      for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
        sum += cell[c];
        any = any || cell[c].squaredNorm() > 0.0;
      }
      node[n] = sum;
      node_active[n] = any;
    } else {
      node[n] = Vec3::Zero();
      node_active[n] = 0;
      for (int k = ch; k < ch + m.node_nchild[n]; ++k) {
        node[n] += node[k];
        node_active[n] = node_active[n] || node_active[k];
      }
    }
  }
}

namespace {

void bisect(std::vector<int>& idx, std::span<const Vec3> p, int begin, int end, int group_size,
            std::vector<int>& bounds) {
  if (end - begin <= group_size) {
    bounds.push_back(end);
    return;
  }
  Box3 bb;
  for (int q = begin; q < end; ++q) bb.extend(p[idx[q]]);
  int axis;
  bb.sizes().maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(idx.begin() + begin, idx.begin() + mid, idx.begin() + end, [&](int a, int b) {
    return p[a][axis] < p[b][axis] || (p[a][axis] == p[b][axis] && a < b);
  });
  bisect(idx, p, begin, mid, group_size, bounds);
  bisect(idx, p, mid, end, group_size, bounds);
}

void compute_group_bounds(Targets& t) {
  const int ng = static_cast<int>(t.group_begin.size()) - 1;
  t.group_center.resize(ng);
  t.group_radius.resize(ng);
  for (int g = 0; g < ng; ++g) {
    Box3 bb;
    for (int q = t.group_begin[g]; q < t.group_begin[g + 1]; ++q) bb.extend(t.position[q]);
    t.group_center[g] = bb.center();
    double r = 0;
    for (int q = t.group_begin[g]; q < t.group_begin[g + 1]; ++q) {
      r = std::max(r, (t.position[q] - t.group_center[g]).norm());
    }
    t.group_radius[g] = r;
  }
}

}  // namespace

Targets Targets::from_points(std::span<const Vec3> points, int group_size) {
  Targets t;
  const int n = static_cast<int>(points.size());
  std::vector<int> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  t.group_begin.push_back(0);
  if (n > 0) bisect(idx, points, 0, n, std::max(1, group_size), t.group_begin);
  t.position.resize(n);
  t.cell.assign(n, -1);
  t.original = idx;
  for (int q = 0; q < n; ++q) t.position[q] = points[idx[q]];
  compute_group_bounds(t);
  return t;
}

Targets Targets::from_induced_cells(const Model& m, const State& s) {
  Targets t;
  t.group_begin.push_back(0);
  for (int n = 0; n < m.node_count(); ++n) {
    if (m.node_child[n] >= 0 || !m.node_induced[n]) continue;
    for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
      if (m.cell_chi[c] == 0.0) continue;
      t.cell.push_back(c);
    }
    t.group_begin.push_back(static_cast<int>(t.cell.size()));
  }
  // original[] maps a target to its rank among the model's induced cells.
  t.original.resize(t.cell.size());
  for (std::size_t q = 0; q < t.cell.size(); ++q) {
    t.original[q] = static_cast<int>(
        std::lower_bound(m.induced_cells.begin(), m.induced_cells.end(), t.cell[q]) - m.induced_cells.begin());
  }
  t.position.resize(t.cell.size());
  t.update_induced_positions(m, s);
  return t;
}

void Targets::update_induced_positions(const Model& m, const State& s) {
  for (std::size_t q = 0; q < cell.size(); ++q) {
    const int c = cell[q];
    position[q] = s.body_pose[m.cell_body[c]].position + s.cell_offset[c];
  }
  compute_group_bounds(*this);
}

namespace {

// Work stack of the body-tree walk, one per thread (no allocation once grown).
std::vector<int>& thread_local_stack() {
  thread_local std::vector<int> stack;
  return stack;
}

// A dipole source for one target group: position relative to the group centre (m), moment.
struct Source {
  Vec3 x, m;
};

#if defined(__AVX2__) && defined(__FMA__)
// B of every source at targets [tb, te) (positions relative to the group centre), added to B.
// Targets in 8 lanes, sources broadcast; float, accumulated per target, then added in double.
void dipoles_f32(const std::vector<Source>& src, const std::vector<Vec3>& rel, int n, Vec3* B) {
  constexpr int kLanes = 8;
  alignas(32) float tx[kLanes], ty[kLanes], tz[kLanes], ox[kLanes], oy[kLanes], oz[kLanes];
  std::vector<float> sx(src.size()), sy(src.size()), sz(src.size()), mx(src.size()), my(src.size()), mz(src.size());
  for (std::size_t i = 0; i < src.size(); ++i) {
    sx[i] = float(src[i].x[0]), sy[i] = float(src[i].x[1]), sz[i] = float(src[i].x[2]);
    mx[i] = float(src[i].m[0]), my[i] = float(src[i].m[1]), mz[i] = float(src[i].m[2]);
  }
  for (int q0 = 0; q0 < n; q0 += kLanes) {
    for (int l = 0; l < kLanes; ++l) {
      const bool in = q0 + l < n;
      tx[l] = in ? float(rel[q0 + l][0]) : 1e6f;
      ty[l] = in ? float(rel[q0 + l][1]) : 1e6f;
      tz[l] = in ? float(rel[q0 + l][2]) : 1e6f;
    }
    const __m256 X = _mm256_load_ps(tx), Y = _mm256_load_ps(ty), Z = _mm256_load_ps(tz);
    __m256 BX = _mm256_setzero_ps(), BY = BX, BZ = BX;
    for (std::size_t i = 0; i < src.size(); ++i) {
      const __m256 rx = _mm256_sub_ps(X, _mm256_set1_ps(sx[i]));
      const __m256 ry = _mm256_sub_ps(Y, _mm256_set1_ps(sy[i]));
      const __m256 rz = _mm256_sub_ps(Z, _mm256_set1_ps(sz[i]));
      const __m256 d2 = _mm256_fmadd_ps(rz, rz, _mm256_fmadd_ps(ry, ry, _mm256_mul_ps(rx, rx)));
      const __m256 z = two_over_sqrt(d2);  // 2/d
      const __m256 z2 = _mm256_mul_ps(z, z);
      const __m256 z5 = _mm256_mul_ps(_mm256_mul_ps(z2, z2), z);  // 32/d^5
      const __m256 bmx = _mm256_set1_ps(mx[i]), bmy = _mm256_set1_ps(my[i]), bmz = _mm256_set1_ps(mz[i]);
      const __m256 mr = _mm256_fmadd_ps(bmz, rz, _mm256_fmadd_ps(bmy, ry, _mm256_mul_ps(bmx, rx)));
      const __m256 a = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(3.0f), mr), z5);
      const __m256 c = _mm256_mul_ps(d2, z5);
      BX = _mm256_add_ps(BX, _mm256_fmsub_ps(a, rx, _mm256_mul_ps(c, bmx)));
      BY = _mm256_add_ps(BY, _mm256_fmsub_ps(a, ry, _mm256_mul_ps(c, bmy)));
      BZ = _mm256_add_ps(BZ, _mm256_fmsub_ps(a, rz, _mm256_mul_ps(c, bmz)));
    }
    _mm256_store_ps(ox, BX), _mm256_store_ps(oy, BY), _mm256_store_ps(oz, BZ);
    for (int l = 0; l < kLanes && q0 + l < n; ++l) {
      B[q0 + l] += (kMu0Over4Pi / 32.0) * Vec3(ox[l], oy[l], oz[l]);
    }
  }
}

// The same in double precision, 4 targets per vector: the induction operator's dipole sums
// (GMRES needs them exact to double rounding). Square root and division are correctly rounded,
// so the result does not depend on the CPU; it differs from the scalar dipole_field() only in
// the order of roundings.
void dipoles_f64(const std::vector<Source>& src, const std::vector<Vec3>& rel, int n, Vec3* B) {
  constexpr int kLanes = 4;
  alignas(32) double tx[kLanes], ty[kLanes], tz[kLanes], ox[kLanes], oy[kLanes], oz[kLanes];
  for (int q0 = 0; q0 < n; q0 += kLanes) {
    for (int l = 0; l < kLanes; ++l) {
      const bool in = q0 + l < n;
      tx[l] = in ? rel[q0 + l][0] : 1e6;
      ty[l] = in ? rel[q0 + l][1] : 1e6;
      tz[l] = in ? rel[q0 + l][2] : 1e6;
    }
    const __m256d X = _mm256_load_pd(tx), Y = _mm256_load_pd(ty), Z = _mm256_load_pd(tz);
    __m256d BX = _mm256_setzero_pd(), BY = BX, BZ = BX;
    for (const Source& sc : src) {
      const __m256d rx = _mm256_sub_pd(X, _mm256_set1_pd(sc.x[0]));
      const __m256d ry = _mm256_sub_pd(Y, _mm256_set1_pd(sc.x[1]));
      const __m256d rz = _mm256_sub_pd(Z, _mm256_set1_pd(sc.x[2]));
      const __m256d d2 = _mm256_fmadd_pd(rz, rz, _mm256_fmadd_pd(ry, ry, _mm256_mul_pd(rx, rx)));
      const __m256d inv = _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(d2));
      const __m256d inv2 = _mm256_mul_pd(inv, inv);
      const __m256d inv5 = _mm256_mul_pd(_mm256_mul_pd(inv2, inv2), inv);
      const __m256d bmx = _mm256_set1_pd(sc.m[0]), bmy = _mm256_set1_pd(sc.m[1]), bmz = _mm256_set1_pd(sc.m[2]);
      const __m256d mr = _mm256_fmadd_pd(bmz, rz, _mm256_fmadd_pd(bmy, ry, _mm256_mul_pd(bmx, rx)));
      const __m256d a = _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(3.0), mr), inv5);
      const __m256d c = _mm256_mul_pd(d2, inv5);
      BX = _mm256_add_pd(BX, _mm256_fmsub_pd(a, rx, _mm256_mul_pd(c, bmx)));
      BY = _mm256_add_pd(BY, _mm256_fmsub_pd(a, ry, _mm256_mul_pd(c, bmy)));
      BZ = _mm256_add_pd(BZ, _mm256_fmsub_pd(a, rz, _mm256_mul_pd(c, bmz)));
    }
    _mm256_store_pd(ox, BX), _mm256_store_pd(oy, BY), _mm256_store_pd(oz, BZ);
    for (int l = 0; l < kLanes && q0 + l < n; ++l) B[q0 + l] += kMu0Over4Pi * Vec3(ox[l], oy[l], oz[l]);
  }
}
#else
void dipoles_f64(const std::vector<Source>& src, const std::vector<Vec3>& rel, int n, Vec3* B) {
  for (int q = 0; q < n; ++q) {
    for (const Source& s : src) B[q] += dipole_field(rel[q] - s.x, s.m);
  }
}
void dipoles_f32(const std::vector<Source>& src, const std::vector<Vec3>& rel, int n, Vec3* B) {
  for (int q = 0; q < n; ++q) {
    Eigen::Vector3f acc = Eigen::Vector3f::Zero();
    for (const Source& s : src) {
      const Eigen::Vector3f r = (rel[q] - s.x).cast<float>();
      const Eigen::Vector3f m = s.m.cast<float>();
      const float d2 = r.squaredNorm(), inv = 1.0f / std::sqrt(d2), inv5 = inv * inv * inv * inv * inv;
      acc += inv5 * (3.0f * m.dot(r) * r - d2 * m);
    }
    B[q] += kMu0Over4Pi * acc.cast<double>();
  }
}
#endif

}  // namespace

std::int64_t field_at_targets(const Model& m, const State& s, const Sources& src, const Targets& t,
                              const FieldOptions& opt, std::span<Vec3> B) {
  const int ngroup = static_cast<int>(t.group_begin.size()) - 1;
  assert(B.size() == t.position.size());
  std::vector<std::int64_t> work(std::max(ngroup, 0), 0);

  const BodyTree& bt = s.body_tree;
  if (bt.empty()) {
    std::fill(B.begin(), B.end(), Vec3::Zero());
    return 0;
  }
  BodyTreeSources agg;
  agg.aggregate(bt, m, src);
  parallel_for_each(ngroup, 1, [&](int g) {
    const int tb = t.group_begin[g], te = t.group_begin[g + 1];
    for (int q = tb; q < te; ++q) B[q] = Vec3::Zero();
    const Vec3 gc = t.group_center[g];
    const double gr = t.group_radius[g];
    std::int64_t count = 0;
    thread_local std::vector<Source> far;   // dipoles evaluated for every target of the group
    thread_local std::vector<int> near;     // cells decided target by target
    thread_local std::vector<Vec3> rel;
    far.clear();
    near.clear();
    int stack[128];
    // The hierarchy over bodies first: a group of bodies far enough away is one dipole at its
    // centre; a body that is not opens into its own cell hierarchy.
    std::vector<int>& tree_stack = thread_local_stack();
    tree_stack.assign(1, 0);
    while (!tree_stack.empty()) {
      const int tn = tree_stack.back();
      tree_stack.pop_back();
      if (!agg.active[tn]) continue;
      const double td = (bt.center[tn] - gc).norm();
      if (bt.child[tn] >= 0 || bt.body[tn] < 0) {
        // Groups open at kGroupTheta * theta, as in the force walk: at the full angle their
        // error slowed the induction's GMRES (100 spheres: 27 iterations in 9 substeps instead
        // of 18).
        if (well_separated(td, bt.radius[tn], gr, agg.open_radius[tn], gr, kGroupTheta * opt.theta, opt.near_field,
                           2.0 * bt.reach[tn])) {
          far.push_back({bt.center[tn] - gc, agg.moment[tn]});
        } else {
          tree_stack.push_back(bt.child[tn] + 1);
          tree_stack.push_back(bt.child[tn]);
        }
        continue;
      }
      const int body = bt.body[tn];
      const int root = m.body_root[body];
      const Vec3 origin = s.body_pose[body].position;
      int top = 0;
      stack[top++] = root;
      while (top > 0) {
        const int n = stack[--top];
        if (!src.node_active[n]) continue;
        const Vec3 nc = origin + s.node_offset[n];
        const double d = (nc - gc).norm();
        const double rn = m.node_radius[n];
        const double near_margin = opt.near_field * 2.0 * m.node_reach[n];
        if (rn + gr < opt.theta * d && d - rn - gr > near_margin) {
          far.push_back({nc - gc, src.node[n]});  // the node acts as one dipole at its centre
          continue;
        }
        const int ch = m.node_child[n];
        if (ch >= 0) {
          assert(top + m.node_nchild[n] <= 128);
          for (int k = ch + m.node_nchild[n] - 1; k >= ch; --k) stack[top++] = k;
          continue;
        }
        // Leaf: cells that may be near some target are decided per target; the rest are dipoles.
        for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
          const Vec3& mc = src.cell[c];
          if (mc.squaredNorm() == 0.0) continue;
          const Vec3 xc = origin + s.cell_offset[c];
          const double lim = std::max(opt.near_field * 2.0 * m.cell_half[c].maxCoeff(), opt.smear_inside ? m.cell_reach[c] : 0.0);
          const bool maybe_near = (xc - gc).norm() - gr < lim + m.cell_reach[c];
          // Targets that are cells skip themselves: cells of the group's own leaf are decided
          // target by target (a group of induced cells is one leaf, from_induced_cells()).
          const bool self = t.cell[tb] >= 0 && m.node_begin[n] <= t.cell[tb] && t.cell[tb] < m.node_end[n];
          if (maybe_near || self) {
            near.push_back(c);
          } else {
            far.push_back({xc - gc, mc});
          }
        }
      }
    }
    const int n = te - tb;
    count += std::int64_t(far.size() + near.size()) * n;
    // Far nodes and plain leaf dipoles.
    rel.resize(n);
    for (int q = 0; q < n; ++q) rel[q] = t.position[tb + q] - gc;
    if (opt.single_precision) {
      dipoles_f32(far, rel, n, B.data() + tb);
    } else {
      dipoles_f64(far, rel, n, B.data() + tb);
    }
    // Near cells, target by target, in double: exact cuboids, smeared cuboids inside, dipoles.
    for (int c : near) {
      const int body = m.cell_body[c];
      const Vec3 origin = s.body_pose[body].position;
      const Vec3& mc = src.cell[c];
      const Vec3 xc = origin + s.cell_offset[c];
      const Vec3 cc = origin + s.body_rotation[body] * m.cell_center[c];
      const Mat3& R = s.part_rotation[m.cell_part[c]];
      const Vec3& h = m.cell_half[c];
      const double lim = opt.near_field * 2.0 * h.maxCoeff();
      for (int q = tb; q < te; ++q) {
        if (t.cell[q] == c) continue;
        const Vec3 rc = t.position[q] - cc;
        bool cuboid = opt.near_field > 0.0 && m.cell_full[c] && rc.squaredNorm() < lim * lim;
        if (!cuboid && opt.smear_inside) {
          const Vec3 local = R.transpose() * rc;
          cuboid = (local.cwiseAbs() - h).maxCoeff() <= 0.0;
        }
        if (cuboid) {
          // The cell's cuboid with its moment smeared over it (exact for full cells).
          const double vol = 8.0 * h.prod();
          B[q] += R * cuboid_b_field(h, R.transpose() * mc / vol, R.transpose() * rc);
        } else {
          const Vec3 r = t.position[q] - xc;
          if (r.squaredNorm() > 0.0) B[q] += dipole_field(r, mc);
        }
      }
    }
    work[g] = count;
  });
  return std::accumulate(work.begin(), work.end(), std::int64_t(0));
}

}  // namespace magbake::magnetics
