// Signs that a bake blew up, gathered frame by frame and summarized at the end.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"
#include "sim_state.h"

namespace magbake::sim {

/// Watches a bake for energy that grows without a source and for bodies that leave the
/// scene's region. Energy has a source when a kinematic body moves (keys) — then only the
/// region is checked. Thresholds (physics.md §8): energy may not rise above its lowest value so
/// far by more than kEnergyFraction of the largest |magnetic| + kinetic energy seen (plus 1 uJ);
/// the region is the box around every body's starting bounds, grown by twice its diagonal and
/// at least kMinMargin on every side.
class HealthMonitor {
 public:
  static constexpr double kEnergyFraction = 0.05;
  static constexpr double kMinMargin = 0.1;  ///< m

  /// `initial` is the state of the scene's first frame.
  HealthMonitor(const scene::Scene& scene, const SimState& initial);
  /// Takes the state and diagnostics of one frame, in order.
  void observe(int frame, const SimState& state, const FrameDiagnostics& d);
  /// One line per problem (empty when the bake looks sane).
  std::vector<std::string> warnings() const;

 private:
  const scene::Scene& scene_;
  bool energy_source_ = false;
  Eigen::AlignedBox3d region_;
  double scale_ = 0;                 // largest |U| + K seen, J
  double lowest_ = 0;                // lowest total energy so far, J
  int lowest_frame_ = -1;
  double worst_rise_ = 0;            // largest rise above the lowest, J
  int rise_from_ = -1, rise_to_ = -1;
  double fastest_ = 0;               // largest speed of any frame, m/s
  int fastest_body_ = -1, fastest_frame_ = -1;
  std::vector<int> left_at_;         // per body: first frame outside the region, -1 if never
  std::vector<Vec3> left_where_;
};

}  // namespace magbake::sim
