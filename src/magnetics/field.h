// Magnetic flux density B at arbitrary points from all cells, by a tree code over the body
// hierarchies (Barnes–Hut with grouped targets and the same opening angle theta as forces).
#pragma once

#include <span>
#include <vector>

#include "body_tree.h"
#include "state.h"

namespace magbake::magnetics {

/// Options of one field evaluation.
struct FieldOptions {
  double theta = 0.5;       ///< opening angle (0 = every cell)
  double near_field = 0.0;  ///< exact cuboid field within this many cell sizes of full cells (0 = off)
  /// Targets inside a cell's cuboid get that cuboid's field with the cell's moment smeared over
  /// it (mu0 (H + M) inside): bounded inside magnets, where a point dipole is singular.
  bool smear_inside = false;
  /// Far and leaf dipoles in single precision (AVX2, 8 targets per instruction); near cells,
  /// sums and everything else in double. (Either way a target that is a cell skips itself.)
  bool single_precision = false;
  /// Permanent parts with an exact surface (Model::has_surfaces) whose cells a target group would
  /// open give their surface-charge field instead (exact up to the tessellation, inside them too:
  /// surface_charge.h). Only for sources that hold the permanent moments (State::total or
  /// State::permanent), since the surfaces carry the model's permanent magnetization.
  bool surfaces = false;
  /// Opening angle of the cell nodes of another body than a target group's when that body's
  /// bounding sphere comes closer to the group than its own radius (targets on cells only; point
  /// targets, farther bodies, whole bodies and groups of bodies use theta; 0 = theta). The
  /// induction solve opens such nodes at a smaller angle: where two soft bodies face each other
  /// their magnetizations vary most (physics.md §7).
  double other_body_theta = 0.0;
};

/// The interaction lists of one field evaluation (field.cpp's dual walk): which far groups of
/// bodies reach which nodes of a hierarchy over the target groups as local expansions, and
/// which cell nodes, cells and far body groups each target group sums itself. They depend on
/// the targets, the poses, the options and which sources are active (and how much a group's
/// moments cancel), not on the moments' values: applied to other moments of the same active
/// cells (the induction's Krylov vectors), the evaluation is one fixed linear operator.
struct FieldPlan {
  enum Kind : std::uint8_t { kBodyNode, kCellNode, kCell };
  /// A far source of one target group: a node of State::body_tree, a cell-hierarchy node, or a cell.
  struct Far {
    Kind kind;
    int index;
  };
  BodyTree target_tree;                         ///< over the target groups (leaf body[] = group)
  std::vector<int> roots;                       ///< target subtrees evaluated independently
  std::vector<int> local_begin;                 ///< (nroot + 1) into local_pair
  std::vector<std::pair<int, int>> local_pair;  ///< (target-tree node, body-tree node)
  std::vector<int> far_begin, far_end;          ///< (ngroup) range of group g in far
  std::vector<Far> far;                         ///< the groups' lists in target-tree order
  std::vector<int> near_begin, near_end;        ///< (ngroup) range of group g in near
  std::vector<int> near;                        ///< cells evaluated target by target
  std::vector<int> surface_begin, surface_end;  ///< (ngroup) range of group g in surface
  std::vector<int> surface;                     ///< parts whose exact surface field each group sums
  std::int64_t pairs = 0;                       ///< source–target evaluations of one application
};

/// Walks the hierarchies once for `targets` and the active sources of `sources` (positions from
/// the state).
FieldPlan plan_field(const Model& model, const State& s, const Sources& sources, const Targets& targets,
                     const FieldOptions& options);

/// B (tesla, world) of `sources` at every target through a plan made for the same targets, state
/// and options (sources active where the plan's were). Returns the source–target evaluations.
std::int64_t apply_field_plan(const FieldPlan& plan, const Model& model, const State& s, const Sources& sources,
                              const Targets& targets, const FieldOptions& options, std::span<Vec3> B);

/// B (tesla, world) of `sources` at every target, in target order (B has targets.position.size()
/// entries). Cell world positions come from the state (body poses set, offsets updated).
/// Adds nothing for the applied field. Returns the number of source–target evaluations.
std::int64_t field_at_targets(const Model& model, const State& s, const Sources& sources, const Targets& targets,
                              const FieldOptions& options, std::span<Vec3> B);

}  // namespace magbake::magnetics
