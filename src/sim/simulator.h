// The step loop: magnetics (src/magnetics) and rigid bodies (Bullet) advanced together.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "magnetics/system.h"
#include "rigid_world.h"
#include "scene/scene.h"
#include "sim_state.h"

namespace magbake::sim {

/// A non-finite number appeared: the bake stops at the last good frame.
class NumericalFault : public std::runtime_error {
 public:
  NumericalFault(std::string body, int frame, const std::string& what)
      : std::runtime_error("non-finite " + what + " on body '" + body + "' while computing frame " +
                           std::to_string(frame)),
        body_(std::move(body)),
        frame_(frame) {}
  const std::string& body() const { return body_; }
  int frame() const { return frame_; }

 private:
  std::string body_;
  int frame_;
};

/// Advances a scene frame by frame. Each substep (physics-notes, bullet-notes):
///  1. magnetics at the current poses -> force and torque on every body (about its COM);
///  2. the substep is split when the magnetic stiffness would make it unstable
///     (h sqrt(k/m) > 0.5 with k = 4|F|/l, l = a quarter of the body's smallest extent, and
///     the pull into a face contact counted at 0.75|F|/l, kPressedStiffness) or when
///     two bodies about to touch close by more than 1% of their size per piece; the split is
///     re-decided after every piece. It is decided per island (RigidWorld::islands(): bodies
///     that may touch within the step): islands that need no split take the substep in one
///     piece while the others are held, then the islands that need it take their pieces while
///     the first are held (and fixed in the magnetics, so their mutual forces are not
///     recomputed). Bodies held together by stuck contacts (face contacts of magnets at rest,
///     joints in Bullet's solver) count only their shares of their group's load from outside;
///  3. Bullet advances one substep with kinematic bodies moved to their keyed pose at t + h,
///     then lets go of the stuck contacts that friction can no longer hold and joins those that
///     came to rest (StuckContacts, physics.md §8 item 11);
///  4. NaN/Inf anywhere stops with a NumericalFault naming the body and frame;
///  5. bodies at rest for Scene::sleep_time fall asleep (Bullet islands); they count as fixed in
///     the magnetics and do not split substeps, and wake on contact or when their magnetic force
///     or torque changes (update_sleep).
class Simulator {
 public:
  /// `model` must be built from the same scene (scene::build_magnetics_model).
  Simulator(const scene::Scene& scene, const magnetics::Model& model);
  ~Simulator();

  /// Sets the initial state (frame `first_frame`): poses from the scene, initial velocities.
  void initialize();
  /// Sets a state read back from a cache (resume); `frame` is the frame it belongs to. Its
  /// forces, induced moments and magnetic energy are taken as stored. A bake resumed this way
  /// continues bit for bit as the uninterrupted bake: every frame ends in restart(), so nothing
  /// but the state (and what the cache holds of it) carries over from one frame to the next.
  void restore(const SimState& state, int frame);
  /// Advances from the current frame to the next; returns what happened in between.
  FrameDiagnostics advance_frame();

  const SimState& state() const { return state_; }
  int frame() const { return frame_; }
  /// The magnetics state of the last evaluation (induced moments, world poses).
  const magnetics::State& magnetics_state() const { return mag_state_; }
  /// Diagnostics of the current state alone (energies, momenta, fastest body), e.g. for the
  /// first frame.
  FrameDiagnostics measure() const;
  /// Pairs of bodies that interpenetrated in the initial state by more than
  /// kOverlapTolerance, before initialize() separated them (deepest first).
  const std::vector<RigidWorld::Penetration>& initial_overlaps() const { return initial_overlaps_; }
  /// Penetration (m) above which initial overlaps are reported and separated.
  static constexpr double kOverlapTolerance = 1e-4;
  /// Stiffness that the part of a body's magnetic pull pressing it into a face contact adds to
  /// the force guard, in units of |F_pressed| / l (l = a quarter of the body's smallest extent):
  /// 0.75 |F| / l = 3 |F| / a, the shear stiffness measured for touching cube magnets
  /// (physics.md §8; the rest of the force counts 4 |F| / l, as does the whole force of a body
  /// in a point or line contact). Soft spheres leave it out.
  static constexpr double kPressedStiffness = 0.75;

  /// Restarts (restart()) at every `frames`-th frame from the first instead of every frame: for
  /// the cost trial (estimate_cost), whose frames are single substeps, so that it restarts
  /// where the bake does. 1 by default.
  void set_restart_period(int frames) { restart_period_ = std::max(1, frames); }

  /// A callback that may change the state after every magnetics evaluation, before the state is
  /// checked for non-finite values and stepped; `frame` is the frame being computed. A test
  /// seam (e.g. to poison a force and see the fault handled); unset in production.
  using StateHook = std::function<void(int frame, SimState& state)>;
  void set_after_magnetics(StateHook hook) { after_magnetics_ = std::move(hook); }

 private:
  void evaluate_magnetics(FrameDiagnostics& d);
  /// Ends a frame (and initialize(), restore()): rounds the poses through the cache's form
  /// (body origins), starts Bullet afresh at state_ (RigidWorld::reset: contacts, pair cache and
  /// warm starts of earlier steps dropped, stuck joints remade from state_), drops the
  /// magnetics' caches (magnetics::State::forget_caches) and re-derives everything else kept
  /// between steps (contact normals, sleep references, the energy baseline) from state_ alone.
  void restart();
  /// Gathers the contact normals of Bullet's last collision detection into contact_normals_
  /// (once per step; read by update_sleep and body_splits).
  void refresh_contacts();
  /// Sleeping, after a magnetics evaluation: a sleeping body whose magnetic force or torque has
  /// changed from the one it fell asleep with (by wake_force_/wake_torque_) is woken; a body
  /// without contacts whose net force or torque is not negligible has its rest clock restarted
  /// (slow is not balanced). Forces are re-evaluated when a body woke.
  void update_sleep(FrameDiagnostics& d);
  /// Pieces each body needs for a step of h seconds from the current state, into split_ (>= 1;
  /// 0 for bodies that are not stepped: static, kinematic, asleep).
  void body_splits(double h);
  /// Largest split_ over the bodies (all of them, or those marked in `among`), at least 1.
  int largest_split(const std::vector<std::uint8_t>* among) const;
  /// Decides which islands need pieces: fast_ (their bodies) and held_ (the other dynamic
  /// bodies); false when no island can be left out (one piece for all, or all need pieces).
  bool split_islands();
  /// One Bullet step of hs seconds from time t with the current forces (`held`: bodies held
  /// still), then the state read back and the step's statistics added to d.
  void step_piece(double t, double hs, const std::vector<std::uint8_t>* held, FrameDiagnostics& d);
  void check_finite(int frame) const;

  const scene::Scene& scene_;
  const magnetics::Model& model_;
  magnetics::Settings settings_;
  magnetics::State mag_state_;
  magnetics::Result mag_result_;
  std::unique_ptr<RigidWorld> world_;
  SimState state_;
  int frame_ = 0;
  std::vector<double> stiffness_length_;  // per body, m
  std::vector<int> split_;                // per body: pieces it needs (body_splits)
  std::vector<double> closing_;           // per body: RigidWorld::closing_rates, s^-1
  std::vector<int> island_;               // per body: RigidWorld::islands
  std::vector<std::uint8_t> fast_, held_; // per body: split_islands()
  bool holding_ = false;                  // held_ bodies are fixed in the magnetics now
  std::vector<std::uint8_t> contact_exempt_;  // per body: dynamic and without magnetic torque (body_splits)
  std::vector<std::vector<Vec3>> contact_normals_;  // per body, of the last step (refresh_contacts())
  std::vector<double> face_slip_;         // per body: RigidWorld::contact_normals' face_slip, m/s
  std::vector<double> partner_speed_;     // per body: RigidWorld::contact_normals' partner_speed, m/s
  std::vector<std::vector<std::uint8_t>> contact_stuck_;  // per body, per contact normal: a stuck contact
  std::vector<Vec3> shared_force_, shared_torque_;  // per body: body_splits' forces after RigidWorld::stuck_shares
  std::vector<RigidWorld::Penetration> initial_overlaps_;
  bool sleep_ = false;                    // Scene::sleep_time > 0
  std::vector<double> wake_force_;        // per body, N: force change that wakes it
  std::vector<double> wake_torque_;       // per body, N·m
  std::vector<std::uint8_t> sleep_reference_set_;  // per body: asleep and its reference taken
  double last_energy_ = 0;  // total energy at the current frame, J (for energy_drift)
  StateHook after_magnetics_;
  int restart_period_ = 1;  // frames between restarts (set_restart_period)
};

}  // namespace magbake::sim
