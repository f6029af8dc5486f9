#include "field.h"

#include <algorithm>
#include <cassert>
#include <numeric>

#include "cuboid.h"
#include "dipole.h"
#include "parallel.h"

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

std::int64_t field_at_targets(const Model& m, const State& s, const Sources& src, const Targets& t,
                              const FieldOptions& opt, std::span<Vec3> B) {
  const int ngroup = static_cast<int>(t.group_begin.size()) - 1;
  assert(B.size() == t.position.size());
  std::vector<std::int64_t> work(std::max(ngroup, 0), 0);

  parallel_for_each(ngroup, 4, [&](int g) {
    const int tb = t.group_begin[g], te = t.group_begin[g + 1];
    for (int q = tb; q < te; ++q) B[q] = Vec3::Zero();
    const Vec3 gc = t.group_center[g];
    const double gr = t.group_radius[g];
    std::int64_t count = 0;
    int stack[128];
    for (int body = 0; body < m.body_count; ++body) {
      const int root = m.body_root[body];
      if (root < 0 || !src.node_active[root]) continue;
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
          // Far: the node acts as one dipole at its centre.
          const Vec3 mn = src.node[n];
          for (int q = tb; q < te; ++q) B[q] += dipole_field(t.position[q] - nc, mn);
          count += te - tb;
          continue;
        }
        const int ch = m.node_child[n];
        if (ch >= 0) {
          assert(top + m.node_nchild[n] <= 128);
          for (int k = ch + m.node_nchild[n] - 1; k >= ch; --k) stack[top++] = k;
          continue;
        }
        // Leaf: every cell, point dipoles, exact cuboids where near.
        for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
          const Vec3 mc = src.cell[c];
          if (mc.squaredNorm() == 0.0) continue;
          const Vec3 xc = origin + s.cell_offset[c];
          const double lim = opt.near_field * 2.0 * m.cell_half[c].maxCoeff();
          const Vec3 cc = origin + s.body_rotation[body] * m.cell_center[c];
          for (int q = tb; q < te; ++q) {
            if (t.cell[q] == c) continue;
            if (opt.near_field > 0.0 && m.cell_full[c] && (t.position[q] - cc).squaredNorm() < lim * lim) {
              // Near a full cell: the exact field of its cuboid.
              const Mat3& R = s.part_rotation[m.cell_part[c]];
              const double vol = 8.0 * m.cell_half[c].prod();
              B[q] += R * cuboid_b_field(m.cell_half[c], R.transpose() * mc / vol, R.transpose() * (t.position[q] - cc));
            } else {
              const Vec3 r = t.position[q] - xc;
              if (r.squaredNorm() > 0.0) B[q] += dipole_field(r, mc);
            }
          }
          count += te - tb;
        }
      }
    }
    work[g] = count;
  });
  return std::accumulate(work.begin(), work.end(), std::int64_t(0));
}

}  // namespace magbake::magnetics
