#include "system.h"

#include <algorithm>

#include "forces.h"
#include "induction.h"
#include "parallel.h"

namespace magbake::magnetics {

void State::resize(const Model& m) {
  if (body_pose.size() != static_cast<std::size_t>(m.body_count)) body_pose.resize(m.body_count);
  const std::size_t nc = m.cell_count(), nn = m.node_count();
  cell_offset.resize(nc);
  node_offset.resize(nn);
  for (Sources* src : {&total, &permanent, &induced}) {
    src->cell.assign(nc, Vec3::Zero());
    src->node.assign(nn, Vec3::Zero());
    src->node_active.assign(nn, 0);
  }
  body_rotation.resize(m.body_count);
  part_rotation.resize(m.part_body.size());
  for (auto* v : {&fx, &fy, &fz, &fmx, &fmy, &fmz, &fclamp}) v->resize(nc);
  for (std::size_t c = 0; c < nc; ++c) fclamp[c] = static_cast<float>(m.cell_clamp[c]);
  if (induced_moment.size() != m.induced_cells.size()) induced_moment.assign(m.induced_cells.size(), Vec3::Zero());
  induced_targets = Targets{};
}

namespace {
// World geometry and permanent moments of every cell and node.
void update_geometry(const Model& m, State& s) {
  // A soft sphere's cells stay aligned with the world as it turns (Model::body_isotropic): its
  // field, forces and energy then do not depend on its orientation at all, as the sphere's own
  // do not, which its zero torque assumes. Turned with the body, the cells' staircase made the
  // force on a rolling steel ball change with its angle while no torque did work for it: a ball
  // rattling against a magnet gained 20 mJ in 0.3 s (physics.md §8).
  for (int b = 0; b < m.body_count; ++b) {
    const bool world_aligned = b < static_cast<int>(m.body_isotropic.size()) && m.body_isotropic[b];
    s.body_rotation[b] = world_aligned ? Mat3::Identity() : s.body_pose[b].rotation.normalized().toRotationMatrix();
  }
  for (std::size_t p = 0; p < m.part_body.size(); ++p) s.part_rotation[p] = s.body_rotation[m.part_body[p]] * m.part_rotation[p];
  parallel_for_each(m.cell_count(), 4096, [&](int c) {
    const Mat3& R = s.body_rotation[m.cell_body[c]];
    s.cell_offset[c] = R * m.cell_position[c];
    s.permanent.cell[c] = R * m.cell_moment[c];
  });
  for (int n = 0; n < m.node_count(); ++n) s.node_offset[n] = s.body_rotation[m.node_body[n]] * m.node_center[n];
  s.body_tree.build(m, s);
  s.permanent.aggregate(m, s.cell_offset, s.node_offset);
}
}  // namespace

void place(const Model& m, State& s, const std::vector<Vec3>& induced) {
  if (m.empty()) return;
  if (s.cell_offset.size() != static_cast<std::size_t>(m.cell_count())) s.resize(m);
  update_geometry(m, s);
  s.total.cell = s.permanent.cell;
  if (induced.size() == m.induced_cells.size()) {
    s.induced_moment = induced;
    for (std::size_t q = 0; q < m.induced_cells.size(); ++q) s.total.cell[m.induced_cells[q]] += induced[q];
  }
  s.total.aggregate(m, s.cell_offset, s.node_offset);
}

void evaluate(const Model& m, const Settings& st, State& s, Result& res) {
  res.force.assign(m.body_count, Vec3::Zero());
  res.torque.assign(m.body_count, Vec3::Zero());
  res.moment.assign(m.body_count, Vec3::Zero());
  res.energy = 0.0;
  res.induction = InductionReport{};
  res.stats = EvalStats{};
  if (m.empty()) return;
  if (s.cell_offset.size() != static_cast<std::size_t>(m.cell_count()) ||
      s.node_offset.size() != static_cast<std::size_t>(m.node_count())) {
    s.resize(m);
  }

  // 1. World geometry and permanent moments.
  update_geometry(m, s);

  // 2. Induced moments (only when the scene has induced cells).
  s.total.cell = s.permanent.cell;
  if (m.has_induced() && st.induction != InductionMode::kOff) {
    if (s.induced_targets.position.empty()) {
      s.induced_targets = Targets::from_induced_cells(m, s);
    } else {
      s.induced_targets.update_induced_positions(m, s);
    }
    res.induction = solve_induction(m, st, s, res.stats);
    res.energy += res.induction.energy;
    for (std::size_t q = 0; q < m.induced_cells.size(); ++q) s.total.cell[m.induced_cells[q]] += s.induced_moment[q];
  }
  s.total.aggregate(m, s.cell_offset, s.node_offset);

  // 3. Single-precision copies for the block kernels.
  parallel_for_each(m.cell_count(), 4096, [&](int c) {
    s.fx[c] = float(s.cell_offset[c][0]), s.fy[c] = float(s.cell_offset[c][1]), s.fz[c] = float(s.cell_offset[c][2]);
    const Vec3& mc = s.total.cell[c];
    s.fmx[c] = float(mc[0]), s.fmy[c] = float(mc[1]), s.fmz[c] = float(mc[2]);
  });

  // 4. Body pairs.
  accumulate_forces(m, st, s, res);

  // 5. Total moments and the applied field (torque; energy -m.B for permanent moments, the
  //    induced ones' share is in the induction energy).
  for (int b = 0; b < m.body_count; ++b) {
    const int root = m.body_root[b];
    if (root < 0) continue;
    res.moment[b] = s.total.node[root];
    if (st.external_field.squaredNorm() > 0.0) {
      const Vec3 perm = s.permanent.node[root];
      res.torque[b] += res.moment[b].cross(st.external_field);
      res.energy -= perm.dot(st.external_field);
    }
    // A soft sphere's energy does not change as it turns, so its torque is exactly zero; the
    // cells' staircase (one cube for a small ball) would otherwise spin it up (physics.md §8).
    if (b < static_cast<int>(m.body_isotropic.size()) && m.body_isotropic[b]) res.torque[b].setZero();
  }
}

std::vector<Vec3> field_at_points(const Model& m, const Settings& st, const State& s, std::span<const Vec3> points,
                                  EvalStats* stats) {
  std::vector<Vec3> out(points.size(), st.external_field);
  if (m.empty() || points.empty()) return out;
  const Targets t = Targets::from_points(points);
  std::vector<Vec3> B(points.size());
  // The same field as the field volumes: exact surfaces of permanent parts, and inside a cell's
  // cuboid its smeared moment (bounded inside material, where a point dipole is singular).
  FieldOptions opt{st.theta, st.near_field};
  opt.smear_inside = true;
  opt.surfaces = true;
  const std::int64_t work = field_at_targets(m, s, s.total, t, opt, B);
  if (stats) stats->field_pairs += work;
  for (std::size_t q = 0; q < B.size(); ++q) out[t.original[q]] += B[q];
  return out;
}

}  // namespace magbake::magnetics
