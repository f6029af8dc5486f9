#include "cache_state.h"

#include <stdexcept>
#include <string>

namespace magbake::cli {

static_assert(io::kStuckValues == std::size_t(sim::StuckJoint::kValues));

io::CacheFrame cache_frame(int frame, double time, const sim::SimState& s, const scene::Scene& scene) {
  io::CacheFrame f;
  f.frame = frame;
  f.time = time;
  const std::size_t n = scene.bodies.size();
  for (std::size_t i = 0; i < n; ++i) {
    f.position.push_back(sim::body_origin(s.com_position[i], s.orientation[i], scene.bodies[i].com));
  }
  f.orientation = s.orientation;
  f.velocity = s.velocity;
  f.angular_velocity = s.angular_velocity;
  f.force = s.magnetic_force;
  f.torque = s.magnetic_torque;
  f.induced_moment = s.induced_moment;
  f.sleep.assign(2 * n, 0.0);
  f.sleep_reference.assign(6 * n, 0.0);
  for (std::size_t i = 0; i < n && i < s.sleep.size(); ++i) {
    f.sleep[2 * i] = s.sleep[i];
    f.sleep[2 * i + 1] = s.rest_time[i];
    for (int c = 0; c < 3; ++c) {
      f.sleep_reference[6 * i + c] = s.sleep_force[i][c];
      f.sleep_reference[6 * i + 3 + c] = s.sleep_torque[i][c];
    }
  }
  return f;
}

io::FrameObservables cache_observables(const sim::FrameDiagnostics& d) {
  io::FrameObservables o;
  o.kinetic_energy = d.kinetic_energy;
  o.gravity_energy = d.gravity_energy;
  o.magnetic_energy = d.magnetic_energy;
  o.momentum = d.momentum;
  o.angular_momentum = d.angular_momentum;
  o.magnetics_seconds = d.magnetics_seconds;
  o.rigid_seconds = d.rigid_seconds;
  o.cells_visited = double(d.cells_visited);
  o.induction_iterations = double(d.induction_iterations);
  o.induction_residual = d.induction_residual;
  o.substeps = double(d.substeps);
  o.energy_drift = d.energy_drift;
  o.max_speed = d.max_speed;
  o.max_penetration = d.max_penetration;
  o.sleeping = double(d.sleeping);
  o.body_steps = double(d.body_steps);
  return o;
}

std::vector<io::StuckRow> cache_stuck_rows(const sim::SimState& s) {
  std::vector<io::StuckRow> out;
  for (const sim::StuckJoint& j : s.stuck_joints) {
    io::StuckRow r;
    std::size_t at = 0;
    r[at++] = double(j.a);
    r[at++] = double(j.b);
    auto put = [&](const auto& m) {
      for (int i = 0; i < int(m.rows()); ++i)
        for (int k = 0; k < int(m.cols()); ++k) r[at++] = m(i, k);
    };
    put(j.normal_in_a);
    r[at++] = j.mu;
    r[at++] = j.lever;
    put(j.pivot_a), put(j.pivot_b), put(j.basis_a), put(j.basis_b), put(j.origin_a), put(j.origin_b);
    out.push_back(r);
  }
  return out;
}

namespace {

sim::StuckJoint stuck_joint(const io::StuckRow& r) {
  sim::StuckJoint j;
  j.a = int(r[0]), j.b = int(r[1]);
  std::size_t at = 2;
  auto get = [&](auto& m) {
    for (int i = 0; i < int(m.rows()); ++i)
      for (int k = 0; k < int(m.cols()); ++k) m(i, k) = r[at++];
  };
  get(j.normal_in_a);
  j.mu = r[at++];
  j.lever = r[at++];
  get(j.pivot_a), get(j.pivot_b), get(j.basis_a), get(j.basis_b), get(j.origin_a), get(j.origin_b);
  return j;
}

}  // namespace

sim::SimState resume_state(const io::CacheReader& cache, int index, const scene::Scene& sc) {
  const io::CacheFrame fr = cache.frame(index);
  const std::string at = cache.path() + ": frame " + std::to_string(fr.frame);
  sim::SimState s;
  s.resize(sc.bodies.size());
  if (fr.position.size() != sc.bodies.size()) throw std::runtime_error(cache.path() + ": body count differs from the scene");
  s.time = fr.time;
  for (std::size_t i = 0; i < sc.bodies.size(); ++i) {
    s.orientation[i] = fr.orientation[i];
    s.com_position[i] = sim::com_from_origin(fr.position[i], fr.orientation[i], sc.bodies[i].com);
    s.velocity[i] = fr.velocity[i];
    s.angular_velocity[i] = fr.angular_velocity[i];
    s.magnetic_force[i] = fr.force[i];
    s.magnetic_torque[i] = fr.torque[i];
  }
  s.induced_moment = fr.induced_moment;
  s.magnetic_energy = cache.observable_at("magnetic_energy", index);
  for (const io::StuckRow& r : cache.stuck_rows(index)) s.stuck_joints.push_back(stuck_joint(r));
  for (std::size_t i = 0; i < sc.bodies.size() && 2 * i + 1 < fr.sleep.size(); ++i) {
    const double state = fr.sleep[2 * i], rest = fr.sleep[2 * i + 1];
    if (!(state == 0 || state == 1 || state == 2) || !(rest >= 0 && rest < 1e12)) {
      throw std::runtime_error(at + " holds an invalid sleep state of body '" + sc.bodies[i].name + "'");
    }
    s.sleep[i] = static_cast<std::uint8_t>(state);
    s.rest_time[i] = rest;
    const double* r = fr.sleep_reference.data() + 6 * i;
    s.sleep_force[i] = magnetics::Vec3(r[0], r[1], r[2]);
    s.sleep_torque[i] = magnetics::Vec3(r[3], r[4], r[5]);
    if (!s.sleep_force[i].allFinite() || !s.sleep_torque[i].allFinite()) {
      throw std::runtime_error(at + " holds a non-finite sleep reference of body '" + sc.bodies[i].name + "'");
    }
  }
  return s;
}

}  // namespace magbake::cli
