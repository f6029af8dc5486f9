// The step loop: magnetics (src/magnetics) and rigid bodies (Bullet) advanced together.
#pragma once

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
///     (h sqrt(k/m) > 0.5 with k = 4|F|/l, l = a quarter of the body's smallest extent);
///  3. Bullet advances one substep with kinematic bodies moved to their keyed pose at t + h;
///  4. NaN/Inf anywhere stops with a NumericalFault naming the body and frame.
class Simulator {
 public:
  /// `model` must be built from the same scene (scene::build_magnetics_model).
  Simulator(const scene::Scene& scene, const magnetics::Model& model);
  ~Simulator();

  /// Sets the initial state (frame `first_frame`): poses from the scene, initial velocities.
  void initialize();
  /// Sets a state read back from a cache (resume); `frame` is the frame it belongs to.
  void restore(const SimState& state, int frame);
  /// Advances from the current frame to the next; returns what happened in between.
  FrameDiagnostics advance_frame();

  const SimState& state() const { return state_; }
  int frame() const { return frame_; }
  /// The magnetics state of the last evaluation (induced moments, world poses).
  const magnetics::State& magnetics_state() const { return mag_state_; }
  /// Diagnostics of the current state alone (energies, momenta), e.g. for the first frame.
  FrameDiagnostics measure() const;

 private:
  void evaluate_magnetics(FrameDiagnostics& d);
  void check_finite(int frame) const;
  void inject_fault_for_tests(int frame);

  const scene::Scene& scene_;
  const magnetics::Model& model_;
  magnetics::Settings settings_;
  magnetics::State mag_state_;
  magnetics::Result mag_result_;
  std::unique_ptr<RigidWorld> world_;
  SimState state_;
  int frame_ = 0;
  std::vector<double> stiffness_length_;  // per body, m
};

}  // namespace magbake::sim
