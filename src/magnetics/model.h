// The immutable description of every magnetic body: dipole cells and their hierarchies.
// Built once per scene (cells.cpp, hierarchy.cpp); per-step data lives in State (state.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/LU>

#include "material.h"
#include "solid.h"
#include "surface_charge.h"
#include "types.h"

namespace magbake::magnetics {

/// One part of a body: a solid, where it sits in the body frame, and its material.
struct PartSpec {
  const Solid* solid = nullptr;  ///< not owned; only used during build_model()
  Pose part_to_body;             ///< part frame -> body frame
  Material material;
  double cell_size = 0;          ///< finest cell edge for this part, m (0: BuildSettings::cell_size)
};

/// One rigid body. Its frame's origin is the point torques are reported about (the caller
/// puts it at the centre of mass). Bodies without magnetic parts get no cells and cost nothing.
struct BodySpec {
  std::vector<PartSpec> parts;
  /// The body is one sphere centred on the body origin. If its cells are also all induced (a
  /// soft, isotropic sphere: build_model checks), its energy cannot depend on its orientation,
  /// its magnetic torque about the origin is exactly zero, and Model::body_isotropic makes
  /// evaluate() report zero instead of the cell staircase's spurious torque (physics.md §8).
  bool isotropic = false;
};

/// Knobs of the cell decomposition.
struct BuildSettings {
  double cell_size = 0.002;   ///< finest cell edge, m (upper bound; each part's grid fits its bounds)
  int leaf_size = 32;         ///< max cells in a hierarchy leaf (block kernels work on leaf pairs)
  int subsamples = 4;         ///< per axis, to measure the inside fraction of boundary cells
  std::int64_t max_cells = 4'000'000;  ///< capacity guard: building more cells is an error
  /// Induced cells closer than this many cell sizes interact through the exact mean field of
  /// their cuboids in the induction solve (point dipoles beyond). 0 = point dipoles only.
  double induction_near = 2.0;
  /// Induced cells per block of the induction preconditioner (consecutive cells of one body,
  /// hierarchy order; each block's operator is factored once) where a body is not one block
  /// (induction_body_block). 0 = no preconditioner.
  int induction_block = 512;
  /// A body with at most this many induced cells is one preconditioner block, while the distinct
  /// whole-body operators fit induction_block_bytes (bodies in index order; the others are split
  /// into induction_block cells). Whole, a body's block holds its surface-charge modes: a steel
  /// ball of 14 cells across (1,840 cells) cut into 512-cell blocks left GMRES(50) at residual
  /// 7e-4 after 300 iterations in the paper's BowlSpheres; whole, it converged to 1e-6 in 84.
  int induction_body_block = 2400;
  /// Memory for the factors of the whole-body blocks, bytes (72 n^2 for a body of n cells;
  /// bodies with equal operators share one).
  std::int64_t induction_block_bytes = std::int64_t(1) << 30;
  /// A permanent part whose solid is a ball (Solid::ball) becomes one cell at its centre holding
  /// the ball's whole moment: exact, since a uniformly magnetized ball's field outside it is that
  /// of a point dipole, and the force and torque a field with its sources outside the ball exerts
  /// on it are those on the point dipole (the mean-value property of harmonic fields, physics.md
  /// §4). false = the ball is cut into lattice cells like any other solid (validation only).
  bool exact_balls = true;
  /// A permanent part whose solid has a surface (Solid::surface) and cells that do not all fit it
  /// (a cylinder, torus or mesh magnet; not a box, not an exact ball) keeps that surface,
  /// tessellated within this distance (m) of the true one: near it, field_at_targets with
  /// FieldOptions::surfaces takes the part's exact surface-charge field instead of its cells'
  /// (physics.md §12). 0 = no surfaces (cells only).
  double surface_tolerance = 0.0;
  /// A part keeps its surface only up to this many triangles: every target near it costs one
  /// evaluation per triangle (a 4096-triangle mesh about 0.3 ms), so finer meshes keep their cells.
  int max_surface_triangles = 4096;
  /// Induced (soft) parts: cells at the surface are split in 8, this many times over, so the
  /// solve resolves the magnetization that gathers at edges, corners and near other bodies
  /// (physics.md §7). 0 = uniform cells.
  int grading = 0;
  /// A cell is graded when it is partly inside its solid or has the centre of a face-neighbour
  /// of its own size outside it on at least this many axes (1 = every surface cell, 2 = edges
  /// and corners of flat-faced solids, and the curved surface).
  int grading_faces = 1;
};

/// Per-part statistics of the decomposition.
struct PartReport {
  int body = 0;
  int cells = 0;            ///< cells kept
  int full_cells = 0;       ///< cells entirely inside (exact cuboids for the near field)
  double grid_volume = 0;   ///< summed cell volume before rescaling, m³
  double true_volume = 0;   ///< the solid's exact volume, m³
  double rescale = 1;       ///< true_volume / grid_volume (paper §4.2)
};

/// All magnetic bodies: cells (flat arrays, hierarchy order) and per-body binary hierarchies.
/// Shapes in comments are (count x components); "body frame" means the body's own frame.
struct Model {
  int body_count = 0;

  // ---- bodies (body_count)
  std::vector<int> body_cell_begin;      ///< (nbody+1) cells of body b are [begin[b], begin[b+1])
  std::vector<int> body_root;            ///< root node of body b, -1 if the body has no cells
  std::vector<std::uint8_t> body_permanent;  ///< body has permanently magnetized cells
  std::vector<std::uint8_t> body_induced;    ///< body has induced (linear/superconducting) cells
  /// Body whose exact magnetic torque about its origin is zero (BodySpec::isotropic); its
  /// reported torque is zero. Empty or 0 for a model read back from a cache.
  std::vector<std::uint8_t> body_isotropic;

  // ---- parts (npart)
  std::vector<int> part_body;            ///< owning body
  std::vector<Pose> part_pose;           ///< part frame -> body frame
  std::vector<Mat3> part_rotation;       ///< part frame -> body frame (cell cuboid axes)
  std::vector<Vec3> part_magnetization;  ///< permanent M in the body frame, A/m (0 if induced)
  std::vector<double> part_chi;          ///< susceptibility (0 for permanent and none)
  /// Saturation magnetization M_s, A/m (Material::saturation / mu0); 0 = linear. Empty for a
  /// model read back from a cache (its moments are stored, not solved).
  std::vector<double> part_saturation;
  std::vector<Vec3> part_half;           ///< half-edges of the part's cells, part frame, m
  std::vector<std::uint8_t> part_consistent;  ///< induced part whose cells are corrected to be
                                         ///< exact for uniform magnetization (its solid has demag_tensor)
  std::vector<PartReport> part_report;
  // Exact surfaces of permanent parts (BuildSettings::surface_tolerance): triangles of part p are
  // [part_surface_begin[p], part_surface_begin[p+1]); triangle t has corners surface_vertex[3t..3t+2]
  // (body frame, m, counter-clockwise seen from outside); its charge density M . n lives in
  // part_surface_mesh. A part with no triangles has no surface. Empty vectors: no part has one.
  std::vector<int> part_surface_begin;   ///< (npart + 1)
  std::vector<Vec3> surface_vertex;      ///< (3 ntri x 3) body frame, m
  std::vector<Vec3> part_surface_center; ///< (npart x 3) centre of a sphere around the surface, body frame, m
  std::vector<double> part_surface_radius;  ///< (npart) its radius, m (0 without a surface)
  std::vector<SurfaceMesh> part_surface_mesh;  ///< (npart) the same triangles prepared for evaluation
  /// Parts with a surface, by body: body b's are body_surface_part[body_surface_begin[b] ..
  /// body_surface_begin[b+1]) (both empty when no part has one).
  std::vector<int> body_surface_begin;   ///< (nbody + 1)
  std::vector<int> body_surface_part;    ///< part indices, by body
  /// Whether a group of cells or targets inside the sphere (c, r) (world frame, m) is near
  /// enough to surface part p, of a body at position x with rotation R, to take the part's exact
  /// field instead of its cells: the theta test between the group and the part's bounding sphere,
  /// as nodes open each other (physics.md §5, §12). Forces and field evaluation both use it.
  bool opens_surface(int p, const Vec3& x, const Mat3& R, const Vec3& c, double r, double theta) const {
    return !(part_surface_radius[p] + r < theta * (x + R * part_surface_center[p] - c).norm());
  }
  bool has_surfaces() const { return !surface_vertex.empty(); }
  /// Triangles of all surfaces.
  int surface_triangle_count() const { return static_cast<int>(surface_vertex.size() / 3); }
  int surface_triangles(int p) const { return has_surfaces() ? part_surface_begin[p + 1] - part_surface_begin[p] : 0; }

  // ---- cells (ncell), ordered so every node's cells are contiguous
  std::vector<Vec3> cell_position;       ///< (ncell x 3) where the moment sits (centroid of the
                                         ///< material in the cell), body frame, m
  std::vector<Vec3> cell_center;         ///< (ncell x 3) centre of the cell's cuboid, body frame, m
  std::vector<Vec3> cell_moment;         ///< (ncell x 3) permanent moment, body frame, A·m²
  std::vector<double> cell_volume;       ///< (ncell) m³ of material, after rescaling to the true volume
  std::vector<double> cell_chi;          ///< (ncell) susceptibility of the cell's material; 0 if not induced
  std::vector<Mat3> cell_polarizability; ///< (ncell x 3 x 3) body frame, m³: m = P B_loc / mu0, with
                                         ///< B_loc the field of all other cells (+ near corrections)
  /// (ncell x 3 x 3) body frame, dimensionless: the cell's own demagnetizing tensor N (its mean
  /// field is -N M from its own M, corrected to be exact for a uniformly magnetized part), of
  /// which cell_polarizability = v chi (1 + chi N)^-1. Zero for cells that are not induced.
  std::vector<Mat3> cell_demag;
  std::vector<Vec3> cell_half;           ///< (ncell x 3) half-edges of the cuboid cell, part frame, m
  std::vector<double> cell_reach;        ///< (ncell) radius of the cell's bounding sphere, m
  std::vector<double> cell_clamp;        ///< (ncell) half of the closest approach of two cells, m
  /// (ncell) radius of the ball of the cell's material volume, (3 v / 4 pi)^(1/3), m: a boundary
  /// cell's clamp radius in the induction's coupling across bodies (physics.md §7)
  std::vector<double> cell_ball_radius;
  std::vector<int> cell_part;            ///< (ncell) part index
  std::vector<int> cell_body;            ///< (ncell) body index
  std::vector<std::uint8_t> cell_full;   ///< (ncell) 1 if the cuboid lies entirely inside its part
  /// (ncell) 1 if the cell is a whole uniformly magnetized ball (BuildSettings::exact_balls): its
  /// radius is cell_half (all three equal), position = centre; a point dipole outside the ball,
  /// B = 2/3 mu0 M inside it. Never full (no cuboid near field).
  std::vector<std::uint8_t> cell_ball;
  std::vector<int> induced_cells;        ///< indices of cells with cell_chi != 0, ascending

  // ---- near-field corrections of the induction operator inside each body (rigid, so built once)
  // Row r belongs to induced_cells[r]: B_mean - B_dipole at that cell = tensor * m(source), body frame.
  double induction_near = 0;             ///< radius used, in cell sizes (BuildSettings::induction_near)
  std::vector<int> near_begin;           ///< (ninduced + 1)
  std::vector<int> near_cell;            ///< source cell of each entry (same body)
  std::vector<Mat3> near_tensor;         ///< T/(A·m²), body frame

  // ---- induction preconditioner (rigid, so factored once): block k covers the induced ranks
  // [precond_begin[k], precond_begin[k+1]) of one body; precond_lu[precond_factor[k]] factors
  // that block of the coupled operator I - P/mu0 (T_dipole + near rows) in the body frame (3 rows
  // per cell). Blocks with equal operators (bodies of one shape, material and cell layout) share
  // one factorization.
  std::vector<int> precond_begin;        ///< (nblock + 1) induced ranks
  std::vector<int> precond_factor;       ///< (nblock) index into precond_lu
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXd>> precond_lu;  ///< (distinct blocks)

  // ---- hierarchy nodes (nnode); children of node n are node_child[n] .. + node_nchild[n] - 1
  std::vector<int> node_begin, node_end; ///< (nnode) cell range
  std::vector<int> node_child;           ///< (nnode) first child, -1 for a leaf
  std::vector<int> node_nchild;          ///< (nnode) number of children (2..8), 0 for a leaf
  std::vector<int> node_body;            ///< (nnode) owning body
  std::vector<Vec3> node_center;         ///< (nnode x 3) volume centroid of the cells, body frame, m
  std::vector<double> node_radius;       ///< (nnode) bounding radius of the cells' cuboids, m
  std::vector<double> node_reach;        ///< (nnode) largest cell_reach below the node, m
  std::vector<Vec3> node_moment;         ///< (nnode x 3) summed permanent moment, body frame, A·m²
  std::vector<std::uint8_t> node_induced;///< (nnode) node holds induced cells
  std::vector<int> node_part;            ///< (nnode) the one part every cell below belongs to, -1 if several

  int cell_count() const { return static_cast<int>(cell_position.size()); }
  int node_count() const { return static_cast<int>(node_begin.size()); }
  bool has_induced() const { return !induced_cells.empty(); }
  bool empty() const { return cell_position.empty(); }
};

/// Cells as flat records in any order (body frame): what build_model() derives from solids, and
/// what a cache stores so field export can rebuild the model without the scene's files.
struct CellTable {
  std::vector<int> body, part;
  std::vector<Vec3> position, center, half, moment;  ///< m, m, m, A·m² (permanent, body frame)
  std::vector<double> volume, chi;
  std::vector<std::uint8_t> full;
  std::vector<std::uint8_t> ball;  ///< Model::cell_ball; empty = no ball cells (older caches)
  std::size_t size() const { return body.size(); }
};

/// Parts of a model (index = part id in CellTable::part).
struct PartTable {
  std::vector<int> body;
  std::vector<Pose> pose;            ///< part frame -> body frame
  std::vector<Vec3> magnetization;   ///< permanent M, body frame, A/m
  std::vector<Vec3> half;            ///< cell half-edges, part frame, m
  std::vector<double> chi;
  /// Model::part_surface_begin and surface_vertex (body frame); empty = no surfaces.
  std::vector<int> surface_begin;
  std::vector<Vec3> surface_vertex;
};

/// Builds the hierarchies over given cells (no induction data: polarizabilities stay zero).
/// If `order` is given, it receives for every model cell the index of the table row it came from.
Model model_from_cells(int body_count, const CellTable& cells, const PartTable& parts, int leaf_size = 32,
                       std::vector<int>* order = nullptr);

/// The cells and parts of a model, in model order (inverse of model_from_cells).
void model_tables(const Model& model, CellTable& cells, PartTable& parts);

/// Decomposes every body into dipole cells (paper §4.2, with inside-fraction weighting of
/// boundary cells) and builds the per-body hierarchies. A cell is a cuboid on its part's lattice
/// carrying the moment of the material inside it (smeared uniformly over the cuboid). Throws std::runtime_error when a part
/// is too small for the cell size or the model would exceed settings.max_cells (the message
/// names the knob to turn).
Model build_model(const std::vector<BodySpec>& bodies, const BuildSettings& settings);

}  // namespace magbake::magnetics
