// Everything an evaluation changes: body poses (input), induced moments (kept for warm starts)
// and work buffers reused from step to step (no allocation once sized).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <span>
#include <vector>

#include "body_tree.h"
#include "model.h"
#include "settings.h"

namespace magbake::magnetics {

/// Cell moments acting as field sources, with their per-node sums.
struct Sources {
  std::vector<Vec3> cell;                 ///< (ncell x 3) world, A·m²
  std::vector<Vec3> node;                 ///< (nnode x 3) world, A·m², sum over the node's cells
  std::vector<std::uint8_t> node_active;  ///< (nnode) some cell below has a non-zero moment
  /// (nnode) m: how far the node's moments are from one dipole at the node's centre c,
  /// |sum_i m_i (x_i - c)^T|_F / |sum_i m_i| (the first moment of the moments; infinite when the
  /// sum vanishes). Zero, to round-off, for a uniformly magnetized node (c is its volume
  /// centroid); induced moments that vary across a body (a superconductor's surface currents,
  /// the side of a steel ball facing a magnet) make it up to many times the node's radius, and
  /// the aggregate's error is then first order, about spread / d. Empty when aggregated without
  /// offsets (the induction operator's Krylov vectors: an opening test that depended on them
  /// would make the operator nonlinear).
  std::vector<double> spread;
  std::vector<Mat3> first_moment;  ///< (nnode) scratch: sum_i m_i (x_i - c)^T, world, A·m²·m

  /// Sizes the arrays and recomputes node sums and activity from `cell` (spread left empty).
  void aggregate(const Model& model);
  /// The same, and `spread` from the cells' and nodes' offsets from their body origins
  /// (State::cell_offset and State::node_offset, world, m).
  void aggregate(const Model& model, std::span<const Vec3> cell_offset, std::span<const Vec3> node_offset);
};

/// The spread test of a far interaction: two aggregates of spreads qa and qb (m) whose centres
/// are d apart are taken as dipoles only if qa + qb < theta^2 d, so that their first-order error
/// is no larger than the second-order error that the radius test (r < theta d) allows a uniform
/// node. Measured on SuperCube's cube (chi = -1, 10 mm, centre 16 mm above its ring's plane):
/// the force at theta 0.5 was 34% off theta 0's without this test and is 26% off with it; the
/// rest is the radius test's second-order error, which cancellation between the ring's sides
/// amplifies (physics.md, known limits).
inline bool spread_ok(double qa, double qb, double theta, double d) { return qa + qb < theta * theta * d; }

struct State;

/// Points where B is wanted, grouped spatially so each group walks the source trees once.
struct Targets {
  std::vector<Vec3> position;      ///< (ntarget x 3) world, m, in group order
  std::vector<int> cell;           ///< (ntarget) cell the target sits on (its self-field is skipped), or -1
  std::vector<int> original;       ///< (ntarget) index in the caller's order
  std::vector<int> group_begin;    ///< (ngroup + 1)
  std::vector<Vec3> group_center;  ///< (ngroup x 3) world, m
  std::vector<double> group_radius;///< (ngroup) m

  /// Groups arbitrary points by recursive bisection (at most `group_size` per group).
  static Targets from_points(std::span<const Vec3> points, int group_size = 32);
  /// Voxel centres origin + (i, j, k) * voxel of an nx x ny x nz grid, grouped in blocks of
  /// block³ voxels; original[] holds the grid index (k * ny + j) * nx + i. Blocks for which
  /// keep(block_min, block_max) is false are left out.
  template <class Keep>
  static Targets from_grid(const Vec3& origin, double voxel, const Eigen::Vector3i& dims, int block, Keep keep);
  /// Targets at the induced cells of the model (groups = hierarchy leaves), world positions from `s`.
  static Targets from_induced_cells(const Model& model, const State& s);
  /// Recomputes positions and group bounds of targets made by from_induced_cells.
  void update_induced_positions(const Model& model, const State& s);
};

template <class Keep>
Targets Targets::from_grid(const Vec3& origin, double voxel, const Eigen::Vector3i& dims, int block, Keep keep) {
  Targets t;
  t.group_begin.push_back(0);
  for (int bk = 0; bk < dims[2]; bk += block) {
    for (int bj = 0; bj < dims[1]; bj += block) {
      for (int bi = 0; bi < dims[0]; bi += block) {
        const Eigen::Vector3i hi(std::min(bi + block, dims[0]), std::min(bj + block, dims[1]), std::min(bk + block, dims[2]));
        const Vec3 lo_p = origin + voxel * Vec3(bi, bj, bk), hi_p = origin + voxel * (hi.cast<double>() - Vec3::Ones());
        if (!keep(lo_p, hi_p)) continue;
        for (int k = bk; k < hi[2]; ++k) {
          for (int j = bj; j < hi[1]; ++j) {
            for (int i = bi; i < hi[0]; ++i) {
              t.position.push_back(origin + voxel * Vec3(i, j, k));
              t.cell.push_back(-1);
              t.original.push_back((k * dims[1] + j) * dims[0] + i);
            }
          }
        }
        t.group_begin.push_back(static_cast<int>(t.position.size()));
        const Vec3 c = 0.5 * (lo_p + hi_p);
        t.group_center.push_back(c);
        t.group_radius.push_back((hi_p - c).norm());
      }
    }
  }
  return t;
}

/// Per-evaluation state of the magnetics. Set body_pose, then call evaluate().
struct State {
  std::vector<Pose> body_pose;        ///< (nbody) body frame -> world; input

  /// (ninduced) world, A·m²; output and the next solve's warm start, used as it stands in the
  /// world frame (induced moments follow the field, not the body: turning them with a spinning
  /// ball made the warm start worse than none).
  std::vector<Vec3> induced_moment;

  // ---- derived each evaluation (world frame)
  std::vector<Vec3> cell_offset;      ///< (ncell x 3) cell position minus body origin, m
  std::vector<Vec3> node_offset;      ///< (nnode x 3) node centre minus body origin, m
  Sources total;                      ///< total (permanent + induced) cell moments and node sums
  Sources permanent;                  ///< permanent moments only (induction right-hand side)
  Sources induced;                    ///< induced moments only (induction operator)
  Targets induced_targets;            ///< the induced cells as field targets

  /// Near-field corrections of the induction operator from cells of other bodies, rows =
  /// induced targets (target order): B_mean(target) - B_dipole(target) = tensor * m(source
  /// cell), world frame, T/(A·m²). Corrections inside a body are the model's (Model::near_tensor,
  /// body frame), applied to the moments rotated into that frame.
  struct NearRows {
    std::vector<int> begin;            ///< (ntarget + 1)
    std::vector<int> cell;             ///< source cell of each entry
    std::vector<Mat3> tensor;          ///< correction tensor of each entry
  } induced_near;
  /// Cross-body near-field tensors kept while two bodies keep their relative pose (resting
  /// contact): key = (target body, source body).
  struct PairTensors {
    Mat3 rotation = Mat3::Identity();  ///< source body axes in target body axes
    Vec3 offset = Vec3::Zero();        ///< source origin in the target body frame, m
    std::unordered_map<std::int64_t, Mat3> tensor;  ///< (target cell, source cell) -> target body frame
  };
  std::map<std::pair<int, int>, PairTensors> cross_tensors;
  /// (nbody) input, optional: 1 for a body that magnetic forces do not move (static or
  /// kinematic). Forces between two such bodies that are purely permanent are computed once
  /// per set of their poses (fixed_pairs); empty = no body is fixed.
  std::vector<std::uint8_t> body_fixed;
  /// The hierarchy over all bodies (world frame), rebuilt from the poses at every evaluation;
  /// every walk (forces, induction, field) starts at its root.
  BodyTree body_tree;
  /// Cache: the mutual forces, torques (about each body's origin) and energy of the fixed,
  /// purely permanent bodies, valid for the poses and force settings stored with it. Pairs of
  /// them are skipped by the force walk while it is valid (accumulate_forces()).
  struct FixedPairs {
    bool valid = false;
    std::vector<std::uint8_t> frozen;  ///< (nbody) the bodies it covers
    std::vector<Pose> poses;           ///< their poses, in body order
    double theta = 0, near_field = 0;
    int near_field_order = 0;
    KernelPrecision precision = KernelPrecision::kSingle;
    bool body_groups = true;
    std::vector<Vec3> force, torque;   ///< (nbody) N, N·m
    double energy = 0;                 ///< J
    std::int64_t near_pairs = 0;
  };
  mutable FixedPairs fixed_pairs;
  std::vector<Mat3> body_rotation;    ///< (nbody) rotation matrices
  std::vector<Mat3> part_rotation;    ///< (npart) part frame -> world
  // float copies for the single-precision block kernels: (ncell) each
  std::vector<float> fx, fy, fz, fmx, fmy, fmz, fclamp;

  /// Sizes every buffer for `model` (call once; evaluate() calls it when sizes differ).
  void resize(const Model& model);
  /// Drops what one evaluation leaves for the next besides induced_moment: the cross-body
  /// tensors (reused within a tolerance of the pose they were made at) and the fixed pairs'
  /// forces. After it, the next evaluation depends only on the poses, the settings and
  /// induced_moment (the simulator calls it at every frame, so a resumed bake matches).
  void forget_caches() {
    cross_tensors.clear();
    fixed_pairs = FixedPairs{};
  }
};

}  // namespace magbake::magnetics
