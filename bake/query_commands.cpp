// check, info, eval, probe: ask magbake what it computes, without baking.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include "cli.h"
#include "io/cache.h"
#include "sim/cost_estimate.h"
#include "scene/scene_magnetics.h"

namespace magbake::cli {
namespace {

struct Evaluated {
  magnetics::Model model;
  magnetics::State state;
  magnetics::Settings settings;
  magnetics::Result result;
  double seconds = 0;  // wall time of the evaluation
};

// Builds the model and evaluates it at time t.
Evaluated evaluate_at(const scene::Scene& s, double t) {
  Evaluated e;
  e.model = scene::build_magnetics_model(s);
  e.state.resize(e.model);
  scene::set_poses_at(s, t, e.state);
  e.settings = scene::magnetics_settings(s, t);
  const auto t0 = std::chrono::steady_clock::now();
  magnetics::evaluate(e.model, e.settings, e.state, e.result);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

// Parses "x,y,z" (or "x y z").
bool parse_point(std::string text, Eigen::Vector3d& p) {
  for (char& ch : text) {
    if (ch == ',') ch = ' ';
  }
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  is >> p[0] >> p[1] >> p[2];
  if (is.fail()) return false;
  std::string rest;
  is >> rest;
  return rest.empty();
}

}  // namespace

int cmd_check(const std::string& path, double trial_seconds, bool json, const Global& g) {
  auto s = load_or_report(path);
  if (!s) return kUsage;
  if (!json) std::cout << scene_summary(*s, g.verbose);
  try {
    // Cells per body and the cost of one evaluation at the first frame.
    Evaluated e = evaluate_at(*s, 0.0);
    int magnetic = 0, fewest = 0, most = 0;
    for (int b = 0; b < e.model.body_count; ++b) {
      const int n = e.model.body_cell_begin[b + 1] - e.model.body_cell_begin[b];
      if (n == 0) continue;
      fewest = magnetic == 0 ? n : std::min(fewest, n), most = std::max(most, n), ++magnetic;
    }
    if (!json) {
      std::cout << "cells    ";
      if (g.verbose || s->bodies.size() <= kSummaryBodies) {
        for (int b = 0; b < e.model.body_count; ++b) {
          const int n = e.model.body_cell_begin[b + 1] - e.model.body_cell_begin[b];
          if (n > 0) std::cout << s->bodies[b].name << " " << n << "  ";
        }
        std::cout << "(total " << e.model.cell_count() << ")\n";
      } else {
        std::cout << e.model.cell_count() << " in " << magnetic << " magnetic bodies (" << fewest << " to " << most
                  << " per body)\n";
      }
    }
    // Repeat a few evaluations (warm) for a steadier figure.
    const auto t0 = std::chrono::steady_clock::now();
    int reps = 0;
    do {
      magnetics::evaluate(e.model, e.settings, e.state, e.result);
      ++reps;
    } while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 0.2 && reps < 50);
    const double per = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps;
    // The expected cost of the bake: a trial bake of the shot's first steps (substep splitting,
    // induction iterations and contact as the bake will see them), scaled to the whole shot.
    const sim::CostEstimate est =
        sim::estimate_cost(*s, e.model, trial_seconds, trial_seconds > 0 ? std::numeric_limits<int>::max() : 0);
    if (json) {
      nlohmann::json out = scene_summary_json(*s);
      out["scene"] = path;
      out["cells"] = e.model.cell_count();
      for (int b = 0; b < e.model.body_count; ++b) {
        out["bodies"][b]["cells"] = e.model.body_cell_begin[b + 1] - e.model.body_cell_begin[b];
      }
      out["evaluation_seconds"] = per;
      out["estimate"] = {{"nominal_steps", est.nominal_steps},
                         {"trial_steps", est.trial_steps},
                         {"trial_seconds", est.trial_seconds},
                         {"substeps", est.substeps},
                         {"evaluations", est.evaluations},
                         {"induction_iterations", est.induction_iterations},
                         {"cells_visited", est.cells_visited},
                         {"magnetics_seconds", est.magnetics_seconds},
                         {"rigid_seconds", est.rigid_seconds},
                         {"seconds", est.seconds()}};
      std::cout << out.dump(2) << "\n";
      return kOk;
    }
    std::printf("cost     %.3g ms per magnetics evaluation at t = 0 (%lld cell pairs, %lld node pairs, "
                "induction %d iterations)\n",
                per * 1e3, (long long)e.result.stats.cell_pairs, (long long)e.result.stats.node_pairs,
                e.result.induction.iterations);
    if (est.trial_steps > 0) {
      std::printf("expect   %.0f substeps for %lld steps of dt (x%.2f), %.3g induction iterations per evaluation "
                  "-> about %.3g s: magnetics %.3g s, rigid bodies %.3g s (trial of the first %d steps, %.2g s)\n",
                  est.substeps, est.nominal_steps, est.substeps / std::max<double>(1, est.nominal_steps),
                  est.evaluations > 0 ? est.induction_iterations / est.evaluations : 0.0, est.seconds(),
                  est.magnetics_seconds, est.rigid_seconds, est.trial_steps, est.trial_seconds);
    } else {
      std::printf("expect   at least %.3g s of magnetics for %lld steps of dt (no trial: substeps not counted)\n",
                  per * est.nominal_steps, est.nominal_steps);
    }
  } catch (const std::exception& ex) {
    std::cerr << path << ": " << ex.what() << "\n";
    return kUsage;
  }
  std::cout << "ok\n";
  return kOk;
}

int cmd_info(const std::string& path, const Global& g) {
  if (!std::filesystem::exists(path)) {
    std::cerr << "magbake info: " << path << ": no such file\n";
    return kUsage;
  }
  if (io::is_hdf5_file(path) || path.ends_with(".h5") || path.ends_with(".partial")) return cmd_info_cache(path, g.verbose);
  auto s = load_or_report(path);
  if (!s) return kUsage;
  std::cout << scene_summary(*s, g.verbose);
  return kOk;
}

int cmd_eval(const std::string& path, double time, bool json, const Global&) {
  auto s = load_or_report(path);
  if (!s) return kUsage;
  Evaluated e;
  try {
    e = evaluate_at(*s, time);
  } catch (const std::exception& ex) {
    std::cerr << path << ": " << ex.what() << "\n";
    return kUsage;
  }
  const auto& r = e.result;
  // Non-finite results (an overflowing scene, a solver fault) are an error, never output.
  for (std::size_t b = 0; b < s->bodies.size(); ++b) {
    if (!r.force[b].allFinite() || !r.torque[b].allFinite() || !r.moment[b].allFinite()) {
      std::cerr << path << ": magnetics gave a non-finite force, torque or moment on body '" << s->bodies[b].name
                << "' at t = " << time << " s; nothing printed\n";
      return kFailure;
    }
  }
  if (!r.induction.converged) {
    spdlog::warn("induction solve stopped at residual {:.2e} after {} iterations", r.induction.residual,
                 r.induction.iterations);
  }
  if (json) {
    nlohmann::json out;
    out["time"] = time;
    out["bodies"] = nlohmann::json::array();
    for (std::size_t b = 0; b < s->bodies.size(); ++b) {
      out["bodies"].push_back({{"name", s->bodies[b].name},
                               {"force", json_vec(r.force[b])},
                               {"torque", json_vec(r.torque[b])},
                               {"moment", json_vec(r.moment[b])},
                               {"center_of_mass", json_vec(e.state.body_pose[b].position)}});
    }
    out["cells"] = e.model.cell_count();
    out["induction"] = {{"iterations", r.induction.iterations},
                        {"residual", r.induction.residual},
                        {"converged", r.induction.converged}};
    if (r.induction.nonlinear_iterations > 0) {  // saturating materials (physics.md §13)
      out["induction"]["nonlinear_iterations"] = r.induction.nonlinear_iterations;
      out["induction"]["nonlinear_residual"] = r.induction.nonlinear_residual;
    }
    out["energy"] = r.energy;
    out["stats"] = {{"cell_pairs", r.stats.cell_pairs},
                    {"node_pairs", r.stats.node_pairs},
                    {"near_pairs", r.stats.near_pairs},
                    {"seconds", e.seconds}};
    print_json(out);
  } else {
    std::printf("t = %g s, %d cells, induction %d iterations (residual %.2e)\n", time, e.model.cell_count(),
                r.induction.iterations, r.induction.residual);
    std::printf("%-16s %36s %36s %36s\n", "body", "force (N)", "torque about COM (N m)", "moment (A m²)");
    for (std::size_t b = 0; b < s->bodies.size(); ++b) {
      std::printf("%-16s %11.4e %11.4e %11.4e  %11.4e %11.4e %11.4e  %11.4e %11.4e %11.4e\n", s->bodies[b].name.c_str(),
                  r.force[b][0], r.force[b][1], r.force[b][2], r.torque[b][0], r.torque[b][1], r.torque[b][2],
                  r.moment[b][0], r.moment[b][1], r.moment[b][2]);
    }
  }
  return kOk;
}

int cmd_probe(const std::string& path, const std::vector<std::string>& at, const std::string& points_file, double time,
              bool json, const Global&) {
  std::vector<Eigen::Vector3d> pts;
  for (const std::string& a : at) {
    Eigen::Vector3d p;
    if (!parse_point(a, p)) {
      std::cerr << "magbake probe: --at expects X,Y,Z (metres), got '" << a << "'\n";
      return kUsage;
    }
    pts.push_back(p);
  }
  if (!points_file.empty()) {
    std::error_code ec;
    if (std::filesystem::exists(points_file, ec) && !std::filesystem::is_regular_file(points_file, ec)) {
      std::cerr << "magbake probe: points file '" << points_file << "' is not a regular file\n";
      return kUsage;
    }
    std::ifstream in(points_file);
    if (!in) {
      std::cerr << "magbake probe: cannot read points file '" << points_file << "'\n";
      return kUsage;
    }
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      Eigen::Vector3d p;
      if (!parse_point(line, p)) {
        std::cerr << points_file << ":" << n << ": expected 'x y z' or 'x,y,z' in metres, got '" << line << "'\n";
        return kUsage;
      }
      pts.push_back(p);
    }
  }
  if (pts.empty()) {
    std::cerr << "magbake probe: no points: give --at X,Y,Z or --points FILE\n";
    return kUsage;
  }
  auto s = load_or_report(path);
  if (!s) return kUsage;
  Evaluated e;
  try {
    e = evaluate_at(*s, time);
  } catch (const std::exception& ex) {
    std::cerr << path << ": " << ex.what() << "\n";
    return kUsage;
  }
  for (std::size_t b = 0; b < s->bodies.size(); ++b) {
    if (!e.result.moment[b].allFinite()) {
      std::cerr << path << ": the magnetic moment of body '" << s->bodies[b].name << "' is not finite at t = " << time
                << " s; nothing printed\n";
      return kFailure;
    }
  }
  const std::vector<Eigen::Vector3d> B = magnetics::field_at_points(e.model, e.settings, e.state, pts);
  for (std::size_t q = 0; q < pts.size(); ++q) {
    if (!B[q].allFinite()) {
      std::cerr << path << ": the field at (" << pts[q][0] << ", " << pts[q][1] << ", " << pts[q][2]
                << ") m is not finite; nothing printed\n";
      return kFailure;
    }
  }
  if (json) {
    nlohmann::json out;
    out["time"] = time;
    out["points"] = nlohmann::json::array();
    out["B"] = nlohmann::json::array();
    for (std::size_t q = 0; q < pts.size(); ++q) {
      out["points"].push_back(json_vec(pts[q]));
      out["B"].push_back(json_vec(B[q]));
    }
    print_json(out);
  } else {
    for (std::size_t q = 0; q < pts.size(); ++q) {
      std::printf("%12.6g %12.6g %12.6g   B = %13.6e %13.6e %13.6e T  |B| = %.6e T\n", pts[q][0], pts[q][1], pts[q][2],
                  B[q][0], B[q][1], B[q][2], B[q].norm());
    }
  }
  return kOk;
}

}  // namespace magbake::cli
