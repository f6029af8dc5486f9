#include "cost_estimate.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "simulator.h"

namespace magbake::sim {

CostEstimate estimate_cost(const scene::Scene& scene, const magnetics::Model& model, double budget_seconds,
                           int max_steps) {
  CostEstimate e;
  const int frames = scene.last_frame - scene.first_frame;
  const double span = 1.0 / scene.fps;
  const long long per_frame = scene.steps_per_frame();
  e.nominal_steps = per_frame * frames;
  if (e.nominal_steps == 0 || max_steps <= 0) return e;

  // The same scene with one frame per nominal step, so the trial can stop after any step.
  scene::Scene trial = scene;
  trial.dt = span / static_cast<double>(per_frame);
  trial.fps = 1.0 / trial.dt;
  trial.first_frame = 0;
  trial.last_frame = static_cast<int>(std::min<long long>(e.nominal_steps, max_steps));
  Simulator sim(trial, model);
  const auto t0 = std::chrono::steady_clock::now();
  sim.initialize();
  double mag = 0, rigid = 0, substeps = 0, evaluations = 0, iterations = 0, visited = 0;
  while (sim.frame() < trial.last_frame) {
    const FrameDiagnostics d = sim.advance_frame();
    ++e.trial_steps;
    mag += d.magnetics_seconds, rigid += d.rigid_seconds;
    substeps += d.substeps, evaluations += d.evaluations;
    iterations += d.induction_iterations, visited += static_cast<double>(d.cells_visited);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > budget_seconds) break;
  }
  e.trial_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // A bake evaluates the magnetics once per substep (the first substep of a frame reuses the
  // previous frame's closing evaluation), as the trial does with its one-step frames, so every
  // count scales with the steps.
  const double scale = static_cast<double>(e.nominal_steps) / e.trial_steps;
  e.substeps = substeps * scale;
  e.evaluations = evaluations * scale;
  e.induction_iterations = iterations * scale;
  e.cells_visited = visited * scale;
  e.magnetics_seconds = mag * scale;
  e.rigid_seconds = rigid * scale;
  return e;
}

}  // namespace magbake::sim
