#include "field.h"

#include <algorithm>
#include <cassert>
#include <limits>
#include <numeric>

#include "body_tree.h"
#include "cuboid.h"
#include "dipole.h"
#include "local_expansion.h"
#include "parallel.h"
#include "simd_rsqrt.h"
#include "surface_charge.h"

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

namespace magbake::magnetics {

void Sources::aggregate(const Model& m, std::span<const Vec3> cell_offset, std::span<const Vec3> node_offset) {
  aggregate(m);
  const int nn = m.node_count();
  first_moment.assign(nn, Mat3::Zero());
  spread.assign(nn, 0.0);
  for (int n = nn - 1; n >= 0; --n) {
    if (!node_active[n]) continue;
    Mat3& q = first_moment[n];
    const int ch = m.node_child[n];
    if (ch < 0) {
      for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) q += cell[c] * (cell_offset[c] - node_offset[n]).transpose();
    } else {
      for (int k = ch; k < ch + m.node_nchild[n]; ++k) {
        q += first_moment[k] + node[k] * (node_offset[k] - node_offset[n]).transpose();
      }
    }
    const double net = node[n].norm();
    spread[n] = net > 0.0 ? q.norm() / net : std::numeric_limits<double>::infinity();
  }
}

void Sources::aggregate(const Model& m) {
  spread.clear();
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
      // 2/d, 0 where the target sits on the source (a cell's own field is not summed).
      const __m256 z = _mm256_andnot_ps(_mm256_cmp_ps(d2, _mm256_setzero_ps(), _CMP_EQ_OQ), two_over_sqrt(d2));
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
      // 0 where the target sits on the source (a cell's own field is not summed).
      const __m256d inv = _mm256_andnot_pd(_mm256_cmp_pd(d2, _mm256_setzero_pd(), _CMP_EQ_OQ),
                                           _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(d2)));
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
    for (const Source& s : src) {
      if ((rel[q] - s.x).squaredNorm() > 0.0) B[q] += dipole_field(rel[q] - s.x, s.m);
    }
  }
}
void dipoles_f32(const std::vector<Source>& src, const std::vector<Vec3>& rel, int n, Vec3* B) {
  for (int q = 0; q < n; ++q) {
    Eigen::Vector3f acc = Eigen::Vector3f::Zero();
    for (const Source& s : src) {
      const Eigen::Vector3f r = (rel[q] - s.x).cast<float>();
      const Eigen::Vector3f m = s.m.cast<float>();
      const float d2 = r.squaredNorm();
      if (d2 == 0.0f) continue;
      const float inv = 1.0f / std::sqrt(d2), inv5 = inv * inv * inv * inv * inv;
      acc += inv5 * (3.0f * m.dot(r) * r - d2 * m);
    }
    B[q] += kMu0Over4Pi * acc.cast<double>();
  }
}
#endif

}  // namespace

namespace {

// Independent pieces of the walk: subtrees of the target hierarchy, found by splitting every
// inner node level by level until there are at least kTasks (a count fixed by the tree alone,
// so the result does not depend on the number of threads).
constexpr int kTasks = 64;

// Fewest target groups under a node of the target hierarchy for which a far group's field is
// taken as a local expansion (below, each group sums the far aggregate at its own targets).
// Measured on 1000 spheres (bench/README.md, "Dual field walk"): 8, 4 and 2 cost the same
// within 2%.
constexpr int kLocalGroups = 4;

std::vector<int> task_roots(const BodyTree& tt) {
  std::vector<int> roots{0};
  while (static_cast<int>(roots.size()) < kTasks) {
    std::vector<int> next;
    for (int n : roots) {
      if (tt.child[n] < 0) {
        next.push_back(n);
      } else {
        next.push_back(tt.child[n]);
        next.push_back(tt.child[n] + 1);
      }
    }
    if (next.size() == roots.size()) break;
    roots.swap(next);
  }
  return roots;
}

// Position (world, m) and moment of a far source of a group.
inline Source far_source(const FieldPlan::Far& f, const Model& m, const State& s, const Sources& src,
                         const BodyTreeSources& agg, const Vec3& gc) {
  switch (f.kind) {
    case FieldPlan::kBodyNode:
      return {s.body_tree.center[f.index] - gc, agg.moment[f.index]};
    case FieldPlan::kCellNode:
      return {s.body_pose[m.node_body[f.index]].position + s.node_offset[f.index] - gc, src.node[f.index]};
    default:
      return {s.body_pose[m.cell_body[f.index]].position + s.cell_offset[f.index] - gc, src.cell[f.index]};
  }
}

}  // namespace

FieldPlan plan_field(const Model& m, const State& s, const Sources& src, const Targets& t, const FieldOptions& opt) {
  FieldPlan plan;
  const int ngroup = static_cast<int>(t.group_begin.size()) - 1;
  const BodyTree& bt = s.body_tree;
  plan.far_begin.assign(std::max(ngroup, 0), 0);
  plan.far_end.assign(std::max(ngroup, 0), 0);
  plan.near_begin.assign(std::max(ngroup, 0), 0);
  plan.near_end.assign(std::max(ngroup, 0), 0);
  plan.surface_begin.assign(std::max(ngroup, 0), 0);
  plan.surface_end.assign(std::max(ngroup, 0), 0);
  if (bt.empty() || ngroup <= 0) return plan;
  const bool surfaces = opt.surfaces && !m.body_surface_part.empty();
  BodyTreeSources agg;
  agg.aggregate(bt, m, src);
  BodyTree& tt = plan.target_tree;
  // Groups of a body's cells under one node (targets on cells); points grouped by space alone.
  std::vector<int> group_body;
  const bool cell_targets = t.cell.size() > 0 && t.cell[0] >= 0;
  if (cell_targets) {
    group_body.resize(ngroup);
    for (int g = 0; g < ngroup; ++g) group_body[g] = m.cell_body[t.cell[t.group_begin[g]]];
  }
  tt.build_over(t.group_center, t.group_radius, group_body);
  plan.roots = task_roots(tt);
  const int ntask = static_cast<int>(plan.roots.size());

  // The dual walk, per subtree of targets: a group of sources far from a group of targets adds
  // its summed dipole's second-order local expansion at the targets' centre (handed down to every
  // target below); a few target groups take the far aggregate at each target; a target group
  // next to a body walks that body's cells.
  std::vector<std::vector<std::pair<int, int>>> locals(ntask);
  // Per subtree: (group, body >= 0 or ~far body-tree node) in walk order, and the lists of its
  // groups, one after the other in tree order (offsets relative to the subtree's own lists).
  std::vector<std::vector<std::pair<int, int>>> walk_near(ntask);
  std::vector<std::vector<FieldPlan::Far>> far(ntask);
  std::vector<std::vector<int>> near(ntask);
  std::vector<std::vector<int>> surface(ntask);
  parallel_for_each(ntask, 1, [&](int k) {
    std::vector<std::pair<int, int>> stack{{plan.roots[k], 0}};
    while (!stack.empty()) {
      const auto [x, y] = stack.back();
      stack.pop_back();
      if (!agg.active[y]) continue;
      const double d = (tt.center[x] - bt.center[y]).norm(), rx = tt.radius[x];
      // Groups of bodies open at kGroupTheta * theta, as in the force walk (at the full angle
      // their error slowed the induction's GMRES); a body at theta, as its own root cell.
      const double theta = bt.child[y] < 0 ? opt.theta : kGroupTheta * opt.theta;
      const bool gap = d - bt.radius[y] - rx > opt.near_field * 2.0 * bt.reach[y];
      if (tt.end[x] - tt.begin[x] < kLocalGroups) {
        // Few targets: the aggregate at each of them costs less than an expansion.
        if (gap && agg.open_radius[y] + rx < theta * d && spread_ok(agg.spread[y], 0.0, theta, d)) {
          for (int q = tt.begin[x]; q < tt.end[x]; ++q) walk_near[k].emplace_back(tt.order[q], ~y);
          continue;
        }
      } else if (gap && agg.open_radius[y] < theta * (d - rx) && spread_ok(agg.spread[y], 0.0, theta, d - rx) &&
                 rx < kLocalTheta * opt.theta * d) {
        // The aggregate's error at the nearest target as above; the expansion's own ~10 (rx/d)^3.
        locals[k].emplace_back(x, y);
        continue;
      }
      const int cx = tt.child[x], cy = bt.child[y];
      if (cx < 0 && cy < 0) {
        walk_near[k].emplace_back(tt.body[x], bt.body[y]);
      } else if (cy < 0 || (cx >= 0 && tt.radius[x] >= bt.radius[y])) {
        stack.emplace_back(cx + 1, y);
        stack.emplace_back(cx, y);
      } else {
        stack.emplace_back(x, cy + 1);
        stack.emplace_back(x, cy);
      }
    }
    // Each group of the subtree against the cell hierarchies of its near bodies: far cell nodes
    // and plain cells are dipoles summed at every target, cells near a target are decided target
    // by target.
    // Entries by group in tree order, walk order kept within a group (a counting sort).
    const int q0 = tt.begin[plan.roots[k]], q1 = tt.end[plan.roots[k]];
    std::vector<int> start(q1 - q0 + 1, 0);
    for (const auto& [g, v] : walk_near[k]) ++start[tt.begin[tt.leaf_of[g]] - q0 + 1];
    for (int q = 0; q < q1 - q0; ++q) start[q + 1] += start[q];
    std::vector<int> wn(walk_near[k].size());
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (const auto& [g, v] : walk_near[k]) wn[fill[tt.begin[tt.leaf_of[g]] - q0]++] = v;
    }
    std::vector<std::pair<int, int>>().swap(walk_near[k]);
    for (int q = tt.begin[plan.roots[k]]; q < tt.end[plan.roots[k]]; ++q) {
      const int g = tt.order[q];
      const int tb = t.group_begin[g];
      const Vec3 gc = t.group_center[g];
      const double gr = t.group_radius[g];
      int stk[128];
      plan.far_begin[g] = static_cast<int>(far[k].size());
      plan.near_begin[g] = static_cast<int>(near[k].size());
      plan.surface_begin[g] = static_cast<int>(surface[k].size());
      for (int e = start[q - q0]; e < start[q - q0 + 1]; ++e) {
        const int body = wn[e];
        if (body < 0) {
          far[k].push_back({FieldPlan::kBodyNode, ~body});
          continue;
        }
        const Vec3 origin = s.body_pose[body].position;
        // Another body closer to the group than its own radius opens at other_body_theta.
        double theta = opt.theta;
        if (cell_targets && opt.other_body_theta > 0 && group_body[g] != body) {
          const int root = m.body_root[body];
          const double rb = m.node_radius[root];
          if ((origin + s.node_offset[root] - gc).norm() - rb - gr < rb) theta = opt.other_body_theta;
        }
        // A surface part that the group would open gives its exact field, and its cells none.
        constexpr int kMaxSurfaces = 16;
        int excl[kMaxSurfaces], nexcl = 0;
        const int s0 = surfaces ? m.body_surface_begin[body] : 0, s1 = surfaces ? m.body_surface_begin[body + 1] : 0;
        for (int i = s0; i < s1 && nexcl < kMaxSurfaces; ++i) {
          const int p = m.body_surface_part[i];
          if (!m.opens_surface(p, origin, s.body_rotation[body], gc, gr, opt.theta)) continue;
          excl[nexcl++] = p;
          surface[k].push_back(p);
        }
        auto excluded = [&](int part) { return std::find(excl, excl + nexcl, part) != excl + nexcl; };
        int top = 0;
        stk[top++] = m.body_root[body];
        while (top > 0) {
          const int n = stk[--top];
          if (!src.node_active[n]) continue;
          // A node of excluded cells only is skipped; one of several parts is opened.
          if (nexcl > 0 && m.node_part[n] >= 0 && excluded(m.node_part[n])) continue;
          const double dn = (origin + s.node_offset[n] - gc).norm();
          const double rn = m.node_radius[n];
          if ((nexcl == 0 || m.node_part[n] >= 0) && rn + gr < theta * dn &&
              dn - rn - gr > opt.near_field * 2.0 * m.node_reach[n] &&
              (src.spread.empty() || spread_ok(src.spread[n], 0.0, theta, dn))) {
            far[k].push_back({FieldPlan::kCellNode, n});  // the node acts as one dipole at its centre
            continue;
          }
          const int ch = m.node_child[n];
          if (ch >= 0) {
            assert(top + m.node_nchild[n] <= 128);
            for (int c = ch + m.node_nchild[n] - 1; c >= ch; --c) stk[top++] = c;
            continue;
          }
          // Leaf: cells that may be near some target are decided per target; the rest are dipoles.
          for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
            if (src.cell[c].squaredNorm() == 0.0 || (nexcl > 0 && excluded(m.cell_part[c]))) continue;
            const Vec3 xc = origin + s.cell_offset[c];
            // A ball cell's field is its dipole outside and uniform inside (its reach).
            const double lim = m.cell_ball[c] ? m.cell_reach[c]
                                              : std::max(opt.near_field * 2.0 * m.cell_half[c].maxCoeff(),
                                                         opt.smear_inside ? m.cell_reach[c] : 0.0);
            const bool maybe_near = (xc - gc).norm() - gr < lim + m.cell_reach[c];
            // Targets that are cells skip themselves: cells of the group's own leaf are decided
            // target by target (a group of induced cells is one leaf, from_induced_cells()).
            const bool self = t.cell[tb] >= 0 && m.node_begin[n] <= t.cell[tb] && t.cell[tb] < m.node_end[n];
            // A cell that apply_field_plan() would take as a plain dipole at every target anyway
            // (no ball, no cuboid, no smearing) is summed with the far ones; a target on the cell
            // itself is 0 away from it, which the sums skip.
            const bool plain = !m.cell_ball[c] && !(opt.near_field > 0.0 && m.cell_full[c]) && !opt.smear_inside;
            if ((maybe_near || self) && !plain) {
              near[k].push_back(c);
            } else {
              far[k].push_back({FieldPlan::kCell, c});
            }
          }
        }
      }
      plan.far_end[g] = static_cast<int>(far[k].size());
      plan.near_end[g] = static_cast<int>(near[k].size());
      plan.surface_end[g] = static_cast<int>(surface[k].size());
    }
  });
  // Flatten, in a fixed order.
  plan.local_begin.assign(ntask + 1, 0);
  for (int k = 0; k < ntask; ++k) plan.local_begin[k + 1] = plan.local_begin[k] + static_cast<int>(locals[k].size());
  plan.local_pair.reserve(plan.local_begin[ntask]);
  for (auto& l : locals) plan.local_pair.insert(plan.local_pair.end(), l.begin(), l.end());
  std::size_t nfar = 0, nnear = 0, nsurf = 0;
  for (int k = 0; k < ntask; ++k) nfar += far[k].size(), nnear += near[k].size(), nsurf += surface[k].size();
  plan.surface.reserve(nsurf);
  plan.far.reserve(nfar);
  plan.near.reserve(nnear);
  for (int k = 0; k < ntask; ++k) {
    const int f0 = static_cast<int>(plan.far.size()), n0 = static_cast<int>(plan.near.size());
    const int s0 = static_cast<int>(plan.surface.size());
    for (int q = tt.begin[plan.roots[k]]; q < tt.end[plan.roots[k]]; ++q) {
      const int g = tt.order[q];
      plan.far_begin[g] += f0, plan.far_end[g] += f0, plan.near_begin[g] += n0, plan.near_end[g] += n0;
      plan.surface_begin[g] += s0, plan.surface_end[g] += s0;
      const std::int64_t n = t.group_begin[g + 1] - t.group_begin[g];
      plan.pairs += n * std::int64_t(plan.far_end[g] - plan.far_begin[g] + plan.near_end[g] - plan.near_begin[g]);
      for (int e = plan.surface_begin[g]; e < plan.surface_end[g]; ++e) {
        plan.pairs += n * m.surface_triangles(surface[k][e - s0]);
      }
    }
    plan.surface.insert(plan.surface.end(), surface[k].begin(), surface[k].end());
    std::vector<int>().swap(surface[k]);
    plan.far.insert(plan.far.end(), far[k].begin(), far[k].end());
    plan.near.insert(plan.near.end(), near[k].begin(), near[k].end());
    std::vector<FieldPlan::Far>().swap(far[k]);
    std::vector<int>().swap(near[k]);
  }
  plan.pairs += static_cast<std::int64_t>(plan.local_pair.size()) + static_cast<std::int64_t>(t.position.size());
  return plan;
}

std::int64_t apply_field_plan(const FieldPlan& plan, const Model& m, const State& s, const Sources& src,
                              const Targets& t, const FieldOptions& opt, std::span<Vec3> B) {
  assert(B.size() == t.position.size());
  std::fill(B.begin(), B.end(), Vec3::Zero());
  const BodyTree& tt = plan.target_tree;
  if (tt.empty() || s.body_tree.empty()) return 0;
  const BodyTree& bt = s.body_tree;
  BodyTreeSources agg;
  agg.aggregate(bt, m, src);
  std::vector<LocalExpansion> local(tt.node_count());
  std::vector<std::uint8_t> has_local(tt.node_count(), 0);
  parallel_for_each(static_cast<int>(plan.roots.size()), 1, [&](int k) {
    // Far groups' expansions, four pairs per AVX2 vector, added in list order (the lanes compute
    // exactly what add_dipole() would).
    const int e1 = plan.local_begin[k + 1];
    int e = plan.local_begin[k];
#if defined(__AVX2__) && defined(__FMA__)
    using v4d = double __attribute__((vector_size(32)));
    for (; e + 4 <= e1; e += 4) {
      alignas(32) double rl[3][4], ml[3][4];
      for (int j = 0; j < 4; ++j) {
        const auto [x, y] = plan.local_pair[e + j];
        const Vec3 d = tt.center[x] - bt.center[y];
        for (int c = 0; c < 3; ++c) rl[c][j] = d[c], ml[c][j] = agg.moment[y][c];
      }
      v4d r[3], mv[3];
      for (int c = 0; c < 3; ++c) r[c] = v4d(_mm256_load_pd(rl[c])), mv[c] = v4d(_mm256_load_pd(ml[c]));
      v4d terms[LocalExpansion::kTerms];
      LocalExpansion::dipole_terms(
          r, mv, [](v4d d2) { return v4d(_mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(__m256d(d2)))); }, terms);
      for (int j = 0; j < 4; ++j) {
        double lane[LocalExpansion::kTerms];
        for (int q = 0; q < LocalExpansion::kTerms; ++q) lane[q] = terms[q][j];
        const int x = plan.local_pair[e + j].first;
        local[x].add_terms(lane);
        has_local[x] = 1;
      }
    }
#endif
    for (; e < e1; ++e) {
      const auto [x, y] = plan.local_pair[e];
      local[x].add_dipole(tt.center[x] - bt.center[y], agg.moment[y]);
      has_local[x] = 1;
    }
    // Hand the expansions down the subtree; at a group, evaluate its expansion at every target,
    // then its far dipoles and near cells.
    std::vector<int> down{plan.roots[k]};
    std::vector<Source> far;
    std::vector<Vec3> rel;
    std::vector<double> corner_distance;
    while (!down.empty()) {
      const int x = down.back();
      down.pop_back();
      const int cx = tt.child[x];
      if (cx >= 0) {
        if (has_local[x]) {
          for (int c = cx; c < cx + 2; ++c) {
            local[x].shift_into(tt.center[c] - tt.center[x], local[c]);
            has_local[c] = 1;
          }
        }
        down.push_back(cx + 1);
        down.push_back(cx);
        continue;
      }
      const int g = tt.body[x];
      const int tb = t.group_begin[g], te = t.group_begin[g + 1], n = te - tb;
      const Vec3 gc = t.group_center[g];
      if (has_local[x]) {
        for (int q = tb; q < te; ++q) B[q] += local[x].at(t.position[q] - tt.center[x]);
      }
      far.clear();
      for (int e = plan.far_begin[g]; e < plan.far_end[g]; ++e) far.push_back(far_source(plan.far[e], m, s, src, agg, gc));
      rel.resize(n);
      for (int q = 0; q < n; ++q) rel[q] = t.position[tb + q] - gc;
      if (opt.single_precision) {
        dipoles_f32(far, rel, n, B.data() + tb);
      } else {
        dipoles_f64(far, rel, n, B.data() + tb);
      }
      // Exact surfaces of permanent parts, in the body frame.
      for (int e = plan.surface_begin[g]; e < plan.surface_end[g]; ++e) {
        const int p = plan.surface[e];
        const int body = m.part_body[p];
        const Vec3& origin = s.body_pose[body].position;
        const Mat3& Rb = s.body_rotation[body];
        for (int q = tb; q < te; ++q) {
          const Vec3 xb = Rb.transpose() * (t.position[q] - origin);
          B[q] += Rb * m.part_surface_mesh[p].b_field(xb, corner_distance);
        }
      }
      // Near cells, target by target, in double: exact cuboids, smeared cuboids inside, dipoles.
      for (int e = plan.near_begin[g]; e < plan.near_end[g]; ++e) {
        const int c = plan.near[e];
        const int body = m.cell_body[c];
        const Vec3 origin = s.body_pose[body].position;
        const Vec3& mc = src.cell[c];
        const Vec3 xc = origin + s.cell_offset[c];
        const Vec3 cc = origin + s.body_rotation[body] * m.cell_center[c];
        const Mat3& R = s.part_rotation[m.cell_part[c]];
        const Vec3& h = m.cell_half[c];
        const double lim = opt.near_field * 2.0 * h.maxCoeff();
        if (m.cell_ball[c]) {
          // A uniformly magnetized ball: its dipole outside, exactly 2/3 mu0 M inside.
          const Vec3 inside = (2.0 / 3.0) * kMu0 / m.cell_volume[c] * mc;
          for (int q = tb; q < te; ++q) {
            if (t.cell[q] == c) continue;
            const Vec3 rc = t.position[q] - cc;
            B[q] += rc.squaredNorm() <= h[0] * h[0] ? inside : dipole_field(rc, mc);
          }
          continue;
        }
        for (int q = tb; q < te; ++q) {
          if (t.cell[q] == c) continue;
          const Vec3 rc = t.position[q] - cc;
          bool cuboid = opt.near_field > 0.0 && m.cell_full[c] && rc.squaredNorm() < lim * lim;
          if (!cuboid && opt.smear_inside) {
            const Vec3 lc = R.transpose() * rc;
            cuboid = (lc.cwiseAbs() - h).maxCoeff() <= 0.0;
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
    }
  });
  return plan.pairs;
}

std::int64_t field_at_targets(const Model& m, const State& s, const Sources& src, const Targets& t,
                              const FieldOptions& opt, std::span<Vec3> B) {
  return apply_field_plan(plan_field(m, s, src, t, opt), m, s, src, t, opt, B);
}

}  // namespace magbake::magnetics
