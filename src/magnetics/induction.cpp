#include "induction.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "cuboid.h"
#include "dipole.h"
#include "induction_model.h"
#include "parallel.h"

namespace magbake::magnetics {
namespace {

using Vector = Eigen::VectorXd;  // 3 x ntarget, target order

// Opening angle of the cell nodes of other bodies within their own radius of a target group, in
// the induction's field walk, in units of its theta (FieldOptions::other_body_theta; farther
// bodies, whole bodies and groups of bodies open as before). Where two soft bodies face each
// other across a small gap their magnetizations vary most, and a node's dipole at its centre
// misses that: two 5 mm chi-700 balls 0.5 mm apart (exact series, physics.md §10) were 7.5% short
// at default with the full angle and are 5.8% short at 0.7 (5.6% with every pair direct); at 14
// cells across 5.2% against 3.4% (1.8%); two touching balls at 0.833 mm cells 10.8 N against
// 17.4 N (18.5 N). 0.7 as the force walk's induced pairs (kInducedTheta in forces.cpp). Cost and
// measurements: bench/results/two_balls_2026-12-08.
constexpr double kOtherBodyTheta = 0.7;

// Newton iterations on a saturating magnetization law before the solve reports not converged.
constexpr int kMaxNewtonIterations = 40;

double dot(const Vector& a, const Vector& b) {
  double s = 0;  // serial, fixed order: bit-identical for any thread count
  for (Eigen::Index q = 0; q < a.size(); ++q) s += a[q] * b[q];
  return s;
}

// Krylov vectors the automatic GMRES restart may keep (Settings::induction_restart = 0).
constexpr double kKrylovBudgetBytes = 256.0 * 1024 * 1024;

// GMRES restart length for n induced cells: the setting, or when it is 0 as many vectors of 3n
// doubles as kKrylovBudgetBytes holds, within [50, induction_max_iterations]. BowlSpheres at
// `high` (19,340 cells) stalled with 50 at a residual of 2e-4 after 300 iterations and converges
// with 300 in 107 (bench/results/two_balls_2026-12-08).
int gmres_restart(const Settings& st, int n) {
  if (st.induction_restart > 0) return std::max(2, st.induction_restart);
  const double fits = kKrylovBudgetBytes / (3.0 * sizeof(double) * std::max(n, 1));
  return static_cast<int>(std::clamp(fits, 50.0, std::max(50.0, 1.0 * st.induction_max_iterations)));
}

// Clamp distance of cells t and j in the induction's coupling across bodies, m. A boundary cell
// is a point dipole at its material's centroid; taken as a ball of its material's volume, whose
// outside field is exactly its dipole's (and the mean of a field over a ball is its value at the
// centre), a pair of them is the exact mean field of one ball over the other while the balls are
// apart. The lattice clamp (half the smallest edge per cell) let two boundary cells that hold
// more than half of their cuboids come closer than their balls allow: at 14 cells across two
// touching steel balls then had a coupled mode with a gain near 1 (one cell at 1.3e10 A/m, 2.3e7
// N; in the paper's BowlSpheres at `high` 450 kN, physics.md §7). Two boundary cells are
// therefore clamped at the larger of the two distances; a pair with a full cell or an exact
// ball keeps the lattice clamp, as in the force kernels.
double cross_clamp(const Model& m, int t, int j) {
  const double lattice = m.cell_clamp[t] + m.cell_clamp[j];
  auto boundary = [&](int c) { return !m.cell_full[c] && !m.cell_ball[c]; };
  if (!boundary(t) || !boundary(j)) return lattice;
  return std::max(lattice, m.cell_ball_radius[t] + m.cell_ball_radius[j]);
}

// Correction (mean field - point dipole) for target cell t and a source cell j of another body,
// world frame: their cuboids are arbitrarily placed, so the mean field comes from quadrature.
Mat3 cross_body_tensor(const Model& m, const Settings& st, const State& s, int t, int j) {
  auto center = [&](int c) {
    const int b = m.cell_body[c];
    return Vec3(s.body_pose[b].position + s.body_rotation[b] * m.cell_center[c]);
  };
  const Cuboid ct{center(t), s.part_rotation[m.cell_part[t]], m.cell_half[t], Vec3::Zero()};
  const Cuboid cj{center(j), s.part_rotation[m.cell_part[j]], m.cell_half[j], Vec3::Zero()};
  const Vec3 r = s.body_pose[m.cell_body[t]].position + s.cell_offset[t] -
                 (s.body_pose[m.cell_body[j]].position + s.cell_offset[j]);
  if (!m.cell_full[t] || !m.cell_full[j]) {
    // A boundary cell is a point dipole at its material's centroid, clamped: its cuboid reaches
    // outside the body, and the cuboids of two touching bodies overlap, where their mean field
    // (the inside field, -M/3) made the pair's induction nearly singular (two steel balls in
    // contact got 1e8 A/m and 15 kN, physics.md §7). Two boundary cells are clamped where the
    // balls of their volumes would overlap (cross_clamp()).
    const double d_min = cross_clamp(m, t, j);
    const double d = r.norm();
    return d < d_min ? Mat3(dipole_tensor(r * (d_min / d)) - dipole_tensor(r)) : Mat3(Mat3::Zero());
  }
  // Order 3 (27 points) next to each other, 2 beyond: the integrand is smooth there.
  const double gap = (ct.center - cj.center).norm() / (m.cell_half[t].maxCoeff() + m.cell_half[j].maxCoeff());
  const int order = std::clamp(gap < 1.5 ? st.near_field_order - 1 : 2, 2, 3);
  return kMu0 * cuboid_mean_field_tensor(ct, cj, order) /
             (8.0 * m.cell_half[j].prod()) -
         dipole_tensor(r);
}

// Rows of near-field corrections for every induced target from cells of other bodies within the
// model's near radius (world frame). The rows inside a body are the model's own (body frame,
// fixed): add_body_near() applies them without rotating a tensor per substep.
void build_near_rows(const Model& m, const Settings& st, State& s) {
  const Targets& t = s.induced_targets;
  const int n = static_cast<int>(t.position.size());
  auto& rows = s.induced_near;
  rows.begin.assign(n + 1, 0);
  rows.cell.clear();
  rows.tensor.clear();
  if (m.induction_near <= 0.0) return;
  // Other bodies' candidate cells, by a tree walk per target group.
  std::vector<std::vector<int>> cross(n);
  const int ngroup = static_cast<int>(t.group_begin.size()) - 1;
  parallel_for_each(ngroup, 1, [&](int g) {
    double reach = 0;
    for (int q = t.group_begin[g]; q < t.group_begin[g + 1]; ++q) reach = std::max(reach, m.cell_reach[t.cell[q]]);
    const int own_body = m.cell_body[t.cell[t.group_begin[g]]];
    std::vector<int> stack, tree_stack(1, 0);
    const BodyTree& bt = s.body_tree;
    const double near_reach = m.induction_near * reach;
    // Bodies whose root spheres can hold a cell within the near radius, found by the hierarchy
    // over bodies; each then by its own cell hierarchy.
    while (!bt.empty() && !tree_stack.empty()) {
      const int tn = tree_stack.back();
      tree_stack.pop_back();
      const double tgap = (bt.center[tn] - t.group_center[g]).norm() - bt.radius[tn] - t.group_radius[g];
      if (tgap > m.induction_near * bt.reach[tn] + near_reach) continue;
      if (bt.child[tn] >= 0) {
        tree_stack.push_back(bt.child[tn] + 1);
        tree_stack.push_back(bt.child[tn]);
        continue;
      }
      const int body = bt.body[tn];
      if (body == own_body) continue;
      const Vec3 origin = s.body_pose[body].position;
      stack.assign(1, m.body_root[body]);
      while (!stack.empty()) {
        const int nd = stack.back();
        stack.pop_back();
        const double gap = (origin + s.node_offset[nd] - t.group_center[g]).norm() - m.node_radius[nd] - t.group_radius[g];
        if (gap > m.induction_near * (m.node_reach[nd] + reach)) continue;
        if (m.node_child[nd] >= 0) {
          for (int k = m.node_child[nd] + m.node_nchild[nd] - 1; k >= m.node_child[nd]; --k) stack.push_back(k);
          continue;
        }
        for (int q = t.group_begin[g]; q < t.group_begin[g + 1]; ++q) {
          const int tc = t.cell[q];
          for (int c = m.node_begin[nd]; c < m.node_end[nd]; ++c) {
            if (m.cell_chi[c] == 0.0 && m.cell_moment[c].squaredNorm() == 0.0) continue;
            // Full pairs get their cuboids' mean field within the near radius; a pair with a
            // boundary cell only its clamp (cross_body_tensor).
            const double lim = m.cell_full[tc] && m.cell_full[c]
                                   ? m.induction_near * (m.cell_half[tc].maxCoeff() + m.cell_half[c].maxCoeff())
                                   : cross_clamp(m, tc, c);
            if ((origin + s.cell_offset[c] - t.position[q]).squaredNorm() < lim * lim) cross[q].push_back(c);
          }
        }
      }
    }
  });
  for (int q = 0; q < n; ++q) rows.begin[q + 1] = rows.begin[q] + static_cast<int>(cross[q].size());
  rows.cell.resize(rows.begin[n]);
  rows.tensor.resize(rows.begin[n]);

  // Cross-body tensors are reused while the two bodies keep their relative pose to 2% of a cell
  // size and 0.02 rad: the tensors (themselves a few-percent correction) then change by about
  // that fraction. Resting contact costs one quadrature, not one per substep.
  auto relative = [&](int tb, int sb, Mat3& R, Vec3& off) {
    R = s.body_rotation[tb].transpose() * s.body_rotation[sb];
    off = s.body_rotation[tb].transpose() * (s.body_pose[sb].position - s.body_pose[tb].position);
  };
  std::map<std::pair<int, int>, bool> valid;
  for (int q = 0; q < n; ++q) {
    const int tb = m.cell_body[t.cell[q]];
    for (int c : cross[q]) {
      const auto key = std::make_pair(tb, m.cell_body[c]);
      if (valid.count(key)) continue;
      Mat3 R;
      Vec3 off;
      relative(key.first, key.second, R, off);
      auto it = s.cross_tensors.find(key);
      const double tol = 2e-2 * m.cell_half[c].minCoeff();
      const bool same = it != s.cross_tensors.end() && (it->second.offset - off).norm() <= tol &&
                        (it->second.rotation - R).norm() <= 2e-2;
      if (!same) s.cross_tensors[key] = State::PairTensors{R, off, {}};
      valid[key] = true;
    }
  }
  // Missing tensors: computed in parallel, then stored.
  std::vector<int> missing_q, missing_c;
  for (int q = 0; q < n; ++q) {
    const int tb = m.cell_body[t.cell[q]];
    for (int c : cross[q]) {
      const auto& pt = s.cross_tensors[{tb, m.cell_body[c]}];
      if (!pt.tensor.count(std::int64_t(t.cell[q]) * m.cell_count() + c)) missing_q.push_back(q), missing_c.push_back(c);
    }
  }
  std::vector<Mat3> computed(missing_q.size());
  parallel_for_each(static_cast<int>(missing_q.size()), 4, [&](int k) {
    const int tc = t.cell[missing_q[k]];
    const Mat3& Rt = s.body_rotation[m.cell_body[tc]];
    computed[k] = Rt.transpose() * cross_body_tensor(m, st, s, tc, missing_c[k]) * Rt;
  });
  for (std::size_t k = 0; k < missing_q.size(); ++k) {
    const int tc = t.cell[missing_q[k]];
    s.cross_tensors[{m.cell_body[tc], m.cell_body[missing_c[k]]}].tensor[std::int64_t(tc) * m.cell_count() + missing_c[k]] =
        computed[k];
  }
  parallel_for_each(n, 8, [&](int q) {
    const int tc = t.cell[q];
    const Mat3& R = s.body_rotation[m.cell_body[tc]];
    int e = rows.begin[q];
    for (int c : cross[q]) {
      const auto& pt = s.cross_tensors.at({m.cell_body[tc], m.cell_body[c]});
      rows.cell[e] = c;
      rows.tensor[e] = R * pt.tensor.at(std::int64_t(tc) * m.cell_count() + c) * R.transpose();
      ++e;
    }
  });
}

// Every cell's moment in its body's frame, local[c] = R_b^T world[c]: what the near rows inside
// a body (Model::near_tensor, body frame) multiply.
void to_body_frame(const Model& m, const State& s, const std::vector<Vec3>& world, std::vector<Vec3>& local) {
  local.resize(world.size());
  parallel_for_each(m.body_count, 16, [&](int b) {
    const Mat3 Rt = s.body_rotation[b].transpose();
    for (int c = m.body_cell_begin[b]; c < m.body_cell_begin[b + 1]; ++c) local[c] = Rt * world[c];
  });
}

// Near-field corrections inside the body of target q (rank r among the induced cells) from
// moments in body frames (to_body_frame()), added to the world-frame field Bq. Entries whose
// source part `skip` rejects are left out.
template <class Skip>
void add_body_near(const Model& m, const State& s, int q, const Targets& t, const std::vector<Vec3>& local,
                   Skip skip, Vec3& Bq) {
  const int r = t.original[q];
  Vec3 sum = Vec3::Zero();
  for (int k = m.near_begin[r]; k < m.near_begin[r + 1]; ++k) {
    const int c = m.near_cell[k];
    if (skip(m.cell_part[c])) continue;
    sum += m.near_tensor[k] * local[c];
  }
  Bq += s.body_rotation[m.cell_body[t.cell[q]]] * sum;
}

}  // namespace

InductionReport solve_induction(const Model& m, const Settings& st, State& s, EvalStats& stats) {
  InductionReport rep;
  const Targets& t = s.induced_targets;
  const int n = static_cast<int>(t.position.size());
  if (n == 0 || st.induction == InductionMode::kOff) {
    s.induced_moment.assign(m.induced_cells.size(), Vec3::Zero());
    return rep;
  }
  // Point dipoles (near pairs are corrected below), with at most theta 0.5: the solve needs an
  // operator close to the exact one (at theta 1 the tree error stalls GMRES). The cell nodes of
  // other induced bodies within their own radius of a target group open at kOtherBodyTheta of it.
  FieldOptions fopt{std::min(st.theta, 0.5), 0.0};
  fopt.other_body_theta = kOtherBodyTheta * fopt.theta;
  build_near_rows(m, st, s);
  const auto& rows = s.induced_near;

  // Polarizability of each target (world frame): m = alpha B_loc. Paper mode: the isotropic
  // small-sphere factor V 3chi/(3+chi) (physics-notes §4); coupled: the model's cell
  // polarizability, whose self-field makes uniform magnetization exact.
  std::vector<Mat3> alpha(n);
  for (int q = 0; q < n; ++q) {
    const int c = t.cell[q];
    if (st.induction == InductionMode::kPaper) {
      alpha[q] = Mat3::Identity() * (m.cell_volume[c] * effective_susceptibility(m.cell_chi[c]) / kMu0);
    } else {
      const Mat3& R = s.body_rotation[m.cell_body[c]];
      alpha[q] = R * m.cell_polarizability[c] * R.transpose() / kMu0;
    }
  }

  // Right-hand side: alpha (B_perm + B_applied), permanent near pairs as cuboids, and permanent
  // parts with an exact surface by their surface field where a target group would open them
  // (the same field as the forces' and the field volumes', physics.md §12); those parts' cells
  // then add no near correction at that group's targets.
  std::vector<Vec3> B(n);
  FieldOptions popt = fopt;
  popt.surfaces = true;
  popt.other_body_theta = 0.0;  // the magnets' field as the forces' and the field volumes' see it
  const FieldPlan pplan = plan_field(m, s, s.permanent, t, popt);
  stats.field_pairs += apply_field_plan(pplan, m, s, s.permanent, t, popt, B);
  Vector b(3 * n);
  std::vector<Vec3> B0(n);  // field of the fixed sources at each target
  std::vector<Vec3> local;  // moments in body frames (add_body_near())
  to_body_frame(m, s, s.permanent.cell, local);
  // Per target group in parallel: each writes only its own targets' B0 and b.
  parallel_for_each(static_cast<int>(t.group_begin.size()) - 1, 4, [&](int g) {
    const auto s0 = pplan.surface.begin() + pplan.surface_begin[g], s1 = pplan.surface.begin() + pplan.surface_end[g];
    auto skip = [&](int part) { return s0 != s1 && std::find(s0, s1, part) != s1; };
    for (int q = t.group_begin[g]; q < t.group_begin[g + 1]; ++q) {
      Vec3 Bq = B[q] + st.external_field;
      add_body_near(m, s, q, t, local, skip, Bq);
      for (int e = rows.begin[q]; e < rows.begin[q + 1]; ++e) {
        if (skip(m.cell_part[rows.cell[e]])) continue;
        Bq += rows.tensor[e] * s.permanent.cell[rows.cell[e]];
      }
      B0[q] = Bq;
      b.segment<3>(3 * q) = alpha[q] * Bq;
    }
  });

  auto store = [&](const Vector& x) {
    s.induced_moment.resize(m.induced_cells.size());
    rep.energy = 0.0;
    for (int q = 0; q < n; ++q) {
      s.induced_moment[t.original[q]] = x.segment<3>(3 * q);
      rep.energy -= 0.5 * x.segment<3>(3 * q).dot(B0[q]);
    }
  };
  const double bnorm = std::sqrt(dot(b, b));
  if (st.induction == InductionMode::kPaper || bnorm == 0.0) {
    store(b);
    rep.iterations = st.induction == InductionMode::kPaper ? 1 : 0;
    return rep;
  }

  // A x = x - alpha B_induced[x]: field of all other induced cells at each induced cell. The
  // tree walk is done once per solve (FieldPlan), so A is one linear operator for GMRES; its
  // opening decisions take the groups' cancellation from the one-pass moments b (a cell whose b
  // is exactly zero still counts as a source).
  auto load = [&](const Vector& x) {
    std::fill(s.induced.cell.begin(), s.induced.cell.end(), Vec3::Zero());
    for (int q = 0; q < n; ++q) s.induced.cell[t.cell[q]] = x.segment<3>(3 * q);
    s.induced.aggregate(m);
  };
  Vector shape = b;
  const double tiny = 1e-30 * bnorm;
  for (int q = 0; q < 3 * n; q += 3) {
    if (shape.segment<3>(q).squaredNorm() == 0.0) shape.segment<3>(q).setConstant(tiny);
  }
  load(shape);
  const FieldPlan plan = plan_field(m, s, s.induced, t, fopt);
  // The field of all other induced cells at each target for moments x (T, world frame), in B;
  // then `use(q, B_q)` per target, in parallel (each writes only its own rows).
  auto induced_field = [&](const Vector& x, auto&& use) {
    load(x);
    stats.field_pairs += apply_field_plan(plan, m, s, s.induced, t, fopt, B);
    to_body_frame(m, s, s.induced.cell, local);
    parallel_for_each(n, 256, [&](int q) {
      Vec3 Bq = B[q];
      add_body_near(m, s, q, t, local, [](int) { return false; }, Bq);
      for (int e = rows.begin[q]; e < rows.begin[q + 1]; ++e) Bq += rows.tensor[e] * s.induced.cell[rows.cell[e]];
      use(q, Bq);
    });
  };
  auto apply = [&](const Vector& x, Vector& y) {
    y.resize(3 * n);
    induced_field(x, [&](int q, const Vec3& Bq) { y.segment<3>(3 * q) = x.segment<3>(3 * q) - alpha[q] * Bq; });
  };

  // Right preconditioner z = M^-1 v: each factored block (one body's consecutive induced cells,
  // body frame) applied in the body's current orientation. Identity without blocks.
  const bool precondition = st.induction_preconditioner && !m.precond_lu.empty();
  std::vector<int> q_of_rank;
  if (precondition) {
    q_of_rank.assign(n, 0);
    for (int q = 0; q < n; ++q) q_of_rank[t.original[q]] = q;
  }
  auto apply_precond = [&](const Vector& v, Vector& z) {
    if (!precondition) {
      z = v;
      return;
    }
    z.resize(3 * n);
    parallel_for_each(static_cast<int>(m.precond_factor.size()), 1, [&](int k) {
      const int r0 = m.precond_begin[k], nb = m.precond_begin[k + 1] - r0;
      const Mat3& R = s.body_rotation[m.cell_body[m.induced_cells[r0]]];
      Eigen::VectorXd local(3 * nb);
      for (int a = 0; a < nb; ++a) local.segment<3>(3 * a) = R.transpose() * v.segment<3>(3 * q_of_rank[r0 + a]);
      local = m.precond_lu[m.precond_factor[k]].solve(local);
      for (int a = 0; a < nb; ++a) z.segment<3>(3 * q_of_rank[r0 + a]) = R * local.segment<3>(3 * a);
    });
  };

  // Restarted GMRES (modified Gram–Schmidt, Givens rotations) for A x = rhs from x, to the
  // relative residual tol; returns the iterations, sets the relative residual.
  auto gmres = [&](const Vector& rhs, Vector& x, double tol, double& residual) {
    const double rnorm = std::sqrt(dot(rhs, rhs));
    const int restart = gmres_restart(st, n);
    std::vector<Vector> V(restart + 1);
    // Not zeroed: the Arnoldi step writes H(0..j+1, j) before anything reads it, and the upper
    // triangular solve reads only those (the automatic restart makes H up to 301 x 300).
    Eigen::MatrixXd H(restart + 1, restart);
    Vector cs(restart), sn(restart), g(restart + 1), r, w, z;
    apply(x, r);
    r = rhs - r;
    double beta = std::sqrt(dot(r, r));
    residual = beta / rnorm;
    int it = 0;
    while (residual > tol && it < st.induction_max_iterations) {
      V[0] = r / beta;
      g.setZero();
      g[0] = beta;
      int j = 0;
      while (j < restart && it < st.induction_max_iterations) {
        apply_precond(V[j], z);
        apply(z, w);
        for (int i = 0; i <= j; ++i) {
          H(i, j) = dot(w, V[i]);
          w -= H(i, j) * V[i];
        }
        H(j + 1, j) = std::sqrt(dot(w, w));
        if (H(j + 1, j) > 0) V[j + 1] = w / H(j + 1, j);
        for (int i = 0; i < j; ++i) {
          const double h0 = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
          H(i + 1, j) = -sn[i] * H(i, j) + cs[i] * H(i + 1, j);
          H(i, j) = h0;
        }
        const double den = std::hypot(H(j, j), H(j + 1, j));
        cs[j] = H(j, j) / den;
        sn[j] = H(j + 1, j) / den;
        H(j, j) = den;
        H(j + 1, j) = 0;
        g[j + 1] = -sn[j] * g[j];
        g[j] = cs[j] * g[j];
        ++j, ++it;
        if (std::abs(g[j]) / rnorm <= tol) break;
      }
      // x += M^-1 V y with H y = g (upper triangular, j x j).
      const Vector y = H.topLeftCorner(j, j).triangularView<Eigen::Upper>().solve(g.head(j));
      Vector u = Vector::Zero(3 * n);
      for (int i = 0; i < j; ++i) u += y[i] * V[i];
      apply_precond(u, z);
      x += z;
      // Converged by GMRES's own residual (|g[j]| is |b - A x| of the updated x, up to round-off):
      // no application to confirm it. Otherwise the restart needs the residual anyway.
      if (std::abs(g[j]) / rnorm <= tol) {
        residual = std::abs(g[j]) / rnorm;
        break;
      }
      apply(x, r);
      r = rhs - r;
      beta = std::sqrt(dot(r, r));
      residual = beta / rnorm;
      if (beta == 0.0) break;
    }
    return it;
  };

  // Warm start from the previous moments (world frame) when they exist, else from the one-pass
  // answer.
  Vector x(3 * n);
  const bool warm = s.induced_moment.size() == m.induced_cells.size();
  for (int q = 0; q < n && warm; ++q) x.segment<3>(3 * q) = s.induced_moment[t.original[q]];
  const bool cold = !warm || dot(x, x) == 0.0;
  if (cold) x = b;

  // Saturating cells (Fröhlich–Kennelly, physics.md §13).
  std::vector<int> sat;  // target indices
  if (!m.part_saturation.empty()) {
    for (int q = 0; q < n; ++q) {
      if (m.part_saturation[m.cell_part[t.cell[q]]] > 0) sat.push_back(q);
    }
  }
  if (sat.empty()) {
    rep.iterations = gmres(b, x, st.induction_tolerance, rep.residual);
    rep.converged = rep.residual <= st.induction_tolerance;
    store(x);
    return rep;
  }

  // Newton's method on the magnetization law: at each saturating cell the law is linearized at
  // the cell's field H_k, M = J H + M_r with the tangent J = dM/dH and M_r = M(H_k) - J H_k, and
  // the coupled linear system with that law is solved by GMRES (warm-started from the last
  // moments). The cell's new field follows from its law, H = J^-1 (M - M_r); Newton stops when
  // M(H) matches M. The first linearization is at the field the warm-start moments imply (at
  // H = 0, the linear law, when there are none).
  const int ns = static_cast<int>(sat.size());
  std::vector<Vec3> Hk(ns), Mr(ns);
  std::vector<Mat3> J(ns), Nw(ns);
  std::vector<double> chi(ns), ms(ns), vol(ns);
  for (int k = 0; k < ns; ++k) {
    const int c = t.cell[sat[k]];
    const Mat3& R = s.body_rotation[m.cell_body[c]];
    chi[k] = m.cell_chi[c];
    ms[k] = m.part_saturation[m.cell_part[c]];
    vol[k] = m.cell_volume[c];
    Nw[k] = R * m.cell_demag[c] * R.transpose();
    Vec3 M0 = cold ? Vec3::Zero() : Vec3(x.segment<3>(3 * sat[k]) / vol[k]);
    if (M0.norm() > 0.99 * ms[k]) M0 *= 0.99 * ms[k] / M0.norm();
    Hk[k] = frohlich_kennelly_inverse(M0, chi[k], ms[k]);
  }
  auto linearize = [&](int k) {
    const double h = Hk[k].norm();
    const double c = chi[k] / (1.0 + chi[k] * h / ms[k]);  // secant susceptibility |M| / |H|
    J[k] = c * Mat3::Identity();
    if (h > 0) {
      const Vec3 u = Hk[k] / h;
      J[k] += (c * c / chi[k] - c) * u * u.transpose();  // along H the slope is c^2 / chi
    }
    Mr[k] = c * Hk[k] - J[k] * Hk[k];
    const Mat3 K = (Mat3::Identity() + J[k] * Nw[k]).inverse();
    const int q = sat[k];
    alpha[q] = vol[k] * K * J[k] / kMu0;
    b.segment<3>(3 * q) = alpha[q] * B0[q] + vol[k] * K * Mr[k];
  };
  // Relative mismatch of the law, |M - M(H)| / |M| over the saturating cells, and their new
  // fields by the linearized law, H = J^-1 (M - M_r). (Not from the field, B_loc / mu0 - N M:
  // at high chi that difference of near-equal terms magnifies the linear solve's error by chi.)
  std::vector<Vec3> Hnew(ns);
  auto mismatch = [&]() {
    double num = 0, den = 0;
    for (int k = 0; k < ns; ++k) {
      const Vec3 M = x.segment<3>(3 * sat[k]) / vol[k];
      Hnew[k] = J[k].inverse() * (M - Mr[k]);
      // Deep in saturation the law is flat and its inverse meaningless: |H| is capped where
      // |M(H)| = M_s (1 - 1e-6), so that no H runs off to infinity (and c, J to zero).
      const double hmax = 1e6 * ms[k] / chi[k], h = Hnew[k].norm();
      if (!(h <= hmax)) Hnew[k] = h > 0 && std::isfinite(h) ? Vec3(Hnew[k] * (hmax / h)) : Vec3(M.normalized() * hmax);
      num += (M - frohlich_kennelly(Hnew[k], chi[k], ms[k])).squaredNorm() * vol[k];
      den += M.squaredNorm() * vol[k];
    }
    return den > 0 ? std::sqrt(num / den) : 0.0;
  };
  const double law_tolerance = std::min(10.0 * st.induction_tolerance, 1e-4);
  double last = INFINITY, step = 1.0;
  rep.converged = false;
  for (int newton = 0; newton < kMaxNewtonIterations; ++newton) {
    for (int k = 0; k < ns; ++k) linearize(k);
    // Every step's linear solve to the tolerance: the new fields come from the linearized law,
    // whose inverse slope along H (chi / c^2) magnifies a looser solve's error in deep saturation
    // (an inexact Newton with Eisenstat and Walker's forcing term diverged there).
    double residual = 0;
    rep.iterations += gmres(b, x, st.induction_tolerance, residual);
    rep.residual = residual;
    rep.nonlinear_iterations = newton + 1;
    rep.nonlinear_residual = mismatch();
    if (rep.nonlinear_residual <= law_tolerance) {
      rep.converged = residual <= st.induction_tolerance;
      break;
    }
    // Damped when the mismatch grows (a step past the knee of the law), restored as it shrinks.
    step = rep.nonlinear_residual < last ? std::min(1.0, 2.0 * step) : std::max(step / 2.0, 1.0 / 16.0);
    last = rep.nonlinear_residual;
    for (int k = 0; k < ns; ++k) Hk[k] += step * (Hnew[k] - Hk[k]);
  }
  store(x);
  // Energy: the moments minimize sum_i v psi(M_i) + (their mutual and self-field energy) -
  // sum_i m_i.B0_i, psi the law's stored energy (mu0 H = dpsi/dM). At the minimum that is
  // -1/2 sum m.B0 + sum_i v (psi(M_i) - mu0 M_i.H_i / 2): nothing more for a linear law; for
  // Fröhlich–Kennelly, with a = chi |H| / M_s (|M| = M_s a / (1 + a)),
  // psi - mu0 M.H / 2 = mu0 M_s^2 / chi (ln(1 + a) - a / (1 + a) - a^2 / (2 (1 + a))) (physics.md
  // §13). In terms of the cell's field, not of |M| / M_s: a linearized step can leave |M| a hair
  // above M_s, where the same expression in |M| / M_s has no value (a bake's energy read 3e6 J).
  // Near saturation the cell's field comes from the field itself, B_loc / mu0 - N M (the law's
  // inverse there magnifies the solve's error without bound); below half of M_s from the law.
  std::vector<int> sat_index(n, -1);
  for (int k = 0; k < ns; ++k) sat_index[sat[k]] = k;
  induced_field(x, [&](int q, const Vec3& Bq) {
    const int k = sat_index[q];
    if (k < 0) return;
    const Vec3 M = x.segment<3>(3 * q) / vol[k];
    if (M.norm() >= 0.5 * ms[k]) Hnew[k] = (B0[q] + Bq) / kMu0 - Nw[k] * M;
  });
  for (int k = 0; k < ns; ++k) {
    const double a = chi[k] * Hnew[k].norm() / ms[k];
    rep.energy += vol[k] * kMu0 * ms[k] * ms[k] / chi[k] * (std::log1p(a) - a / (1.0 + a) - a * a / (2.0 * (1.0 + a)));
  }
  return rep;
}

}  // namespace magbake::magnetics
