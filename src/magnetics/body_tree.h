// One hierarchy over all magnetic bodies (world frame), above the per-body cell hierarchies:
// its leaves are bodies, its inner nodes groups of nearby bodies. Force, induction and field
// walks start here, so far groups of bodies act as one aggregate dipole and the cost of a walk
// grows with log N instead of N (issue 13).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "model.h"
#include "types.h"

namespace magbake::magnetics {

struct State;
struct Sources;

/// A binary bounding-sphere tree over the bodies that have cells, rebuilt from the bodies'
/// root nodes at every evaluation (O(N log N), deterministic: median splits along the widest
/// axis, ties broken by body index). Node 0 is the root; children of an inner node n are
/// child[n] and child[n] + 1.
struct BodyTree {
  std::vector<int> child;       ///< (nnode) first child, -1 for a leaf
  std::vector<int> body;        ///< (nnode) the body of a leaf, -1 for an inner node
  std::vector<int> begin, end;  ///< (nnode) range of `order` below the node
  std::vector<int> parent;      ///< (nnode) -1 for the root
  std::vector<Vec3> center;     ///< (nnode x 3) world, m: centre of the members' root spheres' box
  std::vector<double> radius;   ///< (nnode) m: every member's root sphere lies within it
  std::vector<double> reach;    ///< (nnode) m: largest cell reach below the node
  std::vector<int> order;       ///< bodies in tree order (each node's members are contiguous)
  std::vector<int> leaf_of;     ///< (nbody) leaf node of each body, -1 for bodies without cells

  int node_count() const { return static_cast<int>(child.size()); }
  bool empty() const { return child.empty(); }
  /// Rebuilds the tree from the bodies' current root spheres (s.body_pose, s.node_offset):
  /// every body with cells, or those for which pick(body) is true.
  void build(const Model& model, const State& s, const std::function<bool(int)>& pick = {});
  /// The same tree over arbitrary spheres (centres c, radii r, world, m; reach 0): leaf n holds
  /// item body[n]. The field walk's hierarchy over target groups. With `cluster` (one id >= 0
  /// per item, e.g. the body a group of cells belongs to), the items of one cluster form one
  /// subtree: nodes are split between clusters (by the clusters' mean centres) until each holds
  /// one, then within it. A body's target groups then share one node, which takes far fields as
  /// one local expansion (field.cpp); median splits over all groups cut bodies apart.
  void build_over(const std::vector<Vec3>& c, const std::vector<double>& r, const std::vector<int>& cluster = {});
};

/// Per tree node: the summed moment of a source set (world, A·m²), whether it is non-zero, and
/// the node's effective radius for the opening test (m).
///
/// A group's summed moment is a good far-field source only when its members roughly agree: ten
/// magnets in random directions nearly cancel, and their field is then mostly quadrupole, which
/// a dipole at the centre misses. The aggregate's error relative to the members' own fields is
/// about (r/d) * (sum |m_i|) / |sum m_i|, so the test uses r * (sum |m_i|) / |sum m_i| as the
/// radius (infinite when the sum vanishes: the group is always opened). For one body (a leaf)
/// it is the body's radius, as in the cell hierarchy. Measured on 300 spheres, magnets in
/// random directions and steel (BodyTree.ForcesOfManyBodiesMatchEveryCellPair, theta 0.5,
/// rms force error against theta 0): plain radii and the full angle for groups gave 4.8%;
/// this radius with groups opened at kGroupTheta in every walk gives 0.39% (0.37% when the
/// force walk visits every body pair), 0.13% rms from the every-body-pair forces.
struct BodyTreeSources {
  std::vector<Vec3> moment;
  std::vector<std::uint8_t> active;
  std::vector<double> open_radius;
  /// m: a body's Sources::spread at its root (0 when src has none); for a group, the members'
  /// spreads weighted by |their moment| / |the group's moment| (infinite when that vanishes),
  /// a bound on the part of the group's first moment that its open_radius does not cover.
  std::vector<double> spread;
  /// (nnode) some member has induced cells (Model::body_induced): the force walk then opens the
  /// node as the cell walk opens soft nodes (forces.cpp, kInducedTheta and kSoftSourceTheta).
  std::vector<std::uint8_t> induced;
  /// Sums src.node[root] of each body bottom-up.
  void aggregate(const BodyTree& tree, const Model& model, const Sources& src);
};

/// Opening angle of groups of bodies (inner nodes of the tree), in units of Settings::theta.
/// A member's share of a group interaction is evaluated at its group's centre, and a dipole's
/// force falls as d^-4, so a displacement r changes it by about 4 r / d where the aggregate's
/// field changes by r / d (forces.cpp has the measurements).
constexpr double kGroupTheta = 0.5;

/// Largest radius of a group of targets, in units of Settings::theta times the distance, that
/// takes a far group's field as a second-order local expansion about its centre (field.cpp):
/// the expansion's relative error grows as about 10 (r/d)^3. Since a body's target groups share
/// one node (build_over() with clusters), its nearest far neighbours reach it as expansions:
/// measured on 1000 spheres (DualFieldWalk.MatchesEveryCellAndIsLinearInTheMoments), rms field
/// error 1.46e-2 at 0.5, 9.7e-3 at 0.4, 8.5e-3 at 0.35 (the walk before clusters: 8.4e-3 at 0.5).
constexpr double kLocalTheta = 0.35;

/// The opening test shared by every walk: two spheres (centres d apart, radii ra and rb, cell
/// reaches summed in `reach`) interact as aggregates when their opening radii (oa, ob: the
/// radius, or BodyTreeSources::open_radius for groups of bodies) subtend less than theta and no
/// cell pair between them can be within the near-field radius (near_field * reach).
inline bool well_separated(double d, double ra, double rb, double oa, double ob, double theta, double near_field,
                           double reach) {
  return oa + ob < theta * d && d - ra - rb > near_field * reach;
}

}  // namespace magbake::magnetics
