// Cell decomposition (paper §4.2) and the per-body hierarchy.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>

#include "induction_model.h"
#include "model.h"
#include "parallel.h"

namespace magbake::magnetics {
namespace {

// Cells of one part before they are merged into the model (part frame).
struct PartCells {
  std::vector<Vec3> center;    // lattice site (cuboid centre), part frame, m
  std::vector<Vec3> centroid;  // centroid of the material inside the cell, part frame, m
  std::vector<double> volume;  // m³ (cuboid volume x inside fraction)
  std::vector<std::uint8_t> full;
  std::vector<Vec3> cell_half;  // half-edges of each cell, part frame, m (finer where graded)
  Vec3 half = Vec3::Zero();     // half-edges of the part's base lattice, m
};

// Decomposes one solid into grid cells of edge <= cell_size. Boundary cells keep the inside
// fraction of their volume and the centroid of that inside part (both from sub-samples); the
// cuboid of every cell stays on the lattice, so neighbouring cuboids never overlap.
// `levels` > 0 grades the cells towards the surface (BuildSettings::grading).
PartCells decompose(const Solid& solid, double cell_size, const BuildSettings& s, std::int64_t budget, int levels) {
  const Box3 box = solid.bounds();
  const Vec3 size = box.sizes();
  // Cell counts in floating point first: a cell size far below the part's size must give a clear
  // error, not an integer overflow (which once wrapped to "one cell").
  double counts[3], product = 1;
  for (int a = 0; a < 3; ++a) {
    counts[a] = std::max(1.0, std::ceil(size[a] / cell_size - 1e-9));
    product *= counts[a];
  }
  if (!(product <= double(budget))) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", product);
    throw std::runtime_error(std::string("magnetics: a part needs ") + buf + " grid cells, more than the limit of " +
                             std::to_string(budget) + "; raise magnetics.cell_size");
  }
  const Eigen::Vector3i n(static_cast<int>(counts[0]), static_cast<int>(counts[1]), static_cast<int>(counts[2]));
  const std::int64_t total = std::int64_t(n[0]) * n[1] * n[2];
  const Vec3 e = size.cwiseQuotient(n.cast<double>());
  const double cell_volume = e.prod();
  const Vec3 lo = box.min();

  std::vector<double> frac(total, 0.0);
  std::vector<Vec3> cen(total, Vec3::Zero());
  std::vector<std::uint8_t> full(total, 0);
  const int ss = std::max(1, s.subsamples);

  auto grid_point = [&](int i, int j, int k) {  // exact lattice corner
    return Vec3(lo[0] + i * e[0], lo[1] + j * e[1], lo[2] + k * e[2]);
  };
  auto classify = [&](bool force_subsample) {
    parallel_for_each(n[2], 1, [&](int k) {
      for (int j = 0; j < n[1]; ++j) {
        for (int i = 0; i < n[0]; ++i) {
          const std::int64_t id = (std::int64_t(k) * n[1] + j) * n[0] + i;
          const Vec3 c = grid_point(i, j, k) + 0.5 * e;
          if (solid.is_box()) {
            frac[id] = 1.0, cen[id] = c, full[id] = 1;
            continue;
          }
          int inside = solid.contains(c) ? 1 : 0;
          for (int q = 0; q < 8; ++q) {
            inside += solid.contains(grid_point(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1)));
          }
          if (inside == 9) {
            frac[id] = 1.0, cen[id] = c, full[id] = 1;
            continue;
          }
          if (inside == 0 && !force_subsample) continue;
          // Boundary cell: inside fraction and centroid from ss³ sub-samples.
          int count = 0;
          Vec3 sum = Vec3::Zero();
          for (int c2 = 0; c2 < ss; ++c2) {
            for (int b2 = 0; b2 < ss; ++b2) {
              for (int a2 = 0; a2 < ss; ++a2) {
                const Vec3 p = grid_point(i, j, k) +
                               Vec3((a2 + 0.5) / ss * e[0], (b2 + 0.5) / ss * e[1], (c2 + 0.5) / ss * e[2]);
                if (solid.contains(p)) ++count, sum += p;
              }
            }
          }
          if (count > 0) {
            frac[id] = double(count) / (ss * ss * ss);
            cen[id] = sum / count;
          }
        }
      }
    });
  };
  classify(false);
  const double grid_volume = cell_volume * std::accumulate(frac.begin(), frac.end(), 0.0);
  if (grid_volume < 0.5 * solid.volume()) {
    // Features thinner than a cell slipped between the corner samples: sample every cell.
    classify(true);
  }

  PartCells out;
  out.half = 0.5 * e;
  auto emit = [&](const Vec3& center, const Vec3& centroid, double volume, bool is_full, const Vec3& half) {
    // Checked as cells are made: grading multiplies the surface cells by about 4 per level.
    if (static_cast<std::int64_t>(out.center.size()) >= budget) {
      throw std::runtime_error("magnetics: a graded part needs more than the limit of " + std::to_string(budget) +
                               " cells; raise magnetics.cell_size or lower magnetics.grading");
    }
    out.center.push_back(center);
    out.centroid.push_back(centroid);
    out.volume.push_back(volume);
    out.full.push_back(is_full);
    out.cell_half.push_back(half);
  };
  // A cell is graded when it lies at the surface: partly inside, or with the centre of a
  // face-neighbour of its own size outside the solid on at least `grading_faces` axes.
  const int faces = std::max(1, s.grading_faces);
  auto at_surface = [&](const Vec3& c, const Vec3& edge, bool is_full) {
    if (!is_full) return true;
    int exposed = 0;
    for (int a = 0; a < 3; ++a) {
      Vec3 d = Vec3::Zero();
      d[a] = edge[a];
      if (!solid.contains(c + d) || !solid.contains(c - d)) ++exposed;
    }
    return exposed >= faces;
  };
  // Splits a graded cell (lower corner lo, edges edge) into 8 and recurses; children of a full
  // cell are full, the others are classified like the base lattice.
  std::function<void(const Vec3&, const Vec3&, int, bool)> refine = [&](const Vec3& lo, const Vec3& edge, int level,
                                                                        bool parent_full) {
    const Vec3 ce = 0.5 * edge;
    for (int q = 0; q < 8; ++q) {
      const Vec3 clo = lo + Vec3((q & 1) * ce[0], ((q >> 1) & 1) * ce[1], ((q >> 2) & 1) * ce[2]);
      const Vec3 c = clo + 0.5 * ce;
      double f = 1.0;
      Vec3 centroid = c;
      bool is_full = parent_full;
      if (!parent_full) {
        int inside = solid.contains(c) ? 1 : 0;
        for (int k = 0; k < 8; ++k) inside += solid.contains(clo + Vec3((k & 1) * ce[0], ((k >> 1) & 1) * ce[1], ((k >> 2) & 1) * ce[2]));
        is_full = inside == 9;
        if (!is_full) {
          int count = 0;
          Vec3 sum = Vec3::Zero();
          for (int c2 = 0; c2 < ss; ++c2) {
            for (int b2 = 0; b2 < ss; ++b2) {
              for (int a2 = 0; a2 < ss; ++a2) {
                const Vec3 p = clo + Vec3((a2 + 0.5) / ss * ce[0], (b2 + 0.5) / ss * ce[1], (c2 + 0.5) / ss * ce[2]);
                if (solid.contains(p)) ++count, sum += p;
              }
            }
          }
          if (count == 0) continue;
          f = double(count) / (ss * ss * ss);
          centroid = sum / count;
        }
      }
      if (level < levels && at_surface(c, ce, is_full)) {
        refine(clo, ce, level + 1, is_full);
      } else {
        emit(c, centroid, f * ce.prod(), is_full, 0.5 * ce);
      }
    }
  };
  for (std::int64_t id = 0; id < total; ++id) {
    if (frac[id] <= 0.0) continue;
    const int i = static_cast<int>(id % n[0]), j = static_cast<int>((id / n[0]) % n[1]),
              k = static_cast<int>(id / (std::int64_t(n[0]) * n[1]));
    const Vec3 c = grid_point(i, j, k) + 0.5 * e;
    if (levels > 0 && at_surface(c, e, full[id])) {
      refine(grid_point(i, j, k), e, 1, full[id]);
    } else {
      emit(c, cen[id], frac[id] * cell_volume, full[id], out.half);
    }
  }
  return out;
}

// One body's cells in body frame, before hierarchy ordering.
struct BodyCells {
  std::vector<Vec3> pos, center, mom, half;
  std::vector<double> vol, chi, reach, clamp;
  std::vector<int> part;
  std::vector<std::uint8_t> full, ball;
};

// Recursive bisection of cells [begin, end) of `perm` along the longest axis (paper §4.2).
struct TreeBuilder {
  const BodyCells& bc;
  int leaf_size;
  std::vector<int>& perm;
  Model& m;
  int body;

  int new_node() {
    m.node_begin.push_back(0);
    m.node_end.push_back(0);
    m.node_child.push_back(-1);
    m.node_nchild.push_back(0);
    m.node_body.push_back(body);
    m.node_center.push_back(Vec3::Zero());
    m.node_radius.push_back(0);
    m.node_reach.push_back(0);
    m.node_moment.push_back(Vec3::Zero());
    m.node_induced.push_back(0);
    m.node_part.push_back(-1);
    return m.node_count() - 1;
  }

  void build(int node, int begin, int end) {
    m.node_begin[node] = begin;
    m.node_end[node] = end;
    // Node aggregates: volume centroid, summed permanent moment, bounding radius.
    double v = 0;
    Vec3 c = Vec3::Zero(), mom = Vec3::Zero();
    double rmax = 0;
    bool induced = false;
    int part = begin < end ? bc.part[perm[begin]] : -1;
    Box3 bb;
    for (int q = begin; q < end; ++q) {
      const int id = perm[q];
      if (bc.part[id] != part) part = -1;
      v += bc.vol[id];
      c += bc.vol[id] * bc.pos[id];
      mom += bc.mom[id];
      rmax = std::max(rmax, bc.reach[id]);
      induced = induced || bc.chi[id] != 0.0;
      bb.extend(bc.pos[id]);
    }
    c /= v;
    double radius = 0;
    for (int q = begin; q < end; ++q) {
      const int id = perm[q];
      radius = std::max({radius, (bc.pos[id] - c).norm() + bc.reach[id], (bc.center[id] - c).norm() + bc.reach[id]});
    }
    m.node_center[node] = c;
    m.node_radius[node] = radius;
    m.node_reach[node] = rmax;
    m.node_moment[node] = mom;
    m.node_induced[node] = induced;
    m.node_part[node] = part;
    if (end - begin <= leaf_size) return;

    // Bisect at the middle along every axis at least 0.6 times the longest one (up to 8
    // children, like an octree): nodes stay near-cubic, and a near-cubic uniformly magnetized
    // node is a dipole up to fourth order, where a slab or rod from a single bisection is not.
    const Vec3 size = bb.sizes();
    const Vec3 mid = bb.center();
    std::vector<std::pair<int, int>> ranges{{begin, end}};
    for (int axis = 0; axis < 3; ++axis) {
      if (size[axis] < 0.6 * size.maxCoeff() || size[axis] <= 0.0) continue;
      std::vector<std::pair<int, int>> next;
      for (auto [b0, e0] : ranges) {
        auto first = perm.begin() + b0, last = perm.begin() + e0;
        auto split = std::stable_partition(first, last, [&](int id) { return bc.pos[id][axis] < mid[axis]; });
        const int cut = static_cast<int>(split - perm.begin());
        if (cut > b0) next.emplace_back(b0, cut);
        if (cut < e0) next.emplace_back(cut, e0);
      }
      ranges.swap(next);
    }
    if (ranges.size() < 2) {
      // All centres on one side of every midpoint (degenerate): split at the median.
      int axis;
      size.maxCoeff(&axis);
      auto first = perm.begin() + begin, last = perm.begin() + end;
      auto split = first + (end - begin) / 2;
      std::nth_element(first, split, last, [&](int a, int b) {
        return bc.pos[a][axis] < bc.pos[b][axis] || (bc.pos[a][axis] == bc.pos[b][axis] && a < b);
      });
      const int cut = static_cast<int>(split - perm.begin());
      ranges = {{begin, cut}, {cut, end}};
    }
    const int first_child = m.node_count();
    for (std::size_t k = 0; k < ranges.size(); ++k) new_node();
    m.node_child[node] = first_child;
    m.node_nchild[node] = static_cast<int>(ranges.size());
    for (std::size_t k = 0; k < ranges.size(); ++k) build(first_child + static_cast<int>(k), ranges[k].first, ranges[k].second);
  }
};

// Copies the parts' surfaces into the model with each triangle's charge density and a bounding
// sphere per part, and lists the parts with a surface by body.
void set_surfaces(Model& m, const PartTable& parts) {
  const int np = static_cast<int>(parts.body.size());
  if (parts.surface_begin.empty() || parts.surface_begin.back() == 0) return;
  assert(static_cast<int>(parts.surface_begin.size()) == np + 1);
  m.part_surface_begin = parts.surface_begin;
  m.surface_vertex = parts.surface_vertex;
  std::vector<double> sigma(parts.surface_begin.back());
  m.part_surface_center.assign(np, Vec3::Zero());
  m.part_surface_radius.assign(np, 0.0);
  m.part_surface_mesh.assign(np, SurfaceMesh{});
  for (int p = 0; p < np; ++p) {
    const int t0 = parts.surface_begin[p], t1 = parts.surface_begin[p + 1];
    if (t0 == t1) continue;
    Box3 bb;
    for (int t = t0; t < t1; ++t) {
      const Vec3 &a = m.surface_vertex[3 * t], &b = m.surface_vertex[3 * t + 1], &c = m.surface_vertex[3 * t + 2];
      sigma[t] = parts.magnetization[p].dot((b - a).cross(c - a).normalized());
      bb.extend(a), bb.extend(b), bb.extend(c);
    }
    const Vec3 c = bb.center();
    double r = 0;
    for (int k = 3 * t0; k < 3 * t1; ++k) r = std::max(r, (m.surface_vertex[k] - c).norm());
    m.part_surface_center[p] = c;
    m.part_surface_radius[p] = r;
    if (!m.part_surface_mesh[p].build(&m.surface_vertex[3 * t0], &sigma[t0], t1 - t0, parts.magnetization[p])) {
      throw std::runtime_error("magnetics: the surface of part " + std::to_string(p) + " is not closed");
    }
  }
  m.body_surface_begin.assign(m.body_count + 1, 0);
  for (int p = 0; p < np; ++p) {
    if (m.surface_triangles(p) > 0) ++m.body_surface_begin[parts.body[p] + 1];
  }
  for (int b = 0; b < m.body_count; ++b) m.body_surface_begin[b + 1] += m.body_surface_begin[b];
  m.body_surface_part.resize(m.body_surface_begin[m.body_count]);
  std::vector<int> fill(m.body_surface_begin.begin(), m.body_surface_begin.end() - 1);
  for (int p = 0; p < np; ++p) {
    if (m.surface_triangles(p) > 0) m.body_surface_part[fill[parts.body[p]]++] = p;
  }
}

}  // namespace

Model model_from_cells(int body_count, const CellTable& cells, const PartTable& parts, int leaf_size,
                       std::vector<int>* order) {
  if (order) order->clear();
  Model m;
  m.body_count = body_count;
  m.body_cell_begin.assign(body_count + 1, 0);
  m.body_root.assign(body_count, -1);
  m.body_permanent.assign(body_count, 0);
  m.body_induced.assign(body_count, 0);
  for (std::size_t p = 0; p < parts.body.size(); ++p) {
    m.part_body.push_back(parts.body[p]);
    m.part_pose.push_back(parts.pose[p]);
    m.part_rotation.push_back(parts.pose[p].rotation.toRotationMatrix());
    m.part_magnetization.push_back(parts.magnetization[p]);
    m.part_chi.push_back(parts.chi[p]);
    m.part_half.push_back(parts.half[p]);
    m.part_consistent.push_back(0);
    if (parts.magnetization[p].squaredNorm() > 0) m.body_permanent[parts.body[p]] = 1;
    if (parts.chi[p] != 0.0) m.body_induced[parts.body[p]] = 1;
  }
  set_surfaces(m, parts);
  // Cells of each body, in the given order, then the body's hierarchy.
  std::vector<std::vector<int>> of_body(body_count);
  for (std::size_t c = 0; c < cells.size(); ++c) of_body[cells.body[c]].push_back(static_cast<int>(c));
  for (int b = 0; b < body_count; ++b) {
    BodyCells bc;
    for (int c : of_body[b]) {
      bc.pos.push_back(cells.position[c]);
      bc.center.push_back(cells.center[c]);
      bc.mom.push_back(cells.moment[c]);
      bc.half.push_back(cells.half[c]);
      bc.vol.push_back(cells.volume[c]);
      bc.chi.push_back(cells.chi[c]);
      const bool ball = !cells.ball.empty() && cells.ball[c];
      // A ball cell reaches its radius. Its clamp is half the radius: another body's cells stay
      // outside the ball (distance >= radius), so the clamp only acts on deep overlaps, never on
      // the exact dipole field in contact (unless the other body's cells are coarser than the ball).
      bc.reach.push_back(ball ? cells.half[c][0] : cells.half[c].norm());
      bc.clamp.push_back(ball ? 0.5 * cells.half[c][0] : cells.half[c].minCoeff());
      bc.part.push_back(cells.part[c]);
      bc.full.push_back(ball ? 0 : cells.full[c]);
      bc.ball.push_back(ball);
    }
    const int begin = m.cell_count();
    m.body_cell_begin[b] = begin;
    if (!bc.pos.empty()) {
      std::vector<int> perm(bc.pos.size());
      std::iota(perm.begin(), perm.end(), 0);
      TreeBuilder tb{bc, std::max(1, leaf_size), perm, m, b};
      const int root = tb.new_node();
      m.body_root[b] = root;
      tb.build(root, 0, static_cast<int>(bc.pos.size()));
      // Node ranges are local to the body: shift them to global cell indices.
      for (int n = root; n < m.node_count(); ++n) {
        m.node_begin[n] += begin;
        m.node_end[n] += begin;
      }
      for (int id : perm) {
        if (order) order->push_back(of_body[b][id]);
        m.cell_position.push_back(bc.pos[id]);
        m.cell_center.push_back(bc.center[id]);
        m.cell_moment.push_back(bc.mom[id]);
        m.cell_volume.push_back(bc.vol[id]);
        m.cell_chi.push_back(bc.chi[id]);
        m.cell_half.push_back(bc.half[id]);
        m.cell_reach.push_back(bc.reach[id]);
        m.cell_clamp.push_back(bc.clamp[id]);
        m.cell_ball_radius.push_back(std::cbrt(3.0 * bc.vol[id] / (4.0 * std::numbers::pi)));
        m.cell_part.push_back(bc.part[id]);
        m.cell_body.push_back(b);
        m.cell_full.push_back(bc.full[id]);
        m.cell_ball.push_back(bc.ball[id]);
      }
    }
    m.body_cell_begin[b + 1] = m.cell_count();
  }
  for (int c = 0; c < m.cell_count(); ++c) {
    if (m.cell_chi[c] != 0.0) m.induced_cells.push_back(c);
  }
  m.cell_polarizability.assign(m.cell_count(), Mat3::Zero());
  m.near_begin.assign(m.induced_cells.size() + 1, 0);
  return m;
}

void model_tables(const Model& m, CellTable& cells, PartTable& parts) {
  cells = CellTable{};
  parts = PartTable{};
  for (int c = 0; c < m.cell_count(); ++c) {
    cells.body.push_back(m.cell_body[c]);
    cells.part.push_back(m.cell_part[c]);
    cells.position.push_back(m.cell_position[c]);
    cells.center.push_back(m.cell_center[c]);
    cells.half.push_back(m.cell_half[c]);
    cells.moment.push_back(m.cell_moment[c]);
    cells.volume.push_back(m.cell_volume[c]);
    cells.chi.push_back(m.cell_chi[c]);
    cells.full.push_back(m.cell_full[c]);
    cells.ball.push_back(m.cell_ball[c]);
  }
  parts.body = m.part_body;
  parts.pose = m.part_pose;
  parts.magnetization = m.part_magnetization;
  parts.half = m.part_half;
  parts.chi = m.part_chi;
  if (m.has_surfaces()) {
    parts.surface_begin = m.part_surface_begin;
    parts.surface_vertex = m.surface_vertex;
  }
}

Model build_model(const std::vector<BodySpec>& bodies, const BuildSettings& settings) {
  CellTable cells;
  PartTable parts;
  std::vector<const Solid*> part_solid;
  std::vector<double> part_saturation;  // M_s, A/m
  std::vector<PartReport> reports;
  std::int64_t budget = settings.max_cells;
  parts.surface_begin.push_back(0);
  for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
    for (const PartSpec& ps : bodies[b].parts) {
      if (ps.material.kind == MaterialKind::kNone) continue;
      assert(ps.solid != nullptr);
      const int pid = static_cast<int>(parts.body.size());
      const Mat3 R = ps.part_to_body.rotation.toRotationMatrix();
      const Vec3 M = R * ps.material.magnetization();
      const double chi = ps.material.induced() ? ps.material.susceptibility() : 0.0;
      const double cell = ps.cell_size > 0 ? ps.cell_size : settings.cell_size;
      if (!(cell > 0)) throw std::runtime_error("magnetics: cell_size must be positive");
      double radius = 0;
      const bool ball = settings.exact_balls && chi == 0.0 && M.squaredNorm() > 0 && ps.solid->ball(radius);
      PartCells pc;
      if (ball) {
        // A permanent ball: one exact cell at its centre (BuildSettings::exact_balls).
        if (budget < 1) {
          throw std::runtime_error("magnetics: the model would exceed " + std::to_string(settings.max_cells) +
                                   " cells; raise magnetics.cell_size");
        }
        pc.center = pc.centroid = {Vec3::Zero()};
        pc.volume = {ps.solid->volume()};
        pc.full = {0};
        pc.half = Vec3::Constant(radius);
        pc.cell_half = {pc.half};
      } else {
        pc = decompose(*ps.solid, cell, settings, budget, chi != 0.0 ? settings.grading : 0);
      }
      if (pc.centroid.empty()) {
        throw std::runtime_error("magnetics: body " + std::to_string(b) +
                                 " has a part with no cell inside it; lower magnetics.cell_size");
      }
      budget -= static_cast<std::int64_t>(pc.centroid.size());
      PartReport rep;
      rep.body = b;
      rep.cells = static_cast<int>(pc.centroid.size());
      rep.grid_volume = std::accumulate(pc.volume.begin(), pc.volume.end(), 0.0);
      rep.true_volume = ps.solid->volume();
      rep.rescale = rep.true_volume / rep.grid_volume;
      for (std::size_t q = 0; q < pc.centroid.size(); ++q) {
        const double v = pc.volume[q] * rep.rescale;
        cells.body.push_back(b);
        cells.part.push_back(pid);
        cells.position.push_back(ps.part_to_body.apply(pc.centroid[q]));
        cells.center.push_back(ps.part_to_body.apply(pc.center[q]));
        cells.half.push_back(pc.cell_half[q]);
        cells.moment.push_back(M * v);
        cells.volume.push_back(v);
        cells.chi.push_back(chi);
        cells.full.push_back(pc.full[q]);
        cells.ball.push_back(ball);
        rep.full_cells += pc.full[q];
      }
      parts.body.push_back(b);
      parts.pose.push_back(ps.part_to_body);
      parts.magnetization.push_back(M);
      parts.half.push_back(pc.half);
      parts.chi.push_back(chi);
      // The exact surface of a permanent part that its cells do not fit (physics.md §12).
      if (settings.surface_tolerance > 0 && !ball && chi == 0.0 && M.squaredNorm() > 0 && rep.full_cells < rep.cells) {
        std::vector<Vec3> v;
        std::vector<Eigen::Vector3i> tri;
        if (ps.solid->surface(settings.surface_tolerance, v, tri) && !tri.empty() &&
            static_cast<int>(tri.size()) <= settings.max_surface_triangles) {
          for (const auto& t : tri) {
            for (int k = 0; k < 3; ++k) parts.surface_vertex.push_back(ps.part_to_body.apply(v[t[k]]));
          }
        }
      }
      parts.surface_begin.push_back(static_cast<int>(parts.surface_vertex.size() / 3));
      reports.push_back(rep);
      part_solid.push_back(ps.solid);
      part_saturation.push_back(ps.material.kind == MaterialKind::kLinear && chi > 0 ? ps.material.saturation / kMu0 : 0.0);
    }
  }
  Model m = model_from_cells(static_cast<int>(bodies.size()), cells, parts, settings.leaf_size);
  m.part_report = reports;
  m.part_saturation = part_saturation;
  m.body_isotropic.assign(bodies.size(), 0);
  for (std::size_t b = 0; b < bodies.size(); ++b) m.body_isotropic[b] = bodies[b].isotropic && m.body_induced[b] && !m.body_permanent[b];
  build_induction_model(m, part_solid, settings);
  return m;
}

}  // namespace magbake::magnetics
