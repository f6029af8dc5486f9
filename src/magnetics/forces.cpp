#include "forces.h"

#include <cassert>
#include <cmath>
#include <vector>

#include "block_kernel.h"
#include "cuboid.h"
#include "dipole.h"
#include "parallel.h"

namespace magbake::magnetics {
namespace {

enum : unsigned char { kFar = 0, kBlock = 1, kBlockClamp = 2, kBlockNear = 4 };

struct Interaction {
  int pair;            // index into the body-pair list
  int a, b;            // nodes of the pair's first and second body
  unsigned char kind;  // kFar or kBlock (| kBlockClamp | kBlockNear)
};

struct PairResult {
  Vec3 force = Vec3::Zero();   // on body a
  Vec3 torque = Vec3::Zero();  // on body a about its origin
  double energy = 0.0;
  int near_pairs = 0;
};

// Exact-cuboid correction for the near cell pairs of a leaf block: adds (cuboid - dipole).
// Only full cells are cuboids; a boundary cell stays a dipole at the centroid of its material.
int near_correction(const Model& m, const Settings& st, const State& s, int ta, int tb, int sa, int sb,
                    const Vec3& delta, PairResult& out) {
  int count = 0;
  if (ta >= tb || sa >= sb) return 0;
  const Mat3& Ra = s.body_rotation[m.cell_body[ta]];
  const Mat3& Rb = s.body_rotation[m.cell_body[sa]];
  for (int k = ta; k < tb; ++k) {
    const Vec3 mk = s.total.cell[k];
    if (!m.cell_full[k] || mk.squaredNorm() == 0.0) continue;
    const double hk = m.cell_half[k].maxCoeff();
    const Vec3 ck = Ra * m.cell_center[k];  // cuboid centre relative to body a's origin
    for (int i = sa; i < sb; ++i) {
      const Vec3 rc = delta + ck - Rb * m.cell_center[i];
      const double lim = st.near_field * (hk + m.cell_half[i].maxCoeff());
      if (rc.squaredNorm() >= lim * lim) continue;
      const Vec3 mi = s.total.cell[i];
      if (!m.cell_full[i] || mi.squaredNorm() == 0.0) continue;
      Cuboid cub_k{rc, s.part_rotation[m.cell_part[k]], m.cell_half[k], mk / (8.0 * m.cell_half[k].prod())};
      Cuboid cub_i{Vec3::Zero(), s.part_rotation[m.cell_part[i]], m.cell_half[i], mi / (8.0 * m.cell_half[i].prod())};
      // Quadrature order by distance: the full order at contact, 3 from 2.5 cell sizes on (the
      // integrand is smooth there and 3 already beats the dipole by two orders of magnitude).
      const double dist = rc.norm() / (hk + m.cell_half[i].maxCoeff());
      const int order = dist < 1.5 ? st.near_field_order : dist < 2.5 ? std::max(3, st.near_field_order - 1) : 3;
      // Cells of penetrating bodies (a contact solver's tolerance) overlap: evaluate them at
      // the touching pose and continue the energy linearly, so force and energy stay continuous
      // through contact and the force stays the energy's gradient along the push-out direction.
      Vec3 shift;
      const bool overlap = cuboid_overlap_shift(cub_k, cub_i, shift);
      if (overlap) cub_k.center += shift;
      Vec3 F, T;
      double E = 0.0;
      cuboid_pair(cub_k, cub_i, std::min(order, st.near_field_order), F, T, &E);
      if (overlap) E += F.dot(shift);
      const Vec3 rp = delta + s.cell_offset[k] - s.cell_offset[i];
      const DipolePair dp = dipole_pair(rp, mk, mi, m.cell_clamp[k] + m.cell_clamp[i]);
      // Replace the dipole pair the block kernel added by the cuboid pair (torques about body a's
      // origin), energy included, so that near contact the force stays -grad of the energy.
      out.force += F - dp.force;
      out.torque += ck.cross(F) + T - (s.cell_offset[k].cross(dp.force) + dp.torque);
      out.energy += E - dp.energy;
      ++count;
    }
  }
  return count;
}

// Permanent-permanent energy of two bodies, point dipoles cell by cell (clamped as in the
// kernels): only for bodies that also hold induced cells, whose pair sum mixes both kinds.
double permanent_pair_energy(const Model& m, const State& s, int ba, int bb) {
  double e = 0.0;
  const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
  for (int k = m.body_cell_begin[ba]; k < m.body_cell_begin[ba + 1]; ++k) {
    if (m.cell_moment[k].squaredNorm() == 0.0) continue;
    for (int i = m.body_cell_begin[bb]; i < m.body_cell_begin[bb + 1]; ++i) {
      if (m.cell_moment[i].squaredNorm() == 0.0) continue;
      e += dipole_pair(delta + s.cell_offset[k] - s.cell_offset[i], s.permanent.cell[k], s.permanent.cell[i],
                       m.cell_clamp[k] + m.cell_clamp[i])
               .energy;
    }
  }
  return e;
}

}  // namespace

void accumulate_forces(const Model& m, const Settings& st, const State& s, Result& res) {
  // Body pairs with something magnetic on both sides, in a fixed order.
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < m.body_count; ++a) {
    const int ra = m.body_root[a];
    if (ra < 0 || !s.total.node_active[ra]) continue;
    for (int b = a + 1; b < m.body_count; ++b) {
      const int rb = m.body_root[b];
      if (rb < 0 || !s.total.node_active[rb]) continue;
      pairs.emplace_back(a, b);
    }
  }
  res.stats.body_pairs += static_cast<std::int64_t>(pairs.size());

  // Dual-tree walk of every pair: refine where close, aggregate where far (serial, so the list
  // and hence the summation order never depend on the thread count).
  std::vector<Interaction> list;
  std::vector<std::pair<int, int>> stack;
  for (int p = 0; p < static_cast<int>(pairs.size()); ++p) {
    const auto [ba, bb] = pairs[p];
    const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
    stack.clear();
    stack.emplace_back(m.body_root[ba], m.body_root[bb]);
    while (!stack.empty()) {
      const auto [na, nb] = stack.back();
      stack.pop_back();
      if (!s.total.node_active[na] || !s.total.node_active[nb]) continue;
      const double d = (delta + s.node_offset[na] - s.node_offset[nb]).norm();
      const double ra = m.node_radius[na], rb = m.node_radius[nb];
      const double gap = d - ra - rb;  // lower bound on (centre distance - reaches) of any cell pair
      const double near_margin = st.near_field * (m.node_reach[na] + m.node_reach[nb]);
      if (ra + rb < st.theta * d && gap > near_margin) {
        list.push_back({p, na, nb, kFar});
        continue;
      }
      const int ca = m.node_child[na], cb = m.node_child[nb];
      if (ca < 0 && cb < 0) {
        unsigned char kind = kBlock;
        if (gap < 0.0) kind |= kBlockClamp;
        if (st.near_field > 0.0 && gap < near_margin) kind |= kBlockNear;
        list.push_back({p, na, nb, kind});
      } else if (cb < 0 || (ca >= 0 && ra >= rb)) {
        for (int k = ca + m.node_nchild[na] - 1; k >= ca; --k) stack.emplace_back(k, nb);
      } else {
        for (int k = cb + m.node_nchild[nb] - 1; k >= cb; --k) stack.emplace_back(na, k);
      }
    }
  }

  // Evaluate every interaction into its own slot (parallel), then sum in list order.
  std::vector<PairResult> out(list.size());
  parallel_for_each(static_cast<int>(list.size()), 8, [&](int q) {
    const Interaction& it = list[q];
    const auto [ba, bb] = pairs[it.pair];
    const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
    PairResult& r = out[q];
    if (it.kind == kFar) {
      const Vec3 rel = delta + s.node_offset[it.a] - s.node_offset[it.b];
      const DipolePair dp = dipole_pair(rel, s.total.node[it.a], s.total.node[it.b]);
      r.force = dp.force;
      r.torque = s.node_offset[it.a].cross(dp.force) + dp.torque;
      r.energy = dp.energy;
      return;
    }
    BlockSum bs;
    block_interaction(s, m.node_begin[it.a], m.node_end[it.a], m.node_begin[it.b], m.node_end[it.b], delta,
                      (it.kind & kBlockClamp) != 0, st.precision, bs);
    r.force = bs.force;
    r.torque = bs.torque;
    r.energy = bs.energy;
    if (it.kind & kBlockNear) {
      r.near_pairs = near_correction(m, st, s, m.node_begin[it.a], m.node_end[it.a], m.node_begin[it.b],
                                     m.node_end[it.b], delta, r);
    }
  });

  std::vector<PairResult> sum(pairs.size());
  for (std::size_t q = 0; q < list.size(); ++q) {
    PairResult& t = sum[list[q].pair];
    t.force += out[q].force;
    t.torque += out[q].torque;
    t.energy += out[q].energy;
    t.near_pairs += out[q].near_pairs;
    if (list[q].kind == kFar) {
      ++res.stats.node_pairs;
    } else {
      res.stats.cell_pairs += std::int64_t(m.node_end[list[q].a] - m.node_begin[list[q].a]) *
                              (m.node_end[list[q].b] - m.node_begin[list[q].b]);
    }
  }
  // Apply each pair to both bodies: F_b = -F_a, tau_b = -tau_a - (R_a - R_b) x F_a.
  const bool induced_on = m.has_induced() && st.induction != InductionMode::kOff;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [ba, bb] = pairs[p];
    const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
    res.force[ba] += sum[p].force;
    res.torque[ba] += sum[p].torque;
    res.force[bb] -= sum[p].force;
    res.torque[bb] -= sum[p].torque + delta.cross(sum[p].force);
    // Energy: the pair's own when both bodies are purely permanent; pairs with induced cells
    // get theirs from the induction solve (-1/2 m_ind.B_0), plus the permanent-permanent part
    // of bodies that carry both kinds.
    if (!induced_on || (!m.body_induced[ba] && !m.body_induced[bb])) {
      res.energy += sum[p].energy;
    } else if (m.body_permanent[ba] && m.body_permanent[bb]) {
      res.energy += permanent_pair_energy(m, s, ba, bb);
    }
    res.stats.near_pairs += sum[p].near_pairs;
  }
}

}  // namespace magbake::magnetics
