#include "simulator.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>

#include "scene/scene_magnetics.h"

namespace magbake::sim {
namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

Simulator::Simulator(const scene::Scene& scene, const magnetics::Model& model)
    : scene_(scene), model_(model), settings_(scene::magnetics_settings(scene)) {
  mag_state_.resize(model_);
  // Static and kinematic bodies are not moved by magnetic forces: the magnetics computes their
  // mutual forces once per set of their poses (a kinematic magnet at rest costs nothing).
  mag_state_.body_fixed.assign(scene_.bodies.size(), 0);
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    mag_state_.body_fixed[i] = scene_.bodies[i].motion != scene::Motion::kDynamic;
  }
  world_ = std::make_unique<RigidWorld>(scene_);
  state_.resize(scene_.bodies.size());
  stiffness_length_.resize(scene_.bodies.size());
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    stiffness_length_[i] = 0.25 * scene_.bodies[i].shape.shape->bounds().sizes().minCoeff();
  }
  // Sleeping: a sleeping body wakes when its magnetic force changes by more than would give it
  // 1% of gravity's acceleration (at least 0.01 m/s², for scenes without gravity), or its torque
  // by that force at half its smallest extent.
  sleep_ = scene_.sleep_time > 0;
  wake_force_.resize(scene_.bodies.size());
  wake_torque_.resize(scene_.bodies.size());
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    wake_force_[i] = scene_.bodies[i].mass * 0.01 * std::max(scene_.gravity.norm(), 1.0);
    wake_torque_[i] = wake_force_[i] * 2.0 * stiffness_length_[i];
  }
  contact_exempt_.assign(scene_.bodies.size(), 0);
  for (std::size_t i = 0; i < scene_.bodies.size() && i < model_.body_isotropic.size(); ++i) {
    contact_exempt_[i] = scene_.bodies[i].motion == scene::Motion::kDynamic && model_.body_isotropic[i];
  }
}

Simulator::~Simulator() = default;

void Simulator::initialize() {
  state_.time = 0;
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const scene::Body& b = scene_.bodies[i];
    const magnetics::Pose p = b.pose_at(0.0);
    state_.orientation[i] = p.rotation;
    state_.com_position[i] = p.position + p.rotation * b.com;
    state_.velocity[i] = b.motion == scene::Motion::kDynamic ? b.velocity : Vec3::Zero();
    state_.angular_velocity[i] = b.motion == scene::Motion::kDynamic ? b.angular_velocity : Vec3::Zero();
  }
  world_->set_state(state_);
  // Bodies placed inside each other: pushed apart (positions only) before time starts, and
  // reported, instead of being blown apart by the contact solver's position correction.
  initial_overlaps_ = world_->separate_overlaps(0.5 * kOverlapTolerance);
  std::erase_if(initial_overlaps_, [](const RigidWorld::Penetration& p) { return p.depth <= kOverlapTolerance; });
  world_->get_state(state_);
  refresh_contacts();
  sleep_reference_set_.assign(scene_.bodies.size(), 0);
  frame_ = scene_.first_frame;
  FrameDiagnostics d;
  evaluate_magnetics(d);  // forces of the first frame (reported in the cache)
  restart();
}

void Simulator::restore(const SimState& s, int frame) {
  state_ = s;
  assert(state_.sleep.size() == scene_.bodies.size());  // SimState::resize sizes it (all awake)
  frame_ = frame;
  // The frame's forces, induced moments and energy as stored: not evaluated again (a solve warm
  // started from its own converged moments would end elsewhere within its tolerance).
  if (state_.induced_moment.size() == model_.induced_cells.size()) mag_state_.induced_moment = state_.induced_moment;
  mag_result_.energy = state_.magnetic_energy;
  restart();
}

void Simulator::restart() {
  // Poses as the cache stores them (body origins), and back.
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const Vec3& com = scene_.bodies[i].com;
    state_.com_position[i] = com_from_origin(body_origin(state_.com_position[i], state_.orientation[i], com),
                                             state_.orientation[i], com);
  }
  world_->reset(state_);
  refresh_contacts();
  sleep_reference_set_.assign(scene_.bodies.size(), 0);
  for (std::size_t i = 0; i < state_.sleep.size(); ++i) sleep_reference_set_[i] = state_.sleep[i] == kAsleep;
  mag_state_.forget_caches();
  last_energy_ = measure().total_energy();
}

void Simulator::evaluate_magnetics(FrameDiagnostics& d) {
  const auto t0 = Clock::now();
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    mag_state_.body_pose[i] = magnetics::Pose{state_.orientation[i], state_.com_position[i]};
    // Sleeping bodies do not move: their mutual forces come from the fixed-pairs cache.
    // Held bodies (per-island substeps) do not move while the others take their pieces.
    mag_state_.body_fixed[i] = scene_.bodies[i].motion != scene::Motion::kDynamic || state_.sleep[i] == kAsleep ||
                               (holding_ && held_[i]);
  }
  settings_.external_field = scene_.applied_field(state_.time);  // animated fields (scene 1.1)
  magnetics::evaluate(model_, settings_, mag_state_, mag_result_);
  state_.magnetic_force = mag_result_.force;
  state_.magnetic_torque = mag_result_.torque;
  state_.magnetic_energy = mag_result_.energy;
  state_.induced_moment = mag_state_.induced_moment;
  d.magnetics_seconds += seconds_since(t0);
  d.cells_visited += mag_result_.stats.cell_pairs + mag_result_.stats.node_pairs;
  d.cell_pairs += mag_result_.stats.cell_pairs;
  d.node_pairs += mag_result_.stats.node_pairs;
  d.near_pairs += mag_result_.stats.near_pairs;
  ++d.evaluations;
  d.induction_iterations += mag_result_.induction.iterations;
  d.induction_residual = std::max(d.induction_residual, mag_result_.induction.residual);
  d.magnetic_energy = mag_result_.energy;
}

void Simulator::refresh_contacts() {
  world_->contact_normals(contact_normals_, &face_slip_, &contact_stuck_, &partner_speed_);
}

void Simulator::update_sleep(FrameDiagnostics& d) {
  if (!sleep_) return;
  bool woke = false;
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const scene::Body& b = scene_.bodies[i];
    if (b.motion != scene::Motion::kDynamic) continue;
    const Vec3& f = state_.magnetic_force[i];
    const Vec3& tq = state_.magnetic_torque[i];
    if (state_.sleep[i] == kAsleep) {
      if (!sleep_reference_set_[i]) {
        // First evaluation since it fell asleep (with it among the fixed bodies): the reference.
        state_.sleep_force[i] = f, state_.sleep_torque[i] = tq;
        sleep_reference_set_[i] = 1;
      } else if ((f - state_.sleep_force[i]).norm() > wake_force_[i] ||
                 (tq - state_.sleep_torque[i]).norm() > wake_torque_[i]) {
        world_->wake(static_cast<int>(i));
        state_.sleep[i] = kAwake, state_.rest_time[i] = 0;
        state_.sleep_force[i] = state_.sleep_torque[i] = Vec3::Zero();
        sleep_reference_set_[i] = 0;
        woke = true;
        ++d.wake_ups;
      }
    } else if (contact_normals_[i].empty() &&
               ((f + b.mass * scene_.gravity).norm() > wake_force_[i] || tq.norm() > wake_torque_[i])) {
      // Free and pushed: moving slowly is not being at rest.
      world_->keep_awake(static_cast<int>(i));
      state_.sleep[i] = kAwake, state_.rest_time[i] = 0;
    }
  }
  // Forces of the state as it now is (the woken bodies no longer fixed), so that a bake resumed
  // from this state recomputes them bit for bit. Wake-ups are rare.
  if (woke) evaluate_magnetics(d);
}

void Simulator::body_splits(double h) {
  // Magnetic stiffness: h sqrt(k/m) <= 0.5 (at most 64 pieces) with k = 4|F|/l, l = a quarter
  // of the body's smallest extent (physics.md §8, the force guard). Split F = F_free + F_pressed,
  // F_pressed the part that presses the body into its contacts (F·n < 0 along each contact's
  // normal n). The contact holds F_pressed, but for a body that feels a magnetic torque the pull
  // still sets the pair's shear, twist and rocking stiffness, which the explicit step must
  // resolve. In a face contact at rest (RigidWorld::contact_normals' face_slip: three points of
  // every manifold span a face, and they slide or close by less than 1% of the body's smallest
  // extent over the substep, the impact guard's 1%) friction and the contact face hold those
  // modes, and F_pressed counts at their measured stiffness: two
  // touching 1 cm N42 cubes under a 54.9 N pull, shear 16,800 N/m (3.06 |F|/a, a = 4 l the
  // smallest extent) and a slower twist, hence kPressedStiffness = 0.75 = 3/4 per l. Leaving
  // F_pressed out entirely let a resting pair of cubes walk 20 mm and gain 36% of its binding
  // energy in 0.3 s at dt 1 ms; a magnet slamming its face down is still cut finely. About a
  // point or line contact a body can roll or rock freely, and there the whole |F| counts (two
  // ball magnets snapping turned 53 degrees from each other gained up to 2.3% of their binding
  // energy at 0.75, 2.2-5.3% with a rolling-rate term instead).
  // A body with no magnetic torque (a soft sphere, Model::body_isotropic) has no rotational
  // stiffness, and what presses it into a contact cannot move it while it rests: its F_pressed
  // does not count unless it moves against a magnet it touches by more than 1% of its smallest
  // extent over the substep (RigidWorld::contact_normals' partner_speed). A steel ball rolling
  // round a magnet's edge feels the pull turn over its own size; left out of the guard, that
  // made 4 and 8 mm balls beside a 1 cm cube gain up to 73% of their binding energy in 0.5 s
  // (bench/results/steel_ball_snap_2026-12-05).
  // Impact: magnetic bodies that may touch within the step (Bullet's swept pair cache) and close
  // faster than 1% of the smaller one's size per piece get shorter pieces (at most 256), so a
  // snapping magnet does not sink into its partner: pushing a deep penetration out against the
  // magnetic pull is where the old step gained energy (physics.md §8).
  world_->closing_rates(closing_);
  // Bodies held together by stuck contacts: their shares of the group's load from outside it
  // (the joints resolve the pull between them implicitly, RigidWorld::stuck_shares).
  shared_force_ = state_.magnetic_force;
  shared_torque_ = state_.magnetic_torque;
  world_->stuck_shares(shared_force_, shared_torque_);
  split_.assign(scene_.bodies.size(), 0);
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const scene::Body& b = scene_.bodies[i];
    if (b.motion != scene::Motion::kDynamic || b.mass <= 0 || state_.sleep[i] == kAsleep) continue;
    Vec3 free = shared_force_[i];
    double pressed = 0;  // N, into contacts that are not stuck
    Vec3 unstuck = free;  // the force without what presses into stuck contacts
    for (std::size_t c = 0; c < contact_normals_[i].size(); ++c) {
      const Vec3& n = contact_normals_[i][c];
      const double press = free.dot(n);
      if (press >= 0) continue;
      free -= press * n;
      if (contact_stuck_[i][c]) {
        unstuck -= press * n;
      } else {
        pressed -= press;
      }
    }
    double k_lin = 4.0 * unstuck.norm() / stiffness_length_[i];
    if (contact_exempt_[i] && partner_speed_[i] * h < 0.04 * stiffness_length_[i]) {
      k_lin = 4.0 * free.norm() / stiffness_length_[i];
    } else if (pressed > 0 && face_slip_[i] * h < 0.04 * stiffness_length_[i]) {
      k_lin = (4.0 * free.norm() + kPressedStiffness * pressed) / stiffness_length_[i];
    }
    const double rate = std::sqrt(k_lin / b.mass);
    int split = 1;
    if (rate * h > 0.5) split = std::min(64, static_cast<int>(std::ceil(rate * h / 0.5)));
    const double closing = closing_[i] * h;
    if (closing > 1.0) split = std::max(split, std::min(256, static_cast<int>(std::ceil(closing))));
    split_[i] = split;
  }
}

int Simulator::largest_split(const std::vector<std::uint8_t>* among) const {
  int split = 1;
  for (std::size_t i = 0; i < split_.size(); ++i) {
    if (!among || (*among)[i]) split = std::max(split, split_[i]);
  }
  return split;
}

bool Simulator::split_islands() {
  if (largest_split(nullptr) <= 1) return false;
  world_->islands(island_);
  const std::size_t n = scene_.bodies.size();
  std::vector<int> need(n, 0);  // per island root
  for (std::size_t i = 0; i < n; ++i) {
    if (island_[i] >= 0) need[island_[i]] = std::max(need[island_[i]], split_[i]);
  }
  fast_.assign(n, 0);
  held_.assign(n, 0);
  bool any_slow = false;  // an awake body that can take the substep in one piece
  for (std::size_t i = 0; i < n; ++i) {
    if (island_[i] < 0) continue;
    fast_[i] = need[island_[i]] > 1;
    held_[i] = !fast_[i];
    any_slow = any_slow || (held_[i] && split_[i] > 0);
  }
  return any_slow;
}

void Simulator::step_piece(double t, double hs, const std::vector<std::uint8_t>* held, FrameDiagnostics& d) {
  const auto tr = Clock::now();
  world_->step(t, hs, state_.magnetic_force, state_.magnetic_torque, held);
  world_->get_state(state_);
  refresh_contacts();
  if (sleep_) {
    for (std::size_t i = 0; i < state_.sleep.size(); ++i) {
      if (state_.sleep[i] != kAsleep) sleep_reference_set_[i] = 0;
    }
  }
  const RigidWorld::Penetration pen = world_->deepest_penetration();
  if (pen.depth > d.max_penetration) d.max_penetration = pen.depth, d.penetration_a = pen.a, d.penetration_b = pen.b;
  d.rigid_seconds += seconds_since(tr);
  ++d.substeps;
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    d.body_steps += scene_.bodies[i].motion == scene::Motion::kDynamic && state_.sleep[i] != kAsleep && !(held && (*held)[i]);
  }
}

void Simulator::check_finite(int frame) const {
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    auto bad = [](const Vec3& v) { return !v.allFinite(); };
    if (bad(state_.magnetic_force[i]) || bad(state_.magnetic_torque[i])) {
      throw NumericalFault(scene_.bodies[i].name, frame, "magnetic force or torque");
    }
    if (bad(state_.com_position[i]) || !state_.orientation[i].coeffs().allFinite()) {
      throw NumericalFault(scene_.bodies[i].name, frame, "position or orientation");
    }
    if (bad(state_.velocity[i]) || bad(state_.angular_velocity[i])) {
      throw NumericalFault(scene_.bodies[i].name, frame, "velocity");
    }
  }
}

FrameDiagnostics Simulator::advance_frame() {
  FrameDiagnostics d;
  const int next = frame_ + 1;
  const double t_start = scene_.frame_time(frame_), t_end = scene_.frame_time(next);
  const double span = t_end - t_start;
  const int nominal = scene_.steps_per_frame();
  const double h = span / nominal;  // substeps land exactly on frame times
  for (int k = 0; k < nominal; ++k) {
    const double t0 = t_start + k * h;
    if (k > 0) {  // the first substep reuses the frame's forces
      evaluate_magnetics(d);
      update_sleep(d);
    }
    body_splits(h);
    // Islands that need no pieces take the whole substep first, with the others held; then the
    // others take their pieces with the first held (per-island substeps, physics.md §8).
    const bool local = split_islands();
    if (local) {
      if (after_magnetics_) after_magnetics_(next, state_);
      check_finite(next);
      step_piece(t0, h, &fast_, d);
      world_->rewind_kinematic(t0);
      holding_ = true;
    }
    const std::vector<std::uint8_t>* held = local ? &held_ : nullptr;
    const std::vector<std::uint8_t>* stepped = local ? &fast_ : nullptr;
    // Each nominal substep is cut into equal pieces, re-decided after every piece from the
    // current forces and speeds (so a magnet accelerating into its partner gets shorter pieces
    // as it closes in), and always ends exactly at t0 + h.
    double done = 0;
    bool first = true;
    while (h - done > 1e-12 * h) {
      if (!first) {
        evaluate_magnetics(d);
        update_sleep(d);
        body_splits(h);
      }
      // Piece length the current state needs, then equal pieces over what is left of h.
      const double target = h / largest_split(stepped);
      const double remaining = h - done;
      const int pieces = std::max(1, static_cast<int>(std::ceil(remaining / target - 1e-9)));
      const double hs = remaining / pieces;
      const double t = t0 + done;
      if (!first || !local) {
        if (after_magnetics_) after_magnetics_(next, state_);
        check_finite(next);
      }
      first = false;
      step_piece(t, hs, held, d);
      done = pieces == 1 ? h : done + hs;
      state_.time = t + hs;
    }
    holding_ = false;
  }
  state_.time = t_end;
  frame_ = next;
  // Forces at the new frame's poses (reported with the frame, reused by the next substep).
  evaluate_magnetics(d);
  update_sleep(d);
  check_finite(next);
  for (std::uint8_t z : state_.sleep) d.sleeping += z == kAsleep;
  const FrameDiagnostics m = measure();
  d.kinetic_energy = m.kinetic_energy;
  d.gravity_energy = m.gravity_energy;
  d.momentum = m.momentum;
  d.angular_momentum = m.angular_momentum;
  d.max_speed = m.max_speed;
  d.max_speed_body = m.max_speed_body;
  d.energy_drift = d.total_energy() - last_energy_;
  last_energy_ = d.total_energy();
  // What the cache holds of this frame is all the next one starts from.
  if ((frame_ - scene_.first_frame) % restart_period_ == 0) restart();
  return d;
}

FrameDiagnostics Simulator::measure() const {
  FrameDiagnostics d;
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const scene::Body& b = scene_.bodies[i];
    if (b.motion != scene::Motion::kDynamic) continue;
    const Mat3 R = state_.orientation[i].toRotationMatrix();
    const Mat3 I = R * b.inertia * R.transpose();
    const Vec3& v = state_.velocity[i];
    const Vec3& w = state_.angular_velocity[i];
    d.kinetic_energy += 0.5 * b.mass * v.squaredNorm() + 0.5 * w.dot(I * w);
    d.gravity_energy -= b.mass * scene_.gravity.dot(state_.com_position[i]);
    d.momentum += b.mass * v;
    d.angular_momentum += state_.com_position[i].cross(b.mass * v) + I * w;
    if (v.norm() > d.max_speed) d.max_speed = v.norm(), d.max_speed_body = static_cast<int>(i);
  }
  d.magnetic_energy = mag_result_.energy;
  return d;
}

}  // namespace magbake::sim
