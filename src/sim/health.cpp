#include "health.h"

#include <algorithm>
#include <cstdio>

namespace magbake::sim {

HealthMonitor::HealthMonitor(const scene::Scene& scene, const SimState& initial)
    : scene_(scene), left_at_(scene.bodies.size(), -1), left_where_(scene.bodies.size(), Vec3::Zero()) {
  energy_source_ = scene.applied_field_animated();  // a coil switched or turned does work
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const scene::Body& b = scene.bodies[i];
    if (b.motion == scene::Motion::kKinematic && b.keys.size() > 1) energy_source_ = true;
    const double r = 0.5 * b.shape.shape->bounds().sizes().norm();
    region_.extend(Eigen::AlignedBox3d(initial.com_position[i] - Vec3::Constant(r), initial.com_position[i] + Vec3::Constant(r)));
  }
  if (region_.isEmpty()) return;
  const double grow = std::max(2.0 * region_.sizes().norm(), kMinMargin);
  region_ = Eigen::AlignedBox3d(region_.min() - Vec3::Constant(grow), region_.max() + Vec3::Constant(grow));
}

void HealthMonitor::observe(int frame, const SimState& s, const FrameDiagnostics& d) {
  const double energy = d.total_energy();
  scale_ = std::max(scale_, std::abs(d.magnetic_energy) + d.kinetic_energy);
  if (lowest_frame_ < 0 || energy < lowest_) lowest_ = energy, lowest_frame_ = frame;
  if (energy - lowest_ > worst_rise_) worst_rise_ = energy - lowest_, rise_from_ = lowest_frame_, rise_to_ = frame;
  if (d.max_speed > fastest_) fastest_ = d.max_speed, fastest_body_ = d.max_speed_body, fastest_frame_ = frame;
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    if (left_at_[i] >= 0 || scene_.bodies[i].motion != scene::Motion::kDynamic) continue;
    if (!region_.contains(s.com_position[i])) left_at_[i] = frame, left_where_[i] = s.com_position[i];
  }
}

std::vector<std::string> HealthMonitor::warnings() const {
  std::vector<std::string> out;
  char buf[512];
  const auto& bodies = scene_.bodies;
  if (!energy_source_ && worst_rise_ > kEnergyFraction * scale_ + 1e-6) {
    std::snprintf(buf, sizeof buf,
                  "energy grew without a source: +%.3g J (%.0f%% of the largest magnetic + kinetic energy, %.3g J) "
                  "from frame %d to frame %d",
                  worst_rise_, 100.0 * worst_rise_ / std::max(scale_, 1e-300), scale_, rise_from_, rise_to_);
    std::string line = buf;
    if (fastest_body_ >= 0) {
      std::snprintf(buf, sizeof buf, "; fastest body '%s', %.3g m/s at frame %d", bodies[fastest_body_].name.c_str(),
                    fastest_, fastest_frame_);
      line += buf;
    }
    out.push_back(line);
  }
  int listed = 0, left = 0;
  std::string names;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (left_at_[i] < 0) continue;
    ++left;
    if (listed++ < 5) {
      std::snprintf(buf, sizeof buf, "%s'%s' at frame %d (%.3g, %.3g, %.3g m)", names.empty() ? "" : ", ",
                    bodies[i].name.c_str(), left_at_[i], left_where_[i][0], left_where_[i][1], left_where_[i][2]);
      names += buf;
    }
  }
  if (left > 0) {
    std::snprintf(buf, sizeof buf, "%d bod%s left the scene's region [%.3g, %.3g, %.3g]-[%.3g, %.3g, %.3g] m: ", left,
                  left == 1 ? "y" : "ies", region_.min()[0], region_.min()[1], region_.min()[2], region_.max()[0],
                  region_.max()[1], region_.max()[2]);
    out.push_back(buf + names + (left > 5 ? ", ..." : ""));
  }
  return out;
}

}  // namespace magbake::sim
