#include "cost_estimate.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <vector>

#include "simulator.h"

namespace magbake::sim {

namespace {

// Whether a trial's cost per step has settled: over its last quarter the substeps and the cell
// + node pairs per step are within 25% of the quarter before (at least 8 steps seen).
bool settled(const std::vector<std::array<double, 6>>& cost) {
  const std::size_t n = cost.size(), q = n / 4;
  if (n < 8) return false;
  for (int k : {2, 5}) {
    double last = 0, before = 0;
    for (std::size_t j = n - q; j < n; ++j) last += cost[j][k];
    for (std::size_t j = n - 2 * q; j < n - q; ++j) before += cost[j][k];
    if (last == before) continue;
    if (last > 1.25 * before || before > 1.25 * last) return false;
  }
  return true;
}

}  // namespace

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
  // At most kTrialExtension x max_steps (while the cost has not settled), and the shot.
  const long long cap = std::min<long long>(e.nominal_steps, static_cast<long long>(std::min<double>(
                                                                 kTrialExtension * max_steps, 1e9)));
  trial.last_frame = static_cast<int>(cap);
  Simulator sim(trial, model);
  sim.set_restart_period(static_cast<int>(per_frame));  // at the bake's frames (Simulator::restart)
  const auto t0 = std::chrono::steady_clock::now();
  sim.initialize();
  // Per trial step: magnetics s, rigid s, substeps, evaluations, iterations, cell + node pairs.
  std::vector<std::array<double, 6>> cost;
  while (sim.frame() < trial.last_frame) {
    const FrameDiagnostics d = sim.advance_frame();
    cost.push_back({d.magnetics_seconds, d.rigid_seconds, double(d.substeps), double(d.evaluations),
                    double(d.induction_iterations), static_cast<double>(d.cells_visited)});
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool over = elapsed > budget_seconds || static_cast<long long>(cost.size()) >= max_steps;
    if (over && (elapsed > kTrialExtension * budget_seconds || settled(cost))) break;
  }
  e.trial_steps = static_cast<int>(cost.size());
  e.trial_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // A bake evaluates the magnetics once per substep (the first substep of a frame reuses the
  // previous frame's closing evaluation), as the trial does with its one-step frames. The trial's
  // own steps count as they are; the rest of the shot at the rate of the trial's second half,
  // so that a start unlike the rest (magnets that snap in the first steps and then rest, or
  // bodies that only begin to approach) weighs as little as it lasts.
  std::array<double, 6> total{}, late{};
  const std::size_t half = cost.size() / 2;
  for (std::size_t k = 0; k < cost.size(); ++k) {
    for (int q = 0; q < 6; ++q) {
      total[q] += cost[k][q];
      if (k >= half) late[q] += cost[k][q];
    }
  }
  const double rest = static_cast<double>(e.nominal_steps - e.trial_steps) / static_cast<double>(cost.size() - half);
  std::array<double, 6> out{};
  for (int q = 0; q < 6; ++q) out[q] = total[q] + late[q] * rest;
  e.magnetics_seconds = out[0];
  e.rigid_seconds = out[1];
  e.substeps = out[2];
  e.evaluations = out[3];
  e.induction_iterations = out[4];
  e.cells_visited = out[5];
  return e;
}

}  // namespace magbake::sim
