#include "forces.h"

#include <cassert>
#include <algorithm>
#include <cmath>
#include <vector>

#include "block_kernel.h"
#include "body_tree.h"
#include "cuboid.h"
#include "dipole.h"
#include "parallel.h"
#include "surface_charge.h"

namespace magbake::magnetics {
namespace {

// Node pairs of the cell walk where either node holds induced cells aggregate at
// kInducedTheta * theta. A soft body's force is often a small difference of large pulls (a
// cube over a ring magnet: the ring's sides pull it opposite ways), so the aggregates' error,
// of order theta^2 per pair, is amplified. Measured with `magbake eval` on SuperCube's cube
// (10 mm, chi 700 and chi -1, 19-30 mm above the ring), force along z against theta 0: at
// factor 1 steel was +3/+29/+279% off at z = 19/22/30 mm and the superconductor -5/-26/+1%;
// at 0.7, 0.0/+5.8/+19% and 0.0/-2.8/-10% (the rest is the induction solve's own tree), and a
// SuperCube bake no longer gains 20% energy. Cost on the paper windows (paper_table, pair
// counts): cell pairs +27% BowlSpheres, +51% Bowl2008, +52% DragonLow, +70% DragonHigh, and
// T_mag within 0-30%.
constexpr double kInducedTheta = 0.7;
// With an induced node, each node's radius alone must also be below kSoftSourceTheta times the
// pair's angle: the test r_a + r_b < theta d lets a large source act as one dipole on a small
// soft group, whose force depends on the source field's gradient, where the aggregate's error
// of order (r/d)^2 is amplified. Measured (bench/results/soft_graded_2026-12-06): a soft sphere
// 20 mm from a 10 mm cube magnet, default preset, -0.46% -> -0.14% (uniform cells) and -3.2% ->
// -1.6% (graded: half of the magnet cube had joined as one dipole on the sphere's small graded
// leaves); bake time of the paper scenes' first frames: TST and BowlSpheres within noise,
// SuperCube +15%.
constexpr double kSoftSourceTheta = 0.5;

enum : unsigned char {
  kFar = 0,
  kBlock = 1,
  kBlockClamp = 2,
  kBlockNear = 4,
  kBlockMixed = 8,   // a side's filter splits a leaf (cells of several parts): cell by cell
  kSurfaceOnA = 16,  // a surface part of body b (index a) on the cells of leaf b of body a
  kSurfaceOnB = 32,  // a surface part of body a on the cells of leaf b of body b
};

struct Interaction {
  int pair;            // index into the body-pair list
  int a, b;            // nodes of the pair's first and second body; surfaces: part, target leaf
  unsigned char kind;  // kFar, kBlock (| kBlockClamp | kBlockNear | kBlockMixed) or kSurfaceOn*
  int walk = 0;        // blocks: the walk (and so the filters) it came from
};

struct PairResult {
  Vec3 force = Vec3::Zero();   // on body a
  Vec3 torque = Vec3::Zero();  // on body a about its origin
  double energy = 0.0;
  double permanent_energy = 0.0;  // surfaces: the permanent moments' share (-m_perm . B)
  int near_pairs = 0;
  std::int64_t surface_pairs = 0;
};

// Which cells of one side a walk takes: all, all but those of some parts, or one part's only.
struct Filter {
  int only = -1;             // >= 0: this part's cells only
  const int* ex = nullptr;   // otherwise: all but these parts' cells
  int nex = 0;
  bool all() const { return only < 0 && nex == 0; }
  bool allows(int part) const { return only >= 0 ? part == only : std::find(ex, ex + nex, part) == ex + nex; }
  // 1: every cell below node n passes, 0: none, -1: some (the node must be opened).
  int node(const Model& m, int n) const {
    if (all()) return 1;
    return m.node_part[n] >= 0 ? allows(m.node_part[n]) : -1;
  }
};

// Surface parts (Model::part_surface_mesh) that a body pair takes by their exact field: those
// of body a that body b's root node would open (as a field target group would, field.cpp), and
// likewise of body b. Each opened surface acts on the other body's leaves that would open it;
// the other body's farther subtrees meet the part's cells in a walk of their own. A pair of
// parts is computed once: a surface p of a on b's near leaves, every part of b included; a
// surface q of b on a's near leaves, a's opened surfaces excluded; cells with cells for the rest.
constexpr int kMaxPairSurfaces = 16;
struct PairSurfaces {
  int na = 0, nb = 0;
  int a[kMaxPairSurfaces], b[kMaxPairSurfaces];
  // Per opened surface (a's first, then b's): 1 for each cell of the other body in a leaf
  // that takes the surface (index: cell - first cell of that body). Filled only for the pairs
  // whose energy permanent_pair_energy() sums (the one reader).
  std::vector<std::vector<std::uint8_t>> near_cell;
  bool any() const { return na + nb > 0; }
  bool in_a(int part) const { return std::find(a, a + na, part) != a + na; }
};

// A dual walk of one body pair from (na, nb) with a filter per side.
struct Walk {
  int pair, na, nb;
  Filter fa, fb;
};

// Whether node n of body y would open surface part p of body x (Model::opens_surface, as
// field.cpp's target groups).
bool opens(const Model& m, const Settings& st, const State& s, int p, int x, int y, int n) {
  return m.opens_surface(p, s.body_pose[x].position, s.body_rotation[x], s.body_pose[y].position + s.node_offset[n],
                         m.node_radius[n], st.theta);
}

// The surfaces of body x opened by body y's root node.
int opened_surfaces(const Model& m, const Settings& st, const State& s, int x, int y, int* out) {
  int n = 0;
  if (m.body_surface_part.empty()) return 0;
  for (int i = m.body_surface_begin[x]; i < m.body_surface_begin[x + 1] && n < kMaxPairSurfaces; ++i) {
    if (opens(m, st, s, m.body_surface_part[i], x, y, m.body_root[y])) out[n++] = m.body_surface_part[i];
  }
  return n;
}

// Exact surface field of part `sp` (body bs) on the cells [c0, c1) of body bt that `targets`
// allows: each cell's total moment m feels F = G^T m and the torque m x B (G = grad B of the
// surface at the cell), energy -m . B. Sums on the target body, torque about its origin;
// permanent_energy gets -m_perm . B. Returns the cell-triangle evaluations.
std::int64_t surface_on_cells(const Model& m, const State& s, int sp, int bt, int c0, int c1, const Filter& targets,
                              PairResult& out) {
  const int bs = m.part_body[sp];
  const Mat3& Rs = s.body_rotation[bs];
  const Vec3 rel = s.body_pose[bt].position - s.body_pose[bs].position;
  const SurfaceMesh& mesh = m.part_surface_mesh[sp];
  std::vector<double> scratch;
  std::int64_t count = 0;
  for (int c = c0; c < c1; ++c) {
    const Vec3 mc = s.total.cell[c];
    if (mc.squaredNorm() == 0.0 || !targets.allows(m.cell_part[c])) continue;
    const Vec3 xb = Rs.transpose() * (rel + s.cell_offset[c]);
    Vec3 B;
    Mat3 G;
    mesh.b_field_gradient(xb, scratch, B, G);
    const Vec3 mb = Rs.transpose() * mc;
    const Vec3 F = Rs * (G.transpose() * mb);
    const Vec3 Bw = Rs * B;
    out.force += F;
    out.torque += s.cell_offset[c].cross(F) + mc.cross(Bw);
    out.energy -= mc.dot(Bw);
    out.permanent_energy -= s.permanent.cell[c].dot(Bw);
    count += m.surface_triangles(sp);
  }
  return count;
}

// The dipole pairs of a leaf block whose cells some filter splits, with the cuboid correction
// of its near full cells as near_correction().
void mixed_block(const Model& m, const Settings& st, const State& s, int ta, int tb, int sa, int sb,
                 const Vec3& delta, const Filter& fa, const Filter& fb, bool near, PairResult& out);

// Exact-cuboid correction for the near cell pairs of a leaf block: adds (cuboid - dipole).
// Only full cells are cuboids; a boundary cell stays a dipole at the centroid of its material.
// Cells that the filters leave out are skipped.
int near_correction(const Model& m, const Settings& st, const State& s, int ta, int tb, int sa, int sb,
                    const Vec3& delta, PairResult& out, const Filter& fa = {}, const Filter& fb = {}) {
  int count = 0;
  if (ta >= tb || sa >= sb) return 0;
  const Mat3& Ra = s.body_rotation[m.cell_body[ta]];
  const Mat3& Rb = s.body_rotation[m.cell_body[sa]];
  for (int k = ta; k < tb; ++k) {
    const Vec3 mk = s.total.cell[k];
    if (!m.cell_full[k] || mk.squaredNorm() == 0.0) continue;
    if (!fa.allows(m.cell_part[k])) continue;
    const double hk = m.cell_half[k].maxCoeff();
    const Vec3 ck = Ra * m.cell_center[k];  // cuboid centre relative to body a's origin
    for (int i = sa; i < sb; ++i) {
      const Vec3 rc = delta + ck - Rb * m.cell_center[i];
      const double lim = st.near_field * (hk + m.cell_half[i].maxCoeff());
      if (rc.squaredNorm() >= lim * lim) continue;
      const Vec3 mi = s.total.cell[i];
      if (!m.cell_full[i] || mi.squaredNorm() == 0.0) continue;
      if (!fb.allows(m.cell_part[i])) continue;
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

void mixed_block(const Model& m, const Settings& st, const State& s, int ta, int tb, int sa, int sb,
                 const Vec3& delta, const Filter& fa, const Filter& fb, bool near, PairResult& out) {
  for (int k = ta; k < tb; ++k) {
    const Vec3 mk = s.total.cell[k];
    if (mk.squaredNorm() == 0.0 || !fa.allows(m.cell_part[k])) continue;
    for (int i = sa; i < sb; ++i) {
      const Vec3 mi = s.total.cell[i];
      if (mi.squaredNorm() == 0.0 || !fb.allows(m.cell_part[i])) continue;
      const DipolePair dp =
          dipole_pair(delta + s.cell_offset[k] - s.cell_offset[i], mk, mi, m.cell_clamp[k] + m.cell_clamp[i]);
      out.force += dp.force;
      out.torque += s.cell_offset[k].cross(dp.force) + dp.torque;
      out.energy += dp.energy;
    }
  }
  if (near) out.near_pairs += near_correction(m, st, s, ta, tb, sa, sb, delta, out, fa, fb);
}

// Permanent-permanent energy of two bodies, point dipoles cell by cell (clamped as in the
// kernels): only for bodies that also hold induced cells, whose pair sum mixes both kinds.
// Cell pairs that the pair's surfaces take are left out (their share comes with the surfaces).
double permanent_pair_energy(const Model& m, const State& s, int ba, int bb, const PairSurfaces& ps) {
  double e = 0.0;
  const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
  const int a0 = m.body_cell_begin[ba], b0 = m.body_cell_begin[bb];
  auto surface_takes = [&](int k, int i) {
    for (int j = 0; j < ps.na; ++j) {
      if (m.cell_part[k] == ps.a[j] && ps.near_cell[j][i - b0]) return true;
    }
    if (ps.in_a(m.cell_part[k])) return false;
    for (int j = 0; j < ps.nb; ++j) {
      if (m.cell_part[i] == ps.b[j] && ps.near_cell[ps.na + j][k - a0]) return true;
    }
    return false;
  };
  for (int k = a0; k < m.body_cell_begin[ba + 1]; ++k) {
    if (m.cell_moment[k].squaredNorm() == 0.0) continue;
    for (int i = b0; i < m.body_cell_begin[bb + 1]; ++i) {
      if (m.cell_moment[i].squaredNorm() == 0.0 || (ps.any() && surface_takes(k, i))) continue;
      e += dipole_pair(delta + s.cell_offset[k] - s.cell_offset[i], s.permanent.cell[k], s.permanent.cell[i],
                       m.cell_clamp[k] + m.cell_clamp[i])
               .energy;
    }
  }
  return e;
}

// One side of a walk between hierarchies over bodies: the tree, its moment sums, and the field
// and gradient its nodes feel from far groups of the other side.
// Field and gradient sums per tree node of one side (one task's share, or the sides' own).
// A task's sums cover only a window [base, base + size) of node indices: the subtree under the
// task's node on that side (BodyTree allocates every subtree's nodes contiguously after its root's
// children), so tasks need no tree-sized arrays.
struct NodeSums {
  int base = 0;
  std::vector<Vec3> b;
  std::vector<Mat3> g;
  std::vector<std::uint8_t> has;
  void reset(int n, int first = 0) {
    base = first;
    b.assign(n, Vec3::Zero());
    g.assign(n, Mat3::Zero());
    has.assign(n, 0);
  }
  void add(int n, const Vec3& field, const Mat3& grad) {
    b[n - base] += field, g[n - base] += grad, has[n - base] = 1;
  }
};

// Largest node index in the subtree of each node (BodyTree: children follow their parent, and a
// subtree's nodes are allocated together).
std::vector<int> subtree_last(const BodyTree& t) {
  std::vector<int> last(t.node_count());
  for (int n = t.node_count() - 1; n >= 0; --n) last[n] = t.child[n] < 0 ? n : last[t.child[n] + 1];
  return last;
}

struct TreeSide {
  const BodyTree& tree;
  BodyTreeSources total, permanent;
  NodeSums local;  // field and gradient of the far groups, per node
  TreeSide(const BodyTree& t, const Model& m, const State& s) : tree(t) {
    total.aggregate(t, m, s.total);
    permanent.aggregate(t, m, s.permanent);
    local.reset(t.node_count());
  }
};

// What one part of the walk adds: node sums on each side, energy, node-pair count, the body
// pairs left for the cell walk (in the walk's order).
struct WalkSink {
  NodeSums* a = nullptr;  // tree A's side
  NodeSums* b = nullptr;  // tree B's side (the same object when A is B, except in tasks)
  double energy = 0;
  std::int64_t node_pairs = 0;
  std::vector<std::pair<int, int>> pairs;
};

// Number of subtrees of the body-tree walk handed to parallel tasks. Fixed (not the thread
// count), so the split, and with it every sum's order, is the same for any number of threads.
constexpr std::size_t kWalkTasks = 64;

// Walks tree A against tree B (A against itself when `same`). Groups of bodies that are well
// separated interact as the dipole pair of their summed moments at their centres: each member
// gets the force and torque its own moment would feel at its group's centre (the pair
// interaction is bilinear in the moments, so the members' shares add up to the aggregate pair
// exactly, and every share is an exact dipole pair at displaced positions: linear and angular
// momentum are conserved to round-off, and the error is of order theta like any aggregate).
// The field and gradient a group feels are summed per tree node (hand_down() passes them to the
// members). Body pairs that are not well separated are appended to `pairs` for the cell walk.
// The top of the walk expands the largest pending pair until kWalkTasks pairs are pending; each
// pending pair's subtree of the walk is then a task that sums into its own NodeSums windows,
// added to the sides' in task order afterwards (the body pairs come out in task order).
void walk_trees(TreeSide& A, TreeSide& B, bool same, const Settings& st, Result& res,
                std::vector<std::pair<int, int>>& pairs) {
  const BodyTree &ta = A.tree, &tb = B.tree;
  if (ta.empty() || tb.empty()) return;
  // One node pair: a far pair goes to the sink, a near leaf pair to its body pairs, the rest is
  // split onto the stack.
  auto visit = [&](int x, int y, std::vector<std::pair<int, int>>& stack, WalkSink& sink) {
    if (!A.total.active[x] || !B.total.active[y]) return;
    if (same && x == y) {
      const int c = ta.child[x];
      if (c < 0) return;
      stack.emplace_back(c + 1, c + 1);
      stack.emplace_back(c, c + 1);
      stack.emplace_back(c, c);
      return;
    }
    const Vec3 r = ta.center[x] - tb.center[y];
    const double d = r.norm();
    // Groups of bodies (inner nodes) open at kGroupTheta * theta (body_tree.h). Measured on 300
    // spheres (BodyTree.ForcesOfManyBodiesMatchEveryCellPair): at the full angle the groups put
    // 3.5% rms error on the forces; at half of it they are 0.13% rms from walking every pair.
    const bool leaves = ta.child[x] < 0 && tb.child[y] < 0;
    // Nodes holding soft bodies open as the cell walk opens soft nodes (kInducedTheta,
    // kSoftSourceTheta): otherwise a soft body near a magnet, whose cell walk would open at the
    // root, acts as one dipole here. Measured (bench/results/soft_series_2026-12-07): a soft
    // ball 20 mm from a ball magnet, default preset with 1.6 mm graded cells, -11.2% -> -1.07%.
    const bool soft = A.total.induced[x] || B.total.induced[y];
    const double theta = (leaves ? st.theta : st.body_groups ? kGroupTheta * st.theta : 0.0) * (soft ? kInducedTheta : 1.0);
    const double oa = A.total.open_radius[x], ob = B.total.open_radius[y];
    if (well_separated(d, ta.radius[x], tb.radius[y], oa, ob, theta, st.near_field, ta.reach[x] + tb.reach[y]) &&
        (!soft || std::max(oa, ob) < kSoftSourceTheta * theta * d) &&
        spread_ok(A.total.spread[x], B.total.spread[y], theta, d)) {
      Vec3 ba, bb;
      Mat3 ga, gb;
      dipole_mutual_fields(r, A.total.moment[x], B.total.moment[y], ba, ga, bb, gb);
      sink.a->add(x, ba, ga);
      sink.b->add(y, bb, gb);
      sink.energy -= A.permanent.moment[x].dot(dipole_field(r, B.permanent.moment[y]));
      ++sink.node_pairs;
      return;
    }
    const int cx = ta.child[x], cy = tb.child[y];
    if (cx < 0 && cy < 0) {
      sink.pairs.emplace_back(std::min(ta.body[x], tb.body[y]), std::max(ta.body[x], tb.body[y]));
    } else if (cy < 0 || (cx >= 0 && ta.radius[x] >= tb.radius[y])) {
      stack.emplace_back(cx + 1, y);
      stack.emplace_back(cx, y);
    } else {
      stack.emplace_back(x, cy + 1);
      stack.emplace_back(x, cy);
    }
  };
  auto finish = [&](WalkSink& sink) {
    res.energy += sink.energy;
    res.stats.node_pairs += sink.node_pairs;
    pairs.insert(pairs.end(), sink.pairs.begin(), sink.pairs.end());
  };
  // The top of the walk, serially into the sides' own sums: the pending pair over the most body
  // pairs is visited next (its children take its place, in visiting order) until there are
  // kWalkTasks pending pairs, so the tasks are of similar size. The split depends on the trees
  // alone, not on the thread count.
  std::vector<std::pair<int, int>> pending{{0, 0}};
  {
    WalkSink top;
    top.a = &A.local, top.b = &B.local;
    std::vector<std::pair<int, int>> kids;
    while (!pending.empty() && pending.size() < kWalkTasks) {
      std::size_t best = 0;
      std::int64_t most = -1;
      for (std::size_t i = 0; i < pending.size(); ++i) {
        const auto [x, y] = pending[i];
        const std::int64_t w = std::int64_t(ta.end[x] - ta.begin[x]) * (tb.end[y] - tb.begin[y]);
        if (w > most) most = w, best = i;
      }
      const auto [x, y] = pending[best];
      pending.erase(pending.begin() + best);
      kids.clear();
      visit(x, y, kids, top);  // pushed for a stack: the last is visited first
      pending.insert(pending.begin() + best, kids.rbegin(), kids.rend());
    }
    finish(top);
  }
  if (pending.empty()) return;
  // The pending pairs' subtrees in order, each summing into windows over its own subtrees.
  const int ntask = static_cast<int>(pending.size());
  const std::vector<int> last_a = subtree_last(ta), last_b = same ? std::vector<int>() : subtree_last(tb);
  const std::vector<int>& lb = same ? last_a : last_b;
  std::vector<NodeSums> sa(ntask), sb(ntask);
  std::vector<WalkSink> sinks(ntask);
  parallel_for_each(ntask, 1, [&](int k) {
    const auto [x0, y0] = pending[k];
    sa[k].reset(last_a[x0] - x0 + 1, x0);
    sb[k].reset(lb[y0] - y0 + 1, y0);
    sinks[k].a = &sa[k], sinks[k].b = &sb[k];
    std::vector<std::pair<int, int>> local{pending[k]};
    while (!local.empty()) {
      const auto [x, y] = local.back();
      local.pop_back();
      visit(x, y, local, sinks[k]);
    }
  });
  auto add = [](TreeSide& side, const NodeSums& part) {
    for (std::size_t i = 0; i < part.has.size(); ++i) {
      if (!part.has[i]) continue;
      const int n = part.base + static_cast<int>(i);
      side.local.b[n] += part.b[i], side.local.g[n] += part.g[i], side.local.has[n] = 1;
    }
  };
  for (int k = 0; k < ntask; ++k) {
    add(A, sa[k]);
    add(same ? A : B, sb[k]);
    finish(sinks[k]);
  }
}

// Hands the groups' fields down: body b feels, from each ancestor's far groups, the force
// G^T m_b and the torque m_b x B, both as if its moment sat at that ancestor's centre.
void hand_down(const TreeSide& side, const Model& m, const State& s, Result& res) {
  const BodyTree& t = side.tree;
  for (int q = 0; q < static_cast<int>(t.order.size()); ++q) {
    const int b = t.order[q];
    const Vec3 mb = s.total.node[m.body_root[b]];
    const Vec3 origin = s.body_pose[b].position;
    for (int n = t.leaf_of[b]; n >= 0; n = t.parent[n]) {
      if (!side.local.has[n]) continue;
      const Vec3 F = side.local.g[n].transpose() * mb;
      res.force[b] += F;
      res.torque[b] += mb.cross(side.local.b[n]) + (t.center[n] - origin).cross(F);
    }
  }
}

// Forces between the bodies selected by `pick` and the rest, or among the picked bodies when
// `among` is true (cell walk of the near body pairs included): the whole computation for one
// set of bodies or two.
void body_forces(const Model& m, const Settings& st, const State& s, const BodyTree* ta, const BodyTree* tb,
                 Result& res);

}  // namespace

namespace {

void body_forces(const Model& m, const Settings& st, const State& s, const BodyTree* ta, const BodyTree* tb,
                 Result& res) {
  // Body pairs that need their cells (the rest interact through the hierarchies over bodies),
  // in the walk's fixed order.
  std::vector<std::pair<int, int>> pairs;
  {
    TreeSide A(*ta, m, s);
    if (tb == nullptr) {
      walk_trees(A, A, true, st, res, pairs);
      hand_down(A, m, s, res);
    } else {
      TreeSide B(*tb, m, s);
      walk_trees(A, B, false, st, res, pairs);
      hand_down(A, m, s, res);
      hand_down(B, m, s, res);
    }
  }
  res.stats.body_pairs += static_cast<std::int64_t>(pairs.size());

  // Dual-tree walk of every pair: refine where close, aggregate where far (in chunks of pairs
  // joined in pair order, so the list and hence the summation order never depend on the thread
  // count).
  std::vector<Interaction> list;
  std::vector<Walk> all_walks;  // every walk, for the filters of its mixed blocks
  std::vector<PairSurfaces> psurf(pairs.size());
  // Energy: a pair's own when both bodies are purely permanent; pairs with induced cells get
  // theirs from the induction solve (-1/2 m_ind.B_0), plus the permanent-permanent part of
  // bodies that carry both kinds, summed apart (permanent_pair_energy).
  const bool induced_on = m.has_induced() && st.induction != InductionMode::kOff;
  auto mixed_permanent_pair = [&](int ba, int bb) {
    return induced_on && (m.body_induced[ba] || m.body_induced[bb]) && m.body_permanent[ba] && m.body_permanent[bb];
  };
  // The interaction list of one chunk of body pairs: its interactions and walks (an
  // interaction's `walk` indexes the chunk's walks until the chunks are joined).
  struct Chunk {
    std::vector<Interaction> list;
    std::vector<Walk> walks;
  };
  // The leaves of body y (from node n down) that open surface part p of body x get the surface
  // (an interaction each; their cells marked in `mark`); farther subtrees get a walk against
  // the part's cells (filters fx on x's side, fy on y's).
  auto split = [&](Chunk& out, std::vector<Walk>& walks, int pair, int p, int x, int y, bool y_is_b, const Filter& fy,
                   std::vector<std::uint8_t>* mark) {
    int stk[128], top = 0;
    stk[top++] = m.body_root[y];
    Filter fx;
    fx.only = p;
    while (top > 0) {
      const int n = stk[--top];
      if (!s.total.node_active[n] || fy.node(m, n) == 0) continue;
      if (!opens(m, st, s, p, x, y, n)) {
        walks.push_back(y_is_b ? Walk{pair, m.body_root[x], n, fx, fy} : Walk{pair, n, m.body_root[x], fy, fx});
        continue;
      }
      const int ch = m.node_child[n];
      if (ch >= 0) {
        assert(top + m.node_nchild[n] <= 128);
        for (int c = ch + m.node_nchild[n] - 1; c >= ch; --c) stk[top++] = c;
        continue;
      }
      out.list.push_back({pair, p, n, y_is_b ? kSurfaceOnB : kSurfaceOnA});
      if (mark) {
        for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) (*mark)[c - m.body_cell_begin[y]] = 1;
      }
    }
  };
  // Each pair's walks depend on that pair alone, so chunks of pairs are listed in parallel and
  // joined in pair order: the list is the same for any thread count.
  constexpr int kChunk = 32;
  const int npair = static_cast<int>(pairs.size());
  std::vector<Chunk> chunks((npair + kChunk - 1) / kChunk);
  parallel_for_each(static_cast<int>(chunks.size()), 1, [&](int ci) {
    Chunk& out = chunks[ci];
    std::vector<Walk> walks;
    std::vector<std::pair<int, int>> stack;
    for (int p = ci * kChunk; p < std::min(npair, (ci + 1) * kChunk); ++p) {
      const auto [ba, bb] = pairs[p];
      const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
      PairSurfaces& ps = psurf[p];
      ps.na = opened_surfaces(m, st, s, ba, bb, ps.a);
      ps.nb = opened_surfaces(m, st, s, bb, ba, ps.b);
      walks.clear();
      walks.push_back({p, m.body_root[ba], m.body_root[bb], Filter{-1, ps.a, ps.na}, Filter{-1, ps.b, ps.nb}});
      // The cells each surface takes are marked only for the one reader, permanent_pair_energy().
      const bool marks = mixed_permanent_pair(ba, bb);
      if (marks) ps.near_cell.resize(ps.na + ps.nb);
      for (int i = 0; i < ps.na; ++i) {
        if (marks) ps.near_cell[i].assign(m.body_cell_begin[bb + 1] - m.body_cell_begin[bb], 0);
        split(out, walks, p, ps.a[i], ba, bb, true, Filter{}, marks ? &ps.near_cell[i] : nullptr);
      }
      for (int i = 0; i < ps.nb; ++i) {
        if (marks) ps.near_cell[ps.na + i].assign(m.body_cell_begin[ba + 1] - m.body_cell_begin[ba], 0);
        split(out, walks, p, ps.b[i], bb, ba, false, Filter{-1, ps.a, ps.na}, marks ? &ps.near_cell[ps.na + i] : nullptr);
      }
      for (std::size_t w = 0; w < walks.size(); ++w) {
        const Walk& wk = walks[w];
        const int wid = static_cast<int>(out.walks.size());
        out.walks.push_back(wk);
        stack.clear();
        stack.emplace_back(wk.na, wk.nb);
        while (!stack.empty()) {
          const auto [na, nb] = stack.back();
          stack.pop_back();
          if (!s.total.node_active[na] || !s.total.node_active[nb]) continue;
          const int pa = wk.fa.node(m, na), pb = wk.fb.node(m, nb);
          if (pa == 0 || pb == 0) continue;  // no cell on one side is this walk's
          const bool mixed = pa < 0 || pb < 0;
          const double d = (delta + s.node_offset[na] - s.node_offset[nb]).norm();
          const double ra = m.node_radius[na], rb = m.node_radius[nb];
          const double gap = d - ra - rb;  // lower bound on (centre distance - reaches) of any cell pair
          const double near_margin = st.near_field * (m.node_reach[na] + m.node_reach[nb]);
          // Far: small enough seen from each other, and moments that act as one dipole each.
          const bool soft_pair = m.node_induced[na] || m.node_induced[nb];
          const double theta = soft_pair ? kInducedTheta * st.theta : st.theta;
          if (!mixed && ra + rb < theta * d && (!soft_pair || std::max(ra, rb) < kSoftSourceTheta * theta * d) &&
              gap > near_margin &&
              (s.total.spread.empty() || spread_ok(s.total.spread[na], s.total.spread[nb], theta, d))) {
            out.list.push_back({p, na, nb, kFar, wid});
            continue;
          }
          const int ca = m.node_child[na], cb = m.node_child[nb];
          // A node that the filter splits is opened first.
          const bool open_a = ca >= 0 && (pa < 0 || cb < 0 || (pb > 0 && ra >= rb));
          if (ca < 0 && cb < 0) {
            unsigned char kind = kBlock;
            if (gap < 0.0) kind |= kBlockClamp;
            if (st.near_field > 0.0 && gap < near_margin) kind |= kBlockNear;
            if (mixed) kind |= kBlockMixed;
            out.list.push_back({p, na, nb, kind, wid});
          } else if (open_a) {
            for (int k = ca + m.node_nchild[na] - 1; k >= ca; --k) stack.emplace_back(k, nb);
          } else {
            for (int k = cb + m.node_nchild[nb] - 1; k >= cb; --k) stack.emplace_back(na, k);
          }
        }
      }
    }
  });
  for (Chunk& c : chunks) {
    const int offset = static_cast<int>(all_walks.size());
    all_walks.insert(all_walks.end(), c.walks.begin(), c.walks.end());
    for (Interaction& it : c.list) {
      if (!(it.kind & (kSurfaceOnA | kSurfaceOnB))) it.walk += offset;
    }
    list.insert(list.end(), c.list.begin(), c.list.end());
  }

  // Evaluate every interaction into its own slot (parallel), then sum in list order.
  std::vector<PairResult> out(list.size());
  parallel_for_each(static_cast<int>(list.size()), 8, [&](int q) {
    const Interaction& it = list[q];
    const auto [ba, bb] = pairs[it.pair];
    const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
    PairResult& r = out[q];
    if (it.kind & (kSurfaceOnA | kSurfaceOnB)) {
      const PairSurfaces& ps = psurf[it.pair];
      const int c0 = m.node_begin[it.b], c1 = m.node_end[it.b];
      if (it.kind & kSurfaceOnA) {
        r.surface_pairs = surface_on_cells(m, s, it.a, ba, c0, c1, Filter{-1, ps.a, ps.na}, r);
      } else {
        // Computed on body b, then as the reaction on a: F_a = -F_b, tau_a = -tau_b + delta x F_b.
        PairResult on_b;
        r.surface_pairs = surface_on_cells(m, s, it.a, bb, c0, c1, Filter{}, on_b);
        r.force = -on_b.force;
        r.torque = -on_b.torque + delta.cross(on_b.force);
        r.energy = on_b.energy;
        r.permanent_energy = on_b.permanent_energy;
      }
      return;
    }
    if (it.kind & kBlockMixed) {
      const Walk& wk = all_walks[it.walk];
      mixed_block(m, st, s, m.node_begin[it.a], m.node_end[it.a], m.node_begin[it.b], m.node_end[it.b], delta, wk.fa,
                  wk.fb, (it.kind & kBlockNear) != 0, r);
      return;
    }
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
    t.permanent_energy += out[q].permanent_energy;
    t.near_pairs += out[q].near_pairs;
    t.surface_pairs += out[q].surface_pairs;
    if (list[q].kind == kFar) {
      ++res.stats.node_pairs;
    } else if (list[q].kind & (kSurfaceOnA | kSurfaceOnB)) {
      res.stats.surface_pairs += out[q].surface_pairs;
    } else {
      res.stats.cell_pairs += std::int64_t(m.node_end[list[q].a] - m.node_begin[list[q].a]) *
                              (m.node_end[list[q].b] - m.node_begin[list[q].b]);
    }
  }
  // Apply each pair to both bodies: F_b = -F_a, tau_b = -tau_a - (R_a - R_b) x F_a.
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [ba, bb] = pairs[p];
    const Vec3 delta = s.body_pose[ba].position - s.body_pose[bb].position;
    res.force[ba] += sum[p].force;
    res.torque[ba] += sum[p].torque;
    res.force[bb] -= sum[p].force;
    res.torque[bb] -= sum[p].torque + delta.cross(sum[p].force);
    // Energy (see mixed_permanent_pair).
    if (!induced_on || (!m.body_induced[ba] && !m.body_induced[bb])) {
      res.energy += sum[p].energy;
    } else if (mixed_permanent_pair(ba, bb)) {
      res.energy += permanent_pair_energy(m, s, ba, bb, psurf[p]) + sum[p].permanent_energy;
    }
    res.stats.near_pairs += sum[p].near_pairs;
  }
}

}  // namespace

void accumulate_forces(const Model& m, const Settings& st, const State& s, Result& res) {
  // Fixed bodies (State::body_fixed) that are purely permanent: their mutual forces change only
  // when one of them is moved (a kinematic body's keys), so they come from State::fixed_pairs,
  // recomputed when any of their poses or the force settings differ from the cached ones.
  std::vector<std::uint8_t> frozen(m.body_count, 0);
  int nfrozen = 0;
  for (int b = 0; b < m.body_count; ++b) {
    frozen[b] = b < static_cast<int>(s.body_fixed.size()) && s.body_fixed[b] && m.body_root[b] >= 0 &&
                !m.body_induced[b];
    nfrozen += frozen[b];
  }
  if (nfrozen < 2) {
    body_forces(m, st, s, &s.body_tree, nullptr, res);
    return;
  }
  BodyTree moving, fixed;
  moving.build(m, s, [&](int b) { return !frozen[b]; });
  fixed.build(m, s, [&](int b) { return frozen[b] != 0; });
  State::FixedPairs& cache = s.fixed_pairs;
  std::vector<Pose> poses;
  for (int b = 0; b < m.body_count; ++b) {
    if (frozen[b]) poses.push_back(s.body_pose[b]);
  }
  const bool same_poses = cache.frozen == frozen && cache.poses.size() == poses.size() &&
                          std::equal(poses.begin(), poses.end(), cache.poses.begin(), [](const Pose& x, const Pose& y) {
                            return x.position == y.position && x.rotation.coeffs() == y.rotation.coeffs();
                          });
  const bool same_settings = cache.theta == st.theta && cache.near_field == st.near_field &&
                             cache.near_field_order == st.near_field_order && cache.precision == st.precision &&
                             cache.body_groups == st.body_groups;
  if (!cache.valid || !same_poses || !same_settings) {
    Result own;
    own.force.assign(m.body_count, Vec3::Zero());
    own.torque.assign(m.body_count, Vec3::Zero());
    body_forces(m, st, s, &fixed, nullptr, own);
    res.stats.body_pairs += own.stats.body_pairs;  // work of this evaluation
    res.stats.node_pairs += own.stats.node_pairs;
    res.stats.cell_pairs += own.stats.cell_pairs;
    cache = State::FixedPairs{true,     frozen,     poses,     st.theta,   st.near_field, st.near_field_order,
                              st.precision, st.body_groups, own.force, own.torque, own.energy,  own.stats.near_pairs};
  }
  for (int b = 0; b < m.body_count; ++b) {
    if (!frozen[b]) continue;
    res.force[b] += cache.force[b];
    res.torque[b] += cache.torque[b];
  }
  res.energy += cache.energy;
  res.stats.near_pairs += cache.near_pairs;
  body_forces(m, st, s, &moving, nullptr, res);
  body_forces(m, st, s, &moving, &fixed, res);
}

}  // namespace magbake::magnetics
