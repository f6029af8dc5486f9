// Run-time knobs of an evaluation and what an evaluation reports.
#pragma once

#include <cstdint>
#include <vector>

#include "types.h"

namespace magbake::magnetics {

/// How induced (linear, superconducting) cells get their moments (physics-notes §4).
enum class InductionMode : unsigned char {
  kOff,      ///< induced cells carry no moment
  kPaper,    ///< one pass: each induced cell sees the permanent magnets and the applied field only
  kCoupled,  ///< self-consistent: every induced cell also sees every other cell (Krylov solve)
};

/// Arithmetic of the leaf-pair block kernels. Aggregated (far) interactions, near-field
/// corrections and all sums are double precision in both modes.
enum class KernelPrecision : unsigned char {
  kSingle,  ///< float, AVX2 (8 pairs per instruction); relative error ~1e-6 per block
  kDouble,  ///< double, scalar; for validation
};

/// Accuracy and cost knobs of one evaluation.
struct Settings {
  /// Opening angle of the adaptive traversal: two hierarchy nodes interact as single dipoles
  /// when (r_a + r_b) < theta * distance. 0 = every finest cell pair. Range [0, 1]; the
  /// induction solve uses min(theta, 0.5).
  double theta = 0.5;
  InductionMode induction = InductionMode::kCoupled;
  /// Uniform applied field (Earth, Helmholtz coil), world frame, tesla.
  Vec3 external_field = Vec3::Zero();
  /// Cells of different bodies closer than near_field cell sizes (centre distance over the
  /// mean longest cell edge) interact as exact uniformly magnetized cuboids, not as point
  /// dipoles. 0 turns the correction off (pure dipole method, as in the paper).
  double near_field = 2.5;
  /// Gauss points per face edge of the near-field surface integral (1..8).
  int near_field_order = 4;
  KernelPrecision precision = KernelPrecision::kSingle;
  /// Coupled induction: stop when the residual is below this fraction of the right-hand side.
  double induction_tolerance = 1e-7;
  int induction_max_iterations = 300;
  /// GMRES restart length. 0 = automatic: as many Krylov vectors as 256 MiB holds (3 doubles per
  /// induced cell each), at least 50 and at most induction_max_iterations. Clusters of touching
  /// high-chi bodies at fine cells stall with 50 (physics.md §7); the basis only grows as far as
  /// a solve iterates, so a solve that converges within 50 costs and gives the same either way.
  int induction_restart = 0;
  /// Right-precondition GMRES with the model's factored intra-body blocks (Model::precond_lu),
  /// when it has them. The answer is the same to induction_tolerance; iterations are fewer.
  bool induction_preconditioner = true;
  /// Groups of bodies far apart interact as aggregates in the force walk (the hierarchy over
  /// bodies, body_tree.h), opened at half of theta. false: every pair of bodies is walked at
  /// the cell level, as before 2026-12-02 (N^2; for validation, not a scene key).
  bool body_groups = true;
};

/// Outcome of the induced-magnetization solve.
struct InductionReport {
  int iterations = 0;      ///< Krylov iterations (0 when no solve ran; 1 for paper mode), all
                           ///< Newton steps together
  double residual = 0.0;   ///< final relative residual |b - A x| / |b| (of the last linear solve)
  bool converged = true;   ///< the linear solve, and the saturation law when there is one
  /// Saturating materials (Material::saturation): Newton steps on the law (0 without them) and
  /// the final relative mismatch |M - M(H)| / |M| over their cells (volume-weighted RMS).
  int nonlinear_iterations = 0;
  double nonlinear_residual = 0.0;
  /// Energy of the induced moments in the field B_0 of the permanent cells and the applied
  /// field, -1/2 sum m_ind . B_0 (J): the total magnetic energy of linear induced matter,
  /// induced-induced coupling included (physics.md §8).
  double energy = 0.0;
};

/// Work counters of one evaluation.
struct EvalStats {
  std::int64_t body_pairs = 0;   ///< body pairs traversed (pairs with nothing magnetic are skipped)
  std::int64_t node_pairs = 0;   ///< aggregated dipole–dipole interactions
  std::int64_t cell_pairs = 0;   ///< cell–cell interactions in leaf blocks
  std::int64_t near_pairs = 0;   ///< cell pairs corrected by the exact cuboid near field
  std::int64_t surface_pairs = 0;  ///< cell–triangle evaluations of exact surfaces (forces)
  std::int64_t field_pairs = 0;  ///< source–target field evaluations (induction, probes)
};

/// Forces, torques and moments of every body (index = body index of the Model).
struct Result {
  std::vector<Vec3> force;   ///< N, world frame
  std::vector<Vec3> torque;  ///< N·m, world frame, about the body-frame origin (centre of mass)
  std::vector<Vec3> moment;  ///< total magnetic moment (permanent + induced), world, A·m²
  /// Magnetic energy, J: permanent-permanent pairs of different bodies, -m.B_app of permanent
  /// moments, and InductionReport::energy for induced ones (physics.md §8).
  double energy = 0.0;
  InductionReport induction;
  EvalStats stats;
};

}  // namespace magbake::magnetics
